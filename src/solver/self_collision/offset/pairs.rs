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
//! The search tests bounding spheres before distances. A particle nearer
//! than `ρ = r + skin` to a triangle is within `ρ` and the triangle's
//! radius of its centroid; two edges nearer than `ρ` have midpoints within
//! `ρ` and both half-lengths. A spatial hash of the particles (then of the
//! edges' midpoints) gives the candidates; the threads search contiguous
//! blocks of triangles (then edges), joined in block order, so the list
//! does not depend on the number of threads.

use glam::Vec3;

use super::distance::{closest_on_segments, point_triangle};
use super::{EdgePair, mean_displacement};
use crate::solver::cloth::ClothSpec;
use crate::solver::self_collision::broad_phase::SpatialHash;
use crate::solver::self_collision::tangles::edges_at;
use crate::solver::team;

/// The list's skin, in rest spacings: how far, twice over, the particles
/// may drift beyond their mean motion before the list is searched again.
const SKIN: f32 = 1.0;

/// Triangles (and edges) a thread searches at a time.
const BLOCK: usize = 64;

/// Triangles below which a search runs on one thread.
const PARALLEL_MIN: usize = 256;

/// The near pairs, and where they were found.
#[derive(Clone, Debug, Default)]
pub(super) struct NearPairs {
    hash: SpatialHash,
    /// Particle against triangle: `(particle, triangle)` and their
    /// distance at the search.
    faces: Vec<(u32, u32, f32)>,
    /// Edge against edge, sharing no particle, and their distance at the
    /// search.
    edges: Vec<([u32; 2], [u32; 2], f32)>,
    /// The positions of the last search; empty: none yet.
    at: Vec<Vec3>,
    /// The radius and skin of the last search.
    reach: (f32, f32),
    /// Scratch: each particle's drift since the search.
    drift: Vec<f32>,
    /// Scratch for a search: each triangle's centroid and the radius about
    /// it that holds its corners; the edges, their midpoints and
    /// half-lengths.
    spheres: Vec<(Vec3, f32)>,
    segments: Vec<[u32; 2]>,
    middles: Vec<(Vec3, f32)>,
    points: Vec<Vec3>,
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
        let drift = &self.drift;
        let most = |ids: &[u32]| ids.iter().fold(0.0f32, |m, &k| m.max(drift[k as usize]));
        for &(p, t, d) in &self.faces {
            let tri = triangles[t as usize];
            if d - drift[p as usize] - most(&tri) >= r {
                continue;
            }
            let d = point_triangle(x[p as usize], tri.map(|k| x[k as usize]));
            if d < r {
                for k in std::iter::once(p).chain(tri) {
                    let m = &mut out.nearest[k as usize];
                    *m = m.min(d);
                }
            }
        }
        for &(e, f, d) in &self.edges {
            if d - most(&e) - most(&f) >= r {
                continue;
            }
            let [u, v, a, b] = [e[0], e[1], f[0], f[1]].map(|k| x[k as usize]);
            let (d, se, sf) = closest_on_segments(u, v, a, b);
            if d >= r {
                continue;
            }
            for k in e.into_iter().chain(f) {
                let m = &mut out.nearest[k as usize];
                *m = m.min(d);
            }
            if d < out.keep && d > 0.0 {
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
        }
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
        // Particle against triangle: the particles within `reach` of a
        // triangle's bounding sphere (about its centroid), then by distance.
        self.spheres.clear();
        self.spheres.extend(triangles.iter().map(|t| {
            let c = t.map(|k| x[k as usize]);
            let centre = (c[0] + c[1] + c[2]) / 3.0;
            let radius = c.iter().fold(0.0f32, |m, &v| m.max(v.distance(centre)));
            (centre, radius)
        }));
        let widest = self.spheres.iter().fold(0.0f32, |m, s| m.max(s.1));
        self.hash.build(x, reach + widest);
        let threads = if triangles.len() >= PARALLEL_MIN {
            team::available()
        } else {
            1
        };
        let (hash, spheres) = (&self.hash, &self.spheres);
        let blocks = team::run_blocks(threads, triangles.len(), BLOCK, |range| {
            let mut found = Vec::new();
            for t in range {
                let (tri, (centre, radius)) = (triangles[t], spheres[t]);
                let near = reach + radius;
                let c = tri.map(|k| x[k as usize]);
                hash.query(
                    centre - Vec3::splat(near),
                    centre + Vec3::splat(near),
                    |p| {
                        let xp = x[p as usize];
                        if xp.distance_squared(centre) >= near * near || tri.contains(&p) {
                            return;
                        }
                        let d = point_triangle(xp, c);
                        if d < reach {
                            found.push((p, t as u32, d));
                        }
                    },
                );
            }
            found
        });
        self.faces.extend(blocks.into_iter().flatten());
        // Edge against edge: the edges whose midpoints are nearer than
        // `reach` and both half-lengths, then by distance; each pair once,
        // from the edge listed first.
        self.segments.clear();
        for p in 0..x.len() as u32 {
            for q in edges_at(p, spec).filter(|&q| q > p) {
                self.segments.push([p, q]);
            }
        }
        self.middles.clear();
        self.middles.extend(self.segments.iter().map(|e| {
            let (u, v) = (x[e[0] as usize], x[e[1] as usize]);
            (0.5 * (u + v), 0.5 * u.distance(v))
        }));
        let longest = self.middles.iter().fold(0.0f32, |m, s| m.max(s.1));
        self.points.clear();
        self.points.extend(self.middles.iter().map(|m| m.0));
        // Cells of half the widest query: fewer edges visited than with
        // cells that hold a query, for a few more (mostly empty) cells.
        self.hash.build(&self.points, 0.5 * (reach + 2.0 * longest));
        let (hash, segments, middles) = (&self.hash, &self.segments, &self.middles);
        let blocks = team::run_blocks(threads, segments.len(), BLOCK, |range| {
            let mut found = Vec::new();
            for i in range {
                let (e, (m, half)) = (segments[i], middles[i]);
                let (u, v) = (x[e[0] as usize], x[e[1] as usize]);
                let grow = Vec3::splat(reach + half + longest);
                hash.query(m - grow, m + grow, |j| {
                    if j as usize <= i {
                        return;
                    }
                    let f = segments[j as usize];
                    let (n, other) = middles[j as usize];
                    let near = reach + half + other;
                    if m.distance_squared(n) >= near * near
                        || f.contains(&e[0])
                        || f.contains(&e[1])
                    {
                        return;
                    }
                    let (a, b) = (x[f[0] as usize], x[f[1] as usize]);
                    let d = closest_on_segments(u, v, a, b).0;
                    if d < reach {
                        found.push((e, f, d));
                    }
                });
            }
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
