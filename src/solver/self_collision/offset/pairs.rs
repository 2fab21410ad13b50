//! The primitive pairs near enough to matter for the offset bounds, kept
//! from one search to the next while the motion allows (a Verlet list).
//!
//! A bound needs, for every particle, the distance to the nearest primitive
//! it shares no particle with, capped at the radius `r`. A search finds
//! every particle–triangle and edge–edge pair nearer than `r + skin`, with
//! its distance `D` then. Let `δ_i` be how far particle `i` has since moved
//! beyond the particles' mean motion (a translation changes no distance).
//! A point of a primitive is a convex combination of its corners, so a pair
//! is now at least `D − δ_A − δ_B` apart, `δ_A` the largest `δ` among the
//! corners of one primitive and `δ_B` of the other. So:
//!
//! - a pair left out of the list (`D ≥ r + skin`) is still farther than
//!   `r` while every `δ` is below half the skin: the list holds, and a new
//!   search is made only once a particle has drifted farther;
//! - a listed pair with `D − δ_A − δ_B ≥ r` is still farther than `r`, and
//!   its distance is not computed at all. Right after a search only the
//!   pairs nearer than `r` are; a flat, unstretched grid has none (no
//!   primitive comes nearer than `1/√2` of a spacing to one it shares no
//!   particle with).
//!
//! The search tests boxes before distances: a particle nearer than
//! `ρ = r + skin` to a triangle is inside the triangle's box grown by `ρ`,
//! and two edges nearer than `ρ` have boxes that overlap when each is grown
//! by `ρ/2`.
//! The particles, and the edges' boxes, sorted along the axis the cloth
//! spreads farthest along (`prune.rs`), give the candidates; their
//! distances are measured eight at a time, each bit for bit the distance
//! measured alone (`distance.rs`). The threads search contiguous blocks of
//! triangles (then of sorted edges), joined in block order, and which
//! pairs are near depends on the positions alone, so the list does not
//! depend on the number of threads.

use glam::Vec3;

use super::distance::{closest_on_segments, point_triangle_distances, segment_distances};
use super::{EdgePair, mean_displacement};
use crate::solver::cloth::ClothSpec;
use crate::solver::self_collision::prune::{SortedBoxes, widest_axis};
use crate::solver::self_collision::tangles::edges_at;
use crate::solver::team;

/// The list's skin, in rest spacings: how far, twice over, the particles
/// may drift beyond their mean motion before the list is searched again.
const SKIN: f32 = 1.0;

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
    /// The radius and skin of the last search.
    reach: (f32, f32),
    /// Scratch: each particle's drift since the search.
    drift: Vec<f32>,
    /// The mesh's edges, in the order the list refers to them by.
    segments: Vec<[u32; 2]>,
    /// Scratch for [`NearPairs::nearest`]: each triangle's and edge's
    /// largest drift among its corners; the pairs to measure.
    tri_drift: Vec<f32>,
    seg_drift: Vec<f32>,
    near_faces: Vec<(u32, u32)>,
    near_edges: Vec<(u32, u32)>,
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
        let (dx, dy) = spec.spacing();
        let skin = SKIN * dx.min(dy);
        if !self.holds(x, (r, skin)) && !self.search(x, triangles, spec, (r, skin)) {
            return false;
        }
        // Each primitive's largest drift among its corners.
        let drift = &self.drift;
        let most = |ids: &[u32]| ids.iter().fold(0.0f32, |m, &k| m.max(drift[k as usize]));
        self.tri_drift.clear();
        self.tri_drift.extend(triangles.iter().map(|t| most(t)));
        self.seg_drift.clear();
        self.seg_drift.extend(self.segments.iter().map(|e| most(e)));
        let lower = |k: u32, d: f32, nearest: &mut [f32]| {
            let m = &mut nearest[k as usize];
            *m = m.min(d);
        };
        let tri_drift = &self.tri_drift;
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
        let seg_drift = &self.seg_drift;
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

    /// Whether the list found at the last search still holds for `x`
    /// (same radius and skin, every particle's drift below half the skin,
    /// with a tenth to spare for rounding), measuring each particle's drift.
    fn holds(&mut self, x: &[Vec3], reach: (f32, f32)) -> bool {
        if self.at.len() != x.len() || self.reach != reach {
            return false;
        }
        let t = mean_displacement(x, &self.at);
        self.drift.clear();
        self.drift
            .extend(x.iter().zip(&self.at).map(|(a, b)| (*a - *b - t).length()));
        let limit = 0.45 * reach.1;
        self.drift.iter().all(|d| d.le(&limit))
    }

    /// Finds every pair nearer than `r + skin` at `x`. Returns false if a
    /// position is not finite.
    fn search(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        (r, skin): (f32, f32),
    ) -> bool {
        self.at.clear();
        self.faces.clear();
        self.edges.clear();
        if !x.iter().all(|v| v.is_finite()) {
            return false;
        }
        let reach = r + skin;
        let axis = widest_axis(x);
        // Particle against triangle: the particles within `reach` of a
        // triangle's box, then by distance.
        self.points.build(axis, x.iter().map(|&p| (p, p)));
        let threads = if triangles.len() >= PARALLEL_MIN {
            team::available()
        } else {
            1
        };
        // A box test is exact per axis up to rounding: grown a little more,
        // it keeps every pair nearer than `reach`.
        let grow = reach * (1.0 + BOX_SLACK);
        let points = &self.points;
        let blocks = team::run_blocks(threads, triangles.len(), BLOCK, |range| {
            let mut near = Vec::new();
            for t in range {
                let tri = triangles[t];
                let c = tri.map(|k| x[k as usize]);
                let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                points.within(lo - Vec3::splat(grow), hi + Vec3::splat(grow), |p| {
                    if !tri.contains(&p) {
                        near.push((p, t as u32));
                    }
                });
            }
            let mut found = Vec::new();
            for_each_face_distance(x, triangles, &near, |p, t, d| {
                if d < reach {
                    found.push((p, t, d));
                }
            });
            found
        });
        self.faces.extend(blocks.into_iter().flatten());
        // Edge against edge: the edges whose boxes, each grown by half of
        // `reach`, overlap, then by distance. Each pair once, the edge
        // listed first as `e`.
        self.segments.clear();
        for p in 0..x.len() as u32 {
            for q in edges_at(p, spec).filter(|&q| q > p) {
                self.segments.push([p, q]);
            }
        }
        let half = Vec3::splat(0.5 * grow);
        self.boxes.build(
            axis,
            self.segments.iter().map(|e| {
                let (u, v) = (x[e[0] as usize], x[e[1] as usize]);
                (u.min(v) - half, u.max(v) + half)
            }),
        );
        let (boxes, segments) = (&self.boxes, &self.segments);
        let blocks = team::run_blocks(threads, boxes.len(), BLOCK, |range| {
            let mut near = Vec::new();
            boxes.overlapping(range, |i, j| near.push((i.min(j), i.max(j))));
            // Their distances eight at a time; edges that share a particle
            // are dropped after.
            let mut found = Vec::new();
            for_each_edge_distance(x, segments, &near, |i, j, d| {
                let (e, f) = (segments[i as usize], segments[j as usize]);
                if d < reach && !f.contains(&e[0]) && !f.contains(&e[1]) {
                    found.push((i, j, d));
                }
            });
            found
        });
        self.edges.extend(blocks.into_iter().flatten());
        self.at.extend_from_slice(x);
        self.reach = (r, skin);
        self.drift.clear();
        self.drift.resize(x.len(), 0.0);
        true
    }
}

/// Calls `f(i, j, d)` with the distance `d` between edges `segments[i]`
/// and `segments[j]` for every pair of `pairs`, in order, measured eight at
/// a time (the last eight padded with its last pair, not reported).
fn for_each_edge_distance(
    x: &[Vec3],
    segments: &[[u32; 2]],
    pairs: &[(u32, u32)],
    mut f: impl FnMut(u32, u32, f32),
) {
    let mut lanes = [[Vec3::ZERO; 4]; 8];
    for eight in pairs.chunks(8) {
        for (k, lane) in lanes.iter_mut().enumerate() {
            let (i, j) = eight[k.min(eight.len() - 1)];
            let (e, g) = (segments[i as usize], segments[j as usize]);
            *lane = [e[0], e[1], g[0], g[1]].map(|q| x[q as usize]);
        }
        let d = segment_distances(&lanes);
        for (&(i, j), &d) in eight.iter().zip(&d) {
            f(i, j, d);
        }
    }
}

/// Calls `f(p, t, d)` with the distance `d` of particle `p` from triangle
/// `t` for every pair of `pairs`, in order, measured eight at a time (the
/// last eight padded as for edges).
fn for_each_face_distance(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    pairs: &[(u32, u32)],
    mut f: impl FnMut(u32, u32, f32),
) {
    let mut lanes = [[Vec3::ZERO; 4]; 8];
    for eight in pairs.chunks(8) {
        for (k, lane) in lanes.iter_mut().enumerate() {
            let (p, t) = eight[k.min(eight.len() - 1)];
            let [a, b, c] = triangles[t as usize];
            *lane = [p, a, b, c].map(|q| x[q as usize]);
        }
        let d = point_triangle_distances(&lanes);
        for (&(p, t), &d) in eight.iter().zip(&d) {
            f(p, t, d);
        }
    }
}
