//! No crossing forms in a substep: its path is checked, and where the check
//! fails, every particle is bounded (after Chen et al., "Offset Geometric
//! Contact", ACM TOG 2025). docs/method.md §11b has the whole argument.
//!
//! **The path.** A substep moves the particles from `X⁰` (free of crossings
//! but for the tangled ones) to `X¹` along the straight path. An edge comes
//! to cross a triangle only by touching its border (edge against edge) or
//! by an end passing its face (particle against triangle), so no crossing
//! forms if no particle–triangle or edge–edge pair sharing no particle
//! reaches distance 0 on the way. A point of a primitive is a convex
//! combination of its corners, so a pair at distance `D⁰` at `X⁰` stays at
//! least `D⁰ − max |u_a − u_b|` apart (`u` the corners' moves), and that is
//! at least `D⁰ − δ_A − δ_B` with `δ` each primitive's largest move beyond
//! a common translation. [`PathCheck::path_clear`] checks this for every pair
//! of the near list (`pairs.rs`), exactly for the few the cheap test fails
//! (the plane between their nearest points at the start or at the end
//! parts them at both), and parts those that fail that along the start's,
//! as an inelastic touch would.
//!
//! **The bounds, the fallback.** Where the path still is not clear, every
//! particle `i` gets a bound `b_i = γ d_i` (`γ < ½`, `d_i` its distance to
//! the nearest primitive sharing no particle with it, capped at the radius
//! `r`) at `X⁰` and is brought within it of where the common motion
//! carried it ([`PathCheck::clamp`]): a pair at distance `D` comes no nearer
//! than `D − 2γD > 0`, and the balls are convex, so the straight path
//! keeps them. Driven particles follow their bodies and are neither parted
//! nor clamped. A pulled particle is parted by its mass like any other but
//! not clamped: it follows its pull (and where that takes it beyond its
//! bound, the cloth is no longer known to be free of crossings).
//! Tangled particles (a jerk drags the cloth through itself) are exempt
//! from both: their state is not free of crossings, and holding it would
//! hold the tangle instead of letting it come apart.
//!
//! The distances come from a list of the primitive pairs near enough to
//! matter, kept from one search to the next while the motion allows
//! (`pairs.rs`); the distance functions are in `distance.rs`. A minimum
//! does not depend on the order pairs are met in, and the pairs parted and
//! the edge pairs pushed apart come in the list's order, which the
//! positions alone fix: the results are the same for any number of threads.

mod distance;
mod pairs;

use glam::Vec3;

use pairs::{NearPairs, Nearest};

use crate::solver::cloth::ClothSpec;

/// The fraction of the distance each particle may move: below ½, with room
/// for rounding.
pub(crate) const GAMMA: f32 = 0.4;

/// The query radius, in rest spacings: distances beyond it count as it.
/// In a flat, unstretched grid no primitive comes nearer to one it shares
/// no particle with than `1/√2` of a spacing (a corner against the
/// diagonal across its cell), so a flat cloth finds no pair at all.
pub(crate) const RADIUS: f32 = 0.5;

/// How near, in thicknesses, two edges may come before they are pushed
/// apart ([`PathCheck::keep_edges_apart`]).
pub(crate) const EDGE_GAP: f32 = 0.25;

/// How many times the pairs that fail the path's test are parted
/// before every particle is bounded instead ([`PathCheck::path_clear`]).
const PART_ROUNDS: u32 = 4;

/// How much more a driven particle weighs than a free one with the same
/// bound in the common motion ([`PathCheck::common_motion`]).
const DRIVEN_WEIGHT: f64 = 1e4;

/// The path check of a substep: the near pairs it tests, and, for the
/// fallback, each particle's bound and where it was found.
#[derive(Clone, Debug, Default)]
pub(crate) struct PathCheck {
    near: NearPairs,
    /// The substep's start; empty: nothing to check or clamp.
    from: Vec<Vec3>,
    /// The positions the bounds were found at; empty: none.
    start: Vec<Vec3>,
    /// Per particle, how far beyond the common motion it may move from
    /// `start` (infinite for an exempt particle).
    bound: Vec<f32>,
    /// Scratch: per particle, the smallest distance found.
    nearest: Vec<f32>,
    /// The edge pairs nearer than the thickness.
    pairs: Vec<EdgePair>,
    /// Whether no crossing can have formed since the cloth was last found
    /// free of them: false once a driven particle, which is not clamped,
    /// went beyond its bound.
    pub checked: bool,
    /// Whether the last [`PathCheck::path_clear`] parted a pair.
    pub parted: bool,
}

impl PathCheck {
    /// Forgets the bounds and the substep's start: nothing is clamped
    /// until the next [`PathCheck::begin`].
    pub(crate) fn clear(&mut self) {
        self.from.clear();
        self.start.clear();
        self.near.clear();
        self.checked = false;
    }

    /// Starts a substep at `x` (free of crossings but for the `exempt`
    /// particles): no bound yet, the near list made to hold at `x`
    /// (searched again there if a particle has drifted too far since the
    /// last search), and the edge pairs nearer than a quarter of the
    /// thickness found, to be kept apart.
    pub(crate) fn begin(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        exempt: Option<&[bool]>,
    ) {
        self.start.clear();
        self.bound.clear();
        self.pairs.clear();
        self.from.clear();
        self.from.extend_from_slice(x);
        self.near.new_substep();
        if !self.near.holds(x, 0.0, exempt) && !self.near.search_ahead(x, triangles, spec) {
            return;
        }
        let (dx, dy) = spec.spacing();
        let keep = (EDGE_GAP * spec.thickness).min(RADIUS * dx.min(dy));
        self.nearest.clear();
        self.nearest.resize(x.len(), keep);
        self.near.nearest(
            x,
            triangles,
            spec,
            keep,
            Nearest {
                nearest: &mut self.nearest,
                pairs: &mut self.pairs,
                keep,
            },
        );
        self.pairs.sort_unstable_by_key(|p| (p.e, p.f));
    }

    /// Whether the straight path from the substep's start to `x` is known
    /// to form no crossing (`NearPairs::passes`), searching again at the
    /// start if a particle drifted beyond the list (allowing it this
    /// substep's drift if it moved that far in it alone), and else parting
    /// the pairs that approach too fast, up to [`PART_ROUNDS`] times.
    pub(crate) fn path_clear(
        &mut self,
        x: &mut [Vec3],
        inv_mass: &[f32],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        exempt: Option<&[bool]>,
    ) -> bool {
        self.parted = false;
        if self.from.len() != x.len() || self.near.passes(x, &self.from, triangles, exempt) {
            return true;
        }
        // Drifted beyond the list: search again at the start, and if a
        // particle moves farther in this substep alone than the list
        // allows, with room for the moves measured.
        if !self.near.pairs_failed() && !self.near.searched_at(&self.from) {
            if !self.near.search_ahead(&self.from, triangles, spec) {
                return false;
            }
            if self.near.passes(x, &self.from, triangles, exempt) {
                return true;
            }
        }
        if !self.near.pairs_failed() {
            if !self.near.search_for_substep(&self.from, triangles, spec) {
                return false;
            }
            if self.near.passes(x, &self.from, triangles, exempt) {
                return true;
            }
        }
        for _ in 0..PART_ROUNDS {
            self.parted = true;
            self.near.part_failing(x, inv_mass);
            if self.near.passes(x, &self.from, triangles, exempt) {
                return true;
            }
        }
        false
    }

    /// [`PathCheck::path_clear`] for `x`, moved from `before`, to which the
    /// path from the substep's start was cleared (by the check or by the
    /// bounds): only the pairs with a particle that moved since are checked
    /// again, the others' corners being where they were.
    pub(crate) fn path_clear_after(
        &mut self,
        x: &mut [Vec3],
        before: &[Vec3],
        inv_mass: &[f32],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        exempt: Option<&[bool]>,
    ) -> bool {
        self.near.check_only_moved(x, before);
        let clear = self.path_clear(x, inv_mass, triangles, spec, exempt);
        self.near.check_all();
        clear
    }

    /// Finds every particle's bound at the substep's start.
    pub(crate) fn find_at_start(
        &mut self,
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        exempt: Option<&[bool]>,
    ) {
        let from = std::mem::take(&mut self.from);
        self.find(&from, triangles, spec, exempt);
        self.from = from;
    }

    /// Finds every particle's bound at positions `x` (free of crossings but
    /// for the `exempt` particles, whose bound is infinite).
    pub(crate) fn find(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        exempt: Option<&[bool]>,
    ) {
        let n = x.len();
        let (dx, dy) = spec.spacing();
        let r = RADIUS * dx.min(dy);
        self.start.clear();
        self.start.extend_from_slice(x);
        self.nearest.clear();
        self.nearest.resize(n, r);
        self.pairs.clear();
        let found = self.near.nearest(
            x,
            triangles,
            spec,
            r,
            Nearest {
                nearest: &mut self.nearest,
                pairs: &mut self.pairs,
                keep: (EDGE_GAP * spec.thickness).min(r),
            },
        );
        // In one order whatever the search met them in: they are pushed
        // apart one after another.
        self.pairs.sort_unstable_by_key(|p| (p.e, p.f));
        self.bound.clear();
        if !found {
            self.bound.resize(n, 0.0);
            return;
        }
        self.bound
            .extend(self.nearest.iter().enumerate().map(|(i, &d)| {
                if exempt.is_some_and(|t| t.get(i) == Some(&true)) {
                    f32::INFINITY
                } else {
                    GAMMA * d
                }
            }));
    }

    /// Brings every free particle at `x` back within its bound of where
    /// the particles' mean displacement since the bounds were found
    /// carried it.
    /// A particle a body drives (no `inv_mass`), or the `pulled` one,
    /// beyond its bound is left where its body (or its pull) took it, and
    /// the cloth is no longer known to be free of crossings. Only the
    /// driven ones weigh more in the mean: a pulled particle goes its own
    /// way, not the cloth's.
    /// Returns how many free particles it moved.
    pub(crate) fn clamp(
        &mut self,
        x: &mut [Vec3],
        inv_mass: &[f32],
        pulled: Option<usize>,
    ) -> usize {
        let mut moved = 0;
        if self.start.len() != x.len() {
            return moved;
        }
        let t = self.common_motion(x, inv_mass);
        if !t.is_finite() {
            return moved;
        }
        let moves = x.iter_mut().zip(&self.start).zip(&self.bound).zip(inv_mass);
        for (i, (((now, &then), &b), &w)) in moves.enumerate() {
            if b == f32::INFINITY {
                continue;
            }
            let rel = *now - then - t;
            let len2 = rel.length_squared();
            if len2 > b * b {
                if w == 0.0 || pulled == Some(i) {
                    self.checked = false;
                    continue;
                }
                *now = then + t + rel * (b / len2.sqrt());
                moved += 1;
            }
        }
        moved
    }
}

impl PathCheck {
    /// The common translation the bounds are measured from: the mean
    /// displacement since the bounds were found, each particle weighted by
    /// `1 / b²`, so that the particles with the least room (near another
    /// layer, resting on a collider) move least beyond it, and the driven
    /// particles, which cannot be clamped, [`DRIVEN_WEIGHT`] times more.
    fn common_motion(&self, x: &[Vec3], inv_mass: &[f32]) -> Vec3 {
        let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0f64);
        for (((a, b), &bound), &m) in x.iter().zip(&self.start).zip(&self.bound).zip(inv_mass) {
            if bound == f32::INFINITY {
                continue;
            }
            let driven = if m == 0.0 { DRIVEN_WEIGHT } else { 1.0 };
            let w = driven / (bound as f64).max(1e-9).powi(2);
            sum += (*a - *b).as_dvec3() * w;
            weight += w;
        }
        if weight > 0.0 {
            (sum / weight).as_vec3()
        } else {
            mean_displacement(x, &self.start)
        }
    }
}

impl PathCheck {
    /// Pushes every edge pair found nearer than the thickness apart to it,
    /// along the direction between their nearest points when found (the
    /// side they were on), one pair after another; pairs with an exempt
    /// particle are left alone.
    pub(crate) fn keep_edges_apart(
        &self,
        x: &mut [Vec3],
        inv_mass: &[f32],
        thickness: f32,
        exempt: Option<&[bool]>,
    ) {
        if self.from.len() != x.len() {
            return;
        }
        for p in &self.pairs {
            let [e0, e1] = p.e.map(|k| k as usize);
            let [f0, f1] = p.f.map(|k| k as usize);
            if [e0, e1, f0, f1]
                .iter()
                .any(|&k| exempt.is_some_and(|t| t[k]))
            {
                continue;
            }
            let [s, t] = p.at;
            let pe = x[e0] + (x[e1] - x[e0]) * s;
            let pf = x[f0] + (x[f1] - x[f0]) * t;
            let c = (pe - pf).dot(p.normal) - thickness;
            if c >= 0.0 {
                continue;
            }
            let k = [1.0 - s, s, 1.0 - t, t];
            let ids = [e0, e1, f0, f1];
            let w: f32 = (0..4).map(|j| k[j] * k[j] * inv_mass[ids[j]]).sum();
            if w <= 0.0 {
                continue;
            }
            let l = -c / w;
            for j in 0..4 {
                let sign = if j < 2 { 1.0 } else { -1.0 };
                x[ids[j]] += p.normal * (sign * l * k[j] * inv_mass[ids[j]]);
            }
        }
    }
}

/// Two edges nearer than the thickness at the bounds' positions, kept
/// apart along the direction between their nearest points there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EdgePair {
    pub(super) e: [u32; 2],
    pub(super) f: [u32; 2],
    /// Where along `e` and `f` the nearest points were.
    pub(super) at: [f32; 2],
    /// From `f`'s nearest point to `e`'s, unit.
    pub(super) normal: Vec3,
}

/// The mean displacement from `then` to `now`, every particle alike.
pub(super) fn mean_displacement(now: &[Vec3], then: &[Vec3]) -> Vec3 {
    let mut sum = glam::DVec3::ZERO;
    for (a, b) in now.iter().zip(then) {
        sum += (*a - *b).as_dvec3();
    }
    (sum / now.len().max(1) as f64).as_vec3()
}
