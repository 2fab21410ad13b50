//! The contact search of a substep: every particle–triangle pair near
//! enough to meet in the sweeps, picked from the broad phase's near pairs
//! eight particles at a time, and coloured ([`SelfContacts::build`]).

use glam::Vec3;

use super::broad_phase::{self, NearTriangles};
use super::{SelfContact, Triangle, bounds, least};
use crate::solver::cloth::ClothSpec;
use crate::solver::kernels::Sse as F;
use crate::solver::kernels::lanes::{LANES, each};
use crate::solver::team;
use crate::solver::topology::{Batched, Topology};

/// Positions of a contact search, in lanes.
type V3 = crate::solver::kernels::lanes::V3<F>;
/// How much farther beyond a triangle's edges than [`INSIDE`](super::INSIDE) or
/// [`INSIDE_RIM`](super::INSIDE_RIM) a particle may be, in barycentric terms, to be a contact
/// of the substep: room to come over the triangle during the sweeps. A grid
/// neighbour beside a triangle sits at about −1. A twentieth of the
/// triangle: a quarter made three times the contacts on a folded sheet
/// (every particle near an edge took the triangles beyond it too, whose
/// extended planes can put the particle on the wrong side), cost a third
/// more of the step, and let `folding_sheet` at 32 × 32 and
/// `furling_banner` at 48 × 36 cross where a twentieth does not
/// (BENCHMARKS.md, "Measured design choices").
const CANDIDATE: f32 = 0.05;

/// The contact search's test for one triangle, on [`LANES`] particles at a
/// time: is the particle inside the triangle's box grown by the reach, with
/// its foot within the triangle grown by [`CANDIDATE`] (and the hem, as
/// [`Foot::within`](super::Foot::within))? Each barycentric coordinate is one dot product,
/// `β_b = (x − x_a) · ĝ_b` and `β_c = (x − x_a) · ĝ_c` with the gradients of
/// the foot's coordinates `ĝ_b = (e₂ × c) / |c|²` and `ĝ_c = (c × e₁) / |c|²`
/// (`c = e₁ × e₂`, twice the area along the normal), and
/// `β_a = 1 − β_b − β_c`. This is the search's own definition of a
/// candidate: the particles it lets through are picked without a second
/// test, so one particle alone would be judged by the same operations.
struct Candidates {
    corner: V3,
    to_b: V3,
    to_c: V3,
    /// The lowest barycentric coordinate let through at each corner.
    least: [F; 3],
    /// The triangle's box grown by the reach.
    lo: V3,
    hi: V3,
}

impl Candidates {
    /// The test for the triangle with corners `t`, whose border edges are
    /// `rim`; `None` if it is degenerate (twice its area at most `1e-12`).
    #[inline(always)]
    fn new(t: [Vec3; 3], rim: u8, reach: f32) -> Option<Self> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let cross = e1.cross(e2);
        let area2_squared = cross.length_squared();
        if area2_squared.is_nan() || area2_squared <= 1e-24 {
            return None;
        }
        let inv = area2_squared.recip();
        let (lo, hi) = bounds(t, reach);
        Some(Self {
            corner: V3::splat(t[0]),
            to_b: V3::splat(e2.cross(cross) * inv),
            to_c: V3::splat(cross.cross(e1) * inv),
            least: std::array::from_fn(|k| F::splat(least(rim, k, CANDIDATE))),
            lo: V3::splat(lo),
            hi: V3::splat(hi),
        })
    }

    /// Bit `k` set where lane `k`'s point `x` passes.
    #[inline(always)]
    fn of(&self, x: V3) -> u32 {
        let v = x - self.corner;
        let bb = v.dot(self.to_b);
        let bc = v.dot(self.to_c);
        let ba = F::ONE - bb - bc;
        (x.in_box(self.lo, self.hi)
            & ba.simd_ge(self.least[0])
            & bb.simd_ge(self.least[1])
            & bc.simd_ge(self.least[2]))
        .to_bitmask()
    }
}

/// Up to [`LANES`] particles and their positions, in lanes.
struct Gathered {
    idx: [u32; LANES],
    x: V3,
    /// Bit `k` set if lane `k` holds a particle.
    live: u32,
}

impl Gathered {
    /// The particles `chunk` (at most [`LANES`]) at positions `x`. A short
    /// chunk is padded with its first particle, whose lanes are then masked
    /// off.
    #[inline]
    fn of(chunk: &[u32], x: &[Vec3]) -> Self {
        let idx = each(|k| chunk.get(k).copied().unwrap_or(chunk[0]));
        Self {
            idx,
            x: V3::gather(x, &idx),
            live: (1 << chunk.len()) - 1,
        }
    }
}

/// One triangle's contact search within a substep: its [`Candidates`]
/// test, and the triangle now and at the substep's start, made once a
/// particle passes.
struct Picker {
    tri: [u32; 3],
    rim: u8,
    lanes: Candidates,
    /// Every corner driven: a driven particle is no contact of it.
    driven: bool,
    now: Option<Option<Triangle>>,
    start: Option<Option<Triangle>>,
}

impl Picker {
    /// The search for triangle `tri` (border edges `rim`); `None` if it is
    /// degenerate.
    #[inline]
    fn new(tri: [u32; 3], rim: u8, layers: &Layers, reach: f32) -> Option<Self> {
        let corners = tri.map(|k| layers.now[k as usize]);
        Some(Self {
            tri,
            rim,
            lanes: Candidates::new(corners, rim, reach)?,
            driven: tri.iter().all(|&k| layers.inv_mass[k as usize] == 0.0),
            now: None,
            start: None,
        })
    }

    /// Appends the contacts among the lanes `hits` of particles `idx` that
    /// passed [`Candidates`]: not a corner, not a driven particle of a
    /// driven triangle, not tangled, and closer than `reach` to the plane or
    /// on the other side than it started on. `false` if the triangle turned
    /// out degenerate (now or at the substep's start): no more contacts.
    #[inline]
    fn take(
        &mut self,
        mut hits: u32,
        idx: &[u32; LANES],
        layers: &Layers,
        reach: f32,
        tangled: &impl Fn(u32) -> bool,
        found: &mut Vec<SelfContact>,
    ) -> bool {
        let Layers {
            now,
            start,
            inv_mass,
        } = *layers;
        let tri = self.tri;
        while hits != 0 {
            let p = idx[hits.trailing_zeros() as usize];
            hits &= hits - 1;
            if tri.contains(&p) || (self.driven && inv_mass[p as usize] == 0.0) || tangled(p) {
                continue;
            }
            let t_now = self
                .now
                .get_or_insert_with(|| Triangle::new(tri.map(|k| now[k as usize])));
            let t_start = self
                .start
                .get_or_insert_with(|| Triangle::new(tri.map(|k| start[k as usize])));
            let (Some(t_now), Some(t_start)) = (t_now, t_start) else {
                return false;
            };
            let side = if t_start.distance(start[p as usize]) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let distance = t_now.distance(now[p as usize]);
            if distance.abs() < reach || distance * side < 0.0 {
                found.push(SelfContact {
                    particle: p,
                    triangle: tri,
                    side,
                    rim: self.rim,
                });
            }
        }
        true
    }
}

/// The contacts of one substep, coloured, and the near pairs they were
/// picked from.
#[derive(Clone, Debug, Default)]
pub(crate) struct SelfContacts {
    /// The contacts, colour by colour.
    pub set: Batched<SelfContact>,
    pub(super) near: NearTriangles,
    /// Per particle: an end of an edge that crosses a triangle, or a corner
    /// of a crossed triangle, where they were last looked for
    /// ([`SelfContacts::find_tangles`]); empty until they are.
    pub(super) tangled: Vec<bool>,
    /// How many more substeps leave tangled particles out.
    pub(super) watch: u32,
    /// Whether this substep does.
    pub(super) leaving: bool,
    /// Whether tangles were found where they were last looked for.
    pub(super) tangles_left: bool,
    /// The crossings found there.
    pub(super) crossed: Vec<super::untangle::Crossing>,
}

/// The positions and orientations a contact search reads.
pub(crate) struct Layers<'a> {
    /// Predicted positions (after the update).
    pub now: &'a [Vec3],
    /// Positions at the substep's start.
    pub start: &'a [Vec3],
    /// Inverse masses: a contact between driven particles only is left out.
    pub inv_mass: &'a [f32],
}

/// Triangle groups a thread checks for contacts at a time: a few dozen
/// microseconds' work.
const PICK_BLOCK: usize = 32;

/// The near pairs' skin, in rest spacings: how far the particles may move
/// (beyond their common motion) between two searches, twice over. Larger
/// keeps more pairs to check each substep, smaller searches more often.
const SKIN: f32 = 1.0;

impl SelfContacts {
    /// Finds every particle–triangle pair closer than `reach` (or on the
    /// other side than it started on) at the predicted positions, with the
    /// side each started on, and colours them. The pairs are checked among
    /// the near pairs ([`NearTriangles`]), searched again only when the
    /// cloth has moved enough to need it.
    pub(crate) fn build(
        &mut self,
        layers: &Layers,
        mesh: &Topology,
        spec: &ClothSpec,
        reach: f32,
        threads: usize,
    ) {
        let now = layers.now;
        let (dx, dy) = spec.spacing();
        let triangles = &mesh.triangles;
        self.near
            .update(now, triangles, (reach, SKIN * dx.min(dy)), threads);
        // The threads check blocks of triangle groups; the blocks' finds,
        // joined in order, are what one thread would find alone.
        let this = &*self;
        let groups = broad_phase::groups(triangles.len());
        let blocks = team::run_blocks(threads, groups, PICK_BLOCK, |range| {
            let (mut found, mut gathered) = (Vec::new(), Vec::new());
            for g in range {
                this.pick(g, mesh, layers, reach, &mut found, &mut gathered);
            }
            found
        });
        let found = blocks.concat();
        self.set = Batched::coloured(found, now.len());
    }

    /// Appends the contacts of the triangles of group `g`
    /// ([`NearTriangles`]) among the group's near particles, triangle by
    /// triangle, each in the particles' (ascending) order: each particle
    /// inside the triangle's box grown by `reach`, with its foot over the
    /// triangle (or near enough to come over it in the sweeps:
    /// [`Candidates`]), and closer than `reach` to its plane or on the other
    /// side than it started on. A grid neighbour beside the triangle (a
    /// coordinate near −1) is not. The group's particles are gathered into
    /// lanes once (`gathered`, scratch space) for all its triangles.
    fn pick(
        &self,
        g: usize,
        mesh: &Topology,
        layers: &Layers,
        reach: f32,
        found: &mut Vec<SelfContact>,
        gathered: &mut Vec<Gathered>,
    ) {
        let near = self.near.of_group(g);
        if near.is_empty() {
            return;
        }
        let tangled = |k: u32| self.leaving && self.tangled.get(k as usize) == Some(&true);
        gathered.clear();
        for t in broad_phase::group(g, mesh.triangles.len()) {
            let tri = mesh.triangles[t];
            if tri.into_iter().any(tangled) {
                continue;
            }
            let Some(mut picker) = Picker::new(tri, mesh.rims[t], layers, reach) else {
                continue;
            };
            if gathered.is_empty() {
                gathered.extend(
                    near.chunks(LANES)
                        .map(|chunk| Gathered::of(chunk, layers.now)),
                );
            }
            for chunk in gathered.iter() {
                let hits = picker.lanes.of(chunk.x) & chunk.live;
                if hits != 0 && !picker.take(hits, &chunk.idx, layers, reach, &tangled, found) {
                    break;
                }
            }
        }
    }

    /// Drops the contacts and the near pairs (the family was turned off).
    pub(crate) fn clear(&mut self) {
        self.set = Batched::default();
        self.near.clear();
        self.tangled.clear();
        self.crossed.clear();
        self.watch = 0;
        self.leaving = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_in_lanes_are_the_particles_in_the_box_over_the_grown_triangle() {
        let mut seed = 11u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0
        };
        let reach = 0.01;
        // Coordinates this close to a bound may round either way.
        let near_bound = 1e-4;
        let (mut taken, mut left) = (0, 0);
        for round in 0..2000 {
            // Cells of a 1 cm grid, far from the origin or not, bent.
            let origin =
                Vec3::new(next(), next(), next()) * if round % 2 == 0 { 1.0 } else { 50.0 };
            let a = origin;
            let b = origin + Vec3::new(0.01, 0.002 * next(), 0.004 * next());
            let c = origin + Vec3::new(0.01 * next(), 0.01, 0.004 * next());
            let Some(t) = Triangle::new([a, b, c]) else {
                continue;
            };
            let rim = (round % 8) as u8;
            let Some(lanes) = Candidates::new([a, b, c], rim, reach) else {
                continue;
            };
            // Points in the box grown by a little more than the reach: some
            // outside it.
            let (lo, hi) = bounds([a, b, c], 1.2 * reach);
            let points: [Vec3; LANES] = std::array::from_fn(|_| {
                lo + (hi - lo) * (Vec3::new(next(), next(), next()) * 0.5 + 0.5)
            });
            let hits = lanes.of(V3::gather(&points, &each(|k| k as u32)));
            let (lo, hi) = bounds([a, b, c], reach);
            for (k, &x) in points.iter().enumerate() {
                let in_box = x.cmpge(lo).all() && x.cmple(hi).all();
                let foot = t.foot(x);
                let hit = hits & (1 << k) != 0;
                if in_box && foot.within(rim, CANDIDATE - near_bound) {
                    taken += 1;
                    assert!(hit, "round {round}: lane {k} dropped a candidate");
                }
                if !in_box || !foot.within(rim, CANDIDATE + near_bound) {
                    left += 1;
                    assert!(!hit, "round {round}: lane {k} took a particle too far");
                }
            }
        }
        assert!(taken > 1000 && left > 1000, "{taken} taken, {left} left");
    }
}
