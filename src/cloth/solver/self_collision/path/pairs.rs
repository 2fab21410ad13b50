//! The primitive pairs near enough to matter for the path's check and the
//! bounds, kept from one search to the next while the motion allows (a
//! Verlet list).
//!
//! A search finds every particle–triangle and edge–edge pair nearer than
//! the reach `ρ` (plus each primitive's allowance, below), with its
//! distance `D` then. Let `Δ_i` be how far particle `i` has since moved
//! beyond the particles' mean motion (a translation changes no distance).
//! A point of a primitive is a convex combination of its corners, so a
//! pair is now at least `D − Δ_A − Δ_B` apart, `Δ_A` the largest `Δ` among
//! the corners of one primitive and `Δ_B` of the other. So:
//!
//! - a pair left out of the list (`D ≥ ρ`) is not met while every `Δ` is
//!   below `0.45 ρ` ([`NearPairs::holds`]), and stays farther than a
//!   radius `r` while every `Δ` is below `0.45 (ρ − r)`: a new search is
//!   made only once a particle has drifted farther. A search may allow each
//!   particle more ([`NearPairs::search_ahead`]): four times what it moved
//!   in its last substep, a pair then listed if nearer than `ρ` plus each
//!   primitive's largest allowance;
//! - a listed pair's lower bound `D − Δ_A − Δ_B` at a substep's start,
//!   against how far its corners moved in the substep, clears the path for
//!   most pairs without a distance ([`NearPairs::passes`]); the rest are
//!   checked along the normal between their nearest points at the start,
//!   or at the end, and parted along the start's where neither parts them
//!   ([`NearPairs::part_failing`]);
//! - for the bounds, a listed pair whose lower bound is at least `r` is
//!   farther than `r` and not measured ([`NearPairs::nearest`]).
//!
//! The search tests boxes before distances: a particle nearer than `ρ` to a
//! triangle is inside the triangle's box grown by `ρ`, and two edges nearer
//! than `ρ` have boxes that overlap when each is grown by `ρ/2` (each box,
//! the particles' too, grown by its allowance besides). The particles' and
//! the edges' boxes, sorted along the axis the cloth spreads farthest along
//! (`prune.rs`), give the candidates; their distances are measured eight at
//! a time, each bit for bit the distance measured alone (`distance.rs`).
//! The threads search contiguous blocks of triangles (then of sorted
//! edges), joined in block order, and which pairs are near depends on the
//! positions alone, so the list does not depend on the number of threads.

use glam::Vec3;

use super::distance::{
    closest_on_segments, closest_on_triangle, for_each_edge_distance, for_each_face_distance,
};
use super::{EdgePair, mean_displacement};
use crate::solver::cloth::ClothSpec;
use crate::solver::self_collision::prune::{SortedBoxes, widest_axis};
use crate::solver::self_collision::tangles::edges_at;
use crate::solver::team;

mod search;

/// The list's reach, in rest spacings: it holds every pair nearer than
/// that at the search (and a particle's allowance farther). The particles
/// may drift beyond their mean motion by 0.45 of it, less the bounds'
/// radius for the bounds, before a search is made again. Below the 0.7 of
/// a spacing a flat grid keeps a corner from the diagonal across its cell,
/// so the list leaves those neighbours out (docs/method.md §11b).
const REACH: f32 = 0.6;

/// How many substeps' moves a search allows each particle to drift
/// ([`NearPairs::search_ahead`]), and at most how many reaches.
const AHEAD: f32 = 4.0;
const AHEAD_MOST: f32 = 1.0;

/// How much farther than it moved in a substep a particle is allowed to
/// drift by a search made for that substep ([`NearPairs::search_for_substep`]).
const ALLOWANCE: f32 = 1.25;

/// How much of a pair's distance at a substep's start it may close in the
/// substep for the path to be clear ([`NearPairs::passes`]): below 1,
/// with room for rounding.
const PATH_SHARE: f32 = 0.9;

/// How much of it a pair that closed more is left to have closed once
/// parted ([`NearPairs::part_failing`]).
const PART_SHARE: f32 = 0.8;

/// How far each particle has drifted since the search beyond the
/// particles' mean motion, and each primitive's farthest corner.
#[derive(Clone, Debug, Default)]
struct Drift {
    particle: Vec<f32>,
    triangle: Vec<f32>,
    segment: Vec<f32>,
}

impl Drift {
    /// Each particle's drift from `at` to `now`.
    fn particles(&mut self, now: &[Vec3], at: &[Vec3]) {
        let t = mean_displacement(now, at);
        self.particle.clear();
        self.particle
            .extend(now.iter().zip(at).map(|(a, b)| (*a - *b - t).length()));
    }

    /// No drift: the positions of the search.
    fn zero(&mut self, n: usize) {
        self.particle.clear();
        self.particle.resize(n, 0.0);
    }

    /// Each triangle's and edge's largest drift among its corners.
    fn primitives(&mut self, triangles: &[[u32; 3]], segments: &[[u32; 2]]) {
        let drift = &self.particle;
        let most = |ids: &[u32]| ids.iter().fold(0.0f32, |m, &k| m.max(drift[k as usize]));
        self.triangle.clear();
        self.triangle.extend(triangles.iter().map(|t| most(t)));
        self.segment.clear();
        self.segment.extend(segments.iter().map(|e| most(e)));
    }
}

/// A pair's particles: one primitive's `ids[..split]`, the other's the
/// rest.
#[derive(Clone, Copy, Debug)]
struct Corners {
    ids: [u32; 4],
    split: usize,
}

impl Corners {
    /// Particle `p` and triangle `tri`.
    fn face(p: u32, tri: [u32; 3]) -> Self {
        let [a, b, c] = tri;
        Self {
            ids: [p, a, b, c],
            split: 1,
        }
    }

    /// Edges `e` and `f`.
    fn edges(e: [u32; 2], f: [u32; 2]) -> Self {
        Self {
            ids: [e[0], e[1], f[0], f[1]],
            split: 2,
        }
    }

    /// The unit direction from the other primitive's nearest point to the
    /// first's at `x`, and their distance; `None` for a degenerate triangle
    /// or primitives that touch.
    fn nearest(&self, x: &[Vec3]) -> Option<(Vec3, f32)> {
        let [a, b, c, d] = self.ids.map(|k| x[k as usize]);
        let (on_one, on_other) = if self.split == 1 {
            (a, closest_on_triangle(a, [b, c, d])?)
        } else {
            let (_, s, t) = closest_on_segments(a, b, c, d);
            (a + (b - a) * s, c + (d - c) * t)
        };
        let distance = on_one.distance(on_other);
        let normal = (on_one - on_other) / distance;
        normal.is_finite().then_some((normal, distance))
    }

    /// Whether the pair may meet on the straight path from `from` to `x`:
    /// `None` if a plane parts its corners by `1 − PATH_SHARE` of their
    /// distance at `from` at both ends, so all along the path (the gap
    /// along a fixed normal between two convex hulls is concave in the
    /// path's parameter), for the plane between the nearest points at
    /// `from` or the one between them at `x`. A degenerate triangle at
    /// `from` is left to its edges.
    fn path_failing(self, from: &[Vec3], x: &[Vec3]) -> Option<Failing> {
        let (normal, distance) = self.nearest(from)?;
        let wanted = (1.0 - PATH_SHARE) * distance;
        let parted = |n: Vec3| self.gap(from, n).ge(&wanted) && self.gap(x, n).ge(&wanted);
        if parted(normal) || self.nearest(x).is_some_and(|(n, _)| parted(n)) {
            return None;
        }
        Some(Failing {
            corners: self,
            normal,
            distance,
        })
    }

    /// How far apart along `normal` the first primitive's corners are from
    /// the other's at `x`: the least of the first's against the most of
    /// the other's.
    fn gap(&self, x: &[Vec3], normal: Vec3) -> f32 {
        let (a, b) = self.ids.split_at(self.split);
        let along = |k: &u32| normal.dot(x[*k as usize]);
        let least = a.iter().map(along).fold(f32::INFINITY, f32::min);
        let most = b.iter().map(along).fold(f32::NEG_INFINITY, f32::max);
        least - most
    }
}

/// A listed pair that failed [`NearPairs::passes`].
#[derive(Clone, Copy, Debug)]
struct Failing {
    corners: Corners,
    /// From the other primitive's nearest point to the first's at the
    /// substep's start, unit, and their distance.
    normal: Vec3,
    distance: f32,
}

/// How much, in parts of the reach, the boxes of a search are grown beyond
/// it: room for rounding, so that no pair nearer than the reach is missed.
const BOX_SLACK: f32 = 1e-4;

/// Triangles (and edges) a thread searches at a time.
const BLOCK: usize = 64;

/// Triangles below which a search runs on one thread.
const PARALLEL_MIN: usize = 256;

/// The near pairs, and where they were found.
#[derive(Clone, Debug, Default)]
pub(super) struct NearPairs {
    /// The particles, and the edges' boxes, sorted for a search.
    points: SortedBoxes,
    boxes: SortedBoxes,
    /// Particle against triangle: `(particle, triangle)` and their
    /// distance at the search.
    faces: Vec<(u32, u32, f32)>,
    /// Edge against edge (their indices in `segments`), sharing no
    /// particle, and their distance at the search.
    edges: Vec<(u32, u32, f32)>,
    /// The positions of the last search; empty: none yet.
    at: Vec<Vec3>,
    /// The reach of the last search, and each particle's allowance.
    reach: f32,
    allow: Vec<f32>,
    /// Scratch: the drifts since the search, of the positions asked about
    /// and of the substep's start.
    drift: Drift,
    drift_from: Drift,
    /// Scratch: each particle's move in the substep beyond their mean.
    step: Drift,
    /// Whether `drift_from` is the substep's start's.
    start_known: bool,
    /// Per listed pair (faces, then edges), how far its corners may move
    /// apart in the substep for its path to be clear without a test:
    /// [`PATH_SHARE`] of its lower bound at the substep's start.
    may_close: Vec<f32>,
    /// The mesh's edges, in the order the list refers to them by.
    segments: Vec<[u32; 2]>,
    /// Scratch: the pairs to measure.
    near_faces: Vec<(u32, u32)>,
    near_edges: Vec<(u32, u32)>,
    /// The pairs the last [`NearPairs::passes`] failed.
    failing: Vec<Failing>,
    /// The particles whose pairs alone are checked; every pair if empty
    /// ([`NearPairs::check_only_moved`]).
    only: Vec<bool>,
}

/// What [`NearPairs::nearest`] finds.
pub(super) struct Nearest<'a> {
    /// Per particle, the smallest distance found (left at `r` if none is
    /// nearer).
    pub nearest: &'a mut [f32],
    /// The edge pairs nearer than `keep`.
    pub pairs: &'a mut Vec<EdgePair>,
    /// How near two edges may come before they become a pair to push apart.
    pub keep: f32,
}

impl NearPairs {
    /// Forgets the list: the next call searches.
    pub(super) fn clear(&mut self) {
        self.at.clear();
    }

    /// Lowers every particle's `nearest` to its distance to the nearest
    /// primitive it shares no particle with, where that is below `r`, and
    /// collects the edge pairs nearer than `keep`. Searches again first if
    /// the list may no longer hold. Returns false if the positions are not
    /// finite (no distance can be trusted).
    pub(super) fn nearest(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        r: f32,
        out: Nearest<'_>,
    ) -> bool {
        if !self.holds(x, r, None) && !self.search(x, triangles, spec) {
            return false;
        }
        self.drift.primitives(triangles, &self.segments);
        let (drift, tri_drift) = (&self.drift.particle, &self.drift.triangle);
        let lower = |k: u32, d: f32, nearest: &mut [f32]| {
            let m = &mut nearest[k as usize];
            *m = m.min(d);
        };
        self.near_faces.clear();
        self.near_faces.extend(
            self.faces
                .iter()
                .filter(|&&(p, t, d)| d - drift[p as usize] - tri_drift[t as usize] < r)
                .map(|&(p, t, _)| (p, t)),
        );
        for_each_face_distance(x, triangles, &self.near_faces, |p, t, d| {
            if d < r {
                for k in std::iter::once(p).chain(triangles[t as usize]) {
                    lower(k, d, out.nearest);
                }
            }
        });
        // The edge pairs that may have come nearer than `r`, their
        // distances eight at a time.
        let seg_drift = &self.drift.segment;
        self.near_edges.clear();
        self.near_edges.extend(
            self.edges
                .iter()
                .filter(|&&(i, j, d)| d - seg_drift[i as usize] - seg_drift[j as usize] < r)
                .map(|&(i, j, _)| (i, j)),
        );
        let segments = &self.segments;
        for_each_edge_distance(x, segments, &self.near_edges, |i, j, d| {
            if d >= r {
                return;
            }
            let (e, f) = (segments[i as usize], segments[j as usize]);
            for k in e.into_iter().chain(f) {
                lower(k, d, out.nearest);
            }
            if d < out.keep && d > 0.0 {
                let [u, v, a, b] = [e[0], e[1], f[0], f[1]].map(|k| x[k as usize]);
                let (d, se, sf) = closest_on_segments(u, v, a, b);
                let normal = ((u + (v - u) * se) - (a + (b - a) * sf)) / d;
                if normal.is_finite() {
                    out.pairs.push(EdgePair {
                        e,
                        f,
                        at: [se, sf],
                        normal,
                    });
                }
            }
        });
        true
    }

    /// Whether the list found at the last search still holds for `x` at
    /// radius `r`: every pair left out is still farther than `r` while each
    /// particle's drift is below half of `reach − r`, with a tenth to spare
    /// for rounding. Measures each particle's drift; `exempt` particles'
    /// drifts are not held to it.
    pub(super) fn holds(&mut self, x: &[Vec3], r: f32, exempt: Option<&[bool]>) -> bool {
        if self.at.len() != x.len() {
            return false;
        }
        self.drift.particles(x, &self.at);
        let limit = 0.45 * (self.reach - r);
        self.drift
            .particle
            .iter()
            .zip(&self.allow)
            .enumerate()
            .all(|(i, (d, a))| d.le(&(limit + a)) || exempt.is_some_and(|e| e[i]))
    }

    /// Whether no pair of primitives sharing no particle can meet on the
    /// straight path from the substep's start `from` (free of crossings) to
    /// `x` (docs/method.md §11b): every particle's drift since the search
    /// is below `0.45 · reach`, and every listed pair closed less than
    /// [`PATH_SHARE`] of its distance at `from`: its primitives' largest
    /// moves in the substep beyond the mean add up to less than that share
    /// of a lower bound on it, or else the plane between its nearest points
    /// at `from`, or the one between them at `x`, parts its corners by the
    /// rest at both ends. Pairs and drifts of
    /// `exempt` particles are not held to it. The pairs that fail are kept
    /// for [`NearPairs::part_failing`].
    pub(super) fn passes(
        &mut self,
        x: &[Vec3],
        from: &[Vec3],
        triangles: &[[u32; 3]],
        exempt: Option<&[bool]>,
    ) -> bool {
        self.failing.clear();
        if !self.holds(x, 0.0, exempt) {
            return false;
        }
        // The start's drifts since the search (none if it was made there;
        // found once a substep), and this substep's moves beyond their mean.
        if !self.start_known {
            if self.at == from {
                self.drift_from.zero(x.len());
            } else {
                self.drift_from.particles(from, &self.at);
            }
            self.drift_from.primitives(triangles, &self.segments);
            let start = &self.drift_from;
            self.may_close.clear();
            self.may_close.extend(self.faces.iter().map(|&(p, t, d)| {
                PATH_SHARE * (d - start.particle[p as usize] - start.triangle[t as usize])
            }));
            self.may_close.extend(self.edges.iter().map(|&(i, j, d)| {
                PATH_SHARE * (d - start.segment[i as usize] - start.segment[j as usize])
            }));
            self.start_known = true;
        }
        self.step.particles(x, from);
        self.step.primitives(triangles, &self.segments);
        let segments = &self.segments;
        let free = |ids: &[u32]| exempt.is_none_or(|e| ids.iter().all(|&k| !e[k as usize]));
        let only = &self.only;
        let checked = |ids: &[u32]| only.is_empty() || ids.iter().any(|&k| only[k as usize]);
        // A pair at least `d − start` apart at the substep's start whose
        // corners have moved apart by at most `step` since is clear.
        let step = &self.step;
        let (faces_close, edges_close) = self.may_close.split_at(self.faces.len());
        self.near_faces.clear();
        for (&(p, t, _), close) in self.faces.iter().zip(faces_close) {
            let (p_, t_) = (p as usize, t as usize);
            if !checked(&[p]) && !checked(&triangles[t_]) {
                continue;
            }
            let moved = step.particle[p_] + step.triangle[t_];
            if !moved.lt(close) && free(&[p]) && free(&triangles[t_]) {
                self.near_faces.push((p, t));
            }
        }
        self.near_edges.clear();
        for (&(i, j, _), close) in self.edges.iter().zip(edges_close) {
            let (i_, j_) = (i as usize, j as usize);
            if !checked(&segments[i_]) && !checked(&segments[j_]) {
                continue;
            }
            let moved = step.segment[i_] + step.segment[j_];
            if !moved.lt(close) && free(&segments[i_]) && free(&segments[j_]) {
                self.near_edges.push((i, j));
            }
        }
        let failing = &mut self.failing;
        for &(p, t) in &self.near_faces {
            failing.extend(Corners::face(p, triangles[t as usize]).path_failing(from, x));
        }
        for &(i, j) in &self.near_edges {
            let corners = Corners::edges(segments[i as usize], segments[j as usize]);
            failing.extend(corners.path_failing(from, x));
        }
        self.failing.is_empty()
    }

    /// Parts each pair [`NearPairs::passes`] failed along the normal
    /// between its nearest points at the substep's start, as an inelastic
    /// touch would: each primitive is moved whole along it, shared by
    /// mass (a primitive with a driven corner stays), until the gap is
    /// `1 − PART_SHARE` of the pair's distance there. Momentum is kept.
    /// A pair with driven corners on both sides is left as it is.
    /// Where only some particles' pairs are checked, the parted pairs'
    /// corners are checked from then on too.
    pub(super) fn part_failing(&mut self, x: &mut [Vec3], inv_mass: &[f32]) {
        for f in &self.failing {
            let gap = f.corners.gap(x, f.normal);
            let wanted = (1.0 - PART_SHARE) * f.distance;
            if !gap.lt(&wanted) || !f.normal.is_finite() {
                continue;
            }
            let (one, other) = f.corners.ids.split_at(f.corners.split);
            // Each side's mass; infinite if it has a driven corner.
            let mass = |ids: &[u32]| {
                ids.iter().fold(0.0f32, |m, &k| {
                    let w = inv_mass[k as usize];
                    if w == 0.0 { f32::INFINITY } else { m + 1.0 / w }
                })
            };
            let (m1, m2) = (mass(one), mass(other));
            let share = match (m1.is_finite(), m2.is_finite()) {
                (true, true) => m2 / (m1 + m2),
                (true, false) => 1.0,
                (false, true) => 0.0,
                (false, false) => continue,
            };
            let push = f.normal * (wanted - gap);
            for &k in one {
                x[k as usize] += push * share;
            }
            for &k in other {
                x[k as usize] -= push * (1.0 - share);
            }
            if !self.only.is_empty() {
                for &k in &f.corners.ids {
                    self.only[k as usize] = true;
                }
            }
        }
    }

    /// From now on only the pairs with a corner that has moved from
    /// `before` to `x` are checked by [`NearPairs::passes`]: the path from
    /// the substep's start to `before` was cleared, and the other pairs'
    /// corners are where they were (their bounds hold for any common
    /// translation).
    pub(super) fn check_only_moved(&mut self, x: &[Vec3], before: &[Vec3]) {
        self.only.clear();
        self.only.extend(x.iter().zip(before).map(|(a, b)| a != b));
    }

    /// From now on every pair is checked again.
    pub(super) fn check_all(&mut self) {
        self.only.clear();
    }

    /// Whether the last [`NearPairs::passes`] failed on pairs (else on a
    /// drift, or it passed).
    pub(super) fn pairs_failed(&self) -> bool {
        !self.failing.is_empty()
    }

    /// A new substep starts: its start's drifts are to be found.
    pub(super) fn new_substep(&mut self) {
        self.start_known = false;
    }

    /// Whether the last search was made at `x`.
    pub(super) fn searched_at(&self, x: &[Vec3]) -> bool {
        self.at == x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Edge `e` (particles 0, 1) beside the end of edge `f` (2, 3) at the
    /// start, slid along `f` to stand over its middle at the end.
    fn sliding_over_an_end(lift: f32) -> ([Vec3; 4], [Vec3; 4]) {
        let f = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let from = [
            Vec3::new(1.2, 0.0, 0.1),
            Vec3::new(1.2, 0.0, 1.1),
            f[0],
            f[1],
        ];
        let x = [
            Vec3::new(0.0, 0.0, lift),
            Vec3::new(0.0, 0.0, lift + 1.0),
            f[0],
            f[1],
        ];
        (from, x)
    }

    #[test]
    fn an_edge_that_slides_over_another_passes_by_the_plane_at_the_end() {
        let pair = Corners::edges([0, 1], [2, 3]);
        let (from, x) = sliding_over_an_end(0.1);
        // The start's plane, from `f`'s end to `e`'s, is crossed by `f`
        // itself at the end: alone, it would part a pair that never came
        // nearer than 0.1.
        let (normal, _) = pair.nearest(&from).unwrap();
        assert!(pair.gap(&x, normal) < 0.0);
        assert!(pair.path_failing(&from, &x).is_none());
    }

    #[test]
    fn an_edge_that_comes_down_onto_another_fails() {
        let pair = Corners::edges([0, 1], [2, 3]);
        // At the end `e` is 0.01 above `f`: it closed 0.21 of 0.22.
        let (from, x) = sliding_over_an_end(0.01);
        let failing = pair.path_failing(&from, &x).expect("it approached");
        assert!(
            (failing.distance - 0.2236).abs() < 1e-3,
            "{}",
            failing.distance
        );
    }
}
