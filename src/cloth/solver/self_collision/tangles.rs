//! What self-collision measures and undoes: the pairs closer than the
//! thickness ([`for_each_close`]), the mesh's edges that cross a triangle
//! ([`crossings`]), and the particles a jerk left tangled, which the
//! contacts leave out for a while ([`SelfContacts::find_tangles`]).

use glam::Vec3;

use super::broad_phase::{GROUP, NearTriangles, SpatialHash};
use super::untangle::Crossing;
use super::{Foot, SelfContacts, Triangle, bounds};
use crate::solver::cloth::ClothSpec;
use crate::solver::topology::Topology;

/// Calls `f(p, triangle, depth)` for every particle–triangle pair (`p` not
/// a corner) closer than `thickness`, with its foot in the triangle:
/// `depth = thickness − |distance|`, how far the pair is inside the
/// thickness. Only positions are read.
pub fn for_each_close(
    x: &[Vec3],
    mesh: &Topology,
    spec: &ClothSpec,
    mut f: impl FnMut(u32, [u32; 3], f32),
) {
    let h = spec.thickness;
    if h <= 0.0 {
        return;
    }
    let (dx, dy) = spec.spacing();
    let mut hash = SpatialHash::default();
    hash.build(x, dx.max(dy));
    for (&tri, &rim) in mesh.triangles.iter().zip(&mesh.rims) {
        let corners = tri.map(|k| x[k as usize]);
        let (lo, hi) = bounds(corners, h);
        hash.query(lo, hi, |p| {
            if tri.contains(&p) {
                return;
            }
            if let Some(foot) = Foot::of(x[p as usize], corners)
                && foot.inside(rim)
                && foot.distance.abs() < h
            {
                f(p, tri, h - foot.distance.abs());
            }
        });
    }
}

/// Where segment `u → v` crosses triangle `t`, as the fraction of the way
/// from `u`, given the ends' signed distances `(du, dv)` from its plane and
/// its [`edge_margins`]: the ends on opposite sides of the plane and the
/// crossing point inside the triangle, each by more than [`ON_PLANE`].
/// `None` otherwise: an edge that only touches the triangle, or lies in its
/// plane (two layers pressed flat on the ground), does not cross.
#[inline]
fn crosses_at(
    u: Vec3,
    v: Vec3,
    (du, dv): (f32, f32),
    t: &Triangle,
    margins: &[f32; 3],
) -> Option<f32> {
    if du * dv >= 0.0 || du.abs() <= ON_PLANE || dv.abs() <= ON_PLANE {
        return None;
    }
    let at = du / (du - dv);
    let foot = t.foot(u + (v - u) * at);
    (0..3).all(|k| foot.bary[k] > margins[k]).then_some(at)
}

/// [`ON_PLANE`] in barycentric terms at each corner: a point's coordinate
/// `b_k` times twice the area over the opposite edge is its distance from
/// that edge.
fn edge_margins(t: &Triangle) -> [f32; 3] {
    let corners = [t.corner, t.corner + t.e1, t.corner + t.e2];
    std::array::from_fn(|k| {
        let edge = corners[(k + 2) % 3].distance(corners[(k + 1) % 3]);
        ON_PLANE * edge * t.inv_area2
    })
}

/// How close to a triangle's plane or edges, in metres, a point counts as
/// on them rather than on a side: 1 µm, far below any thickness and far
/// above `f32` rounding at the scale of a cloth.
pub const ON_PLANE: f32 = 1e-6;

/// The grid's edges (weft, warp, and the diagonal that splits each cell into
/// its two triangles) that leave particle `p` towards higher indices, then
/// towards lower ones: every edge of the triangle mesh at `p`.
#[inline]
pub(super) fn edges_at(p: u32, spec: &ClothSpec) -> impl Iterator<Item = u32> {
    let (w, h) = (spec.weft, spec.warp);
    let (i, j) = (p % w, p / w);
    let (right, up, left, down) = (i + 1 < w, j + 1 < h, i > 0, j > 0);
    [
        (right, p.wrapping_add(1)),
        (up, p.wrapping_add(w)),
        (right && up, p.wrapping_add(w + 1)),
        (left, p.wrapping_sub(1)),
        (down, p.wrapping_sub(w)),
        (left && down, p.wrapping_sub(w + 1)),
    ]
    .into_iter()
    .filter_map(|(there, o)| there.then_some(o))
}

/// How many (edge, triangle) pairs of the cloth's mesh cross, among pairs
/// that share no particle: 0 for a cloth that does not pass through itself.
/// Each crossing is found from the edge's end nearer the crossing point,
/// which lies within half the longest edge of the triangle's box.
pub fn crossings(x: &[Vec3], triangles: &[[u32; 3]], spec: &ClothSpec, threads: usize) -> usize {
    crossing_points(x, triangles, spec, threads).len()
}

/// Where the edges that [`crossings`] counts pass through their triangles:
/// one point per crossing, in triangle order. Found on `threads` threads,
/// each over a contiguous share of the grid's cells, joined in order: the
/// same for any number of them.
pub fn crossing_points(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    spec: &ClothSpec,
    threads: usize,
) -> Vec<Vec3> {
    let points = |part: &[[u32; 3]]| {
        let mut points = Vec::new();
        scan_crossings(x, part, spec, None, |_, _, at| points.push(at));
        points
    };
    if threads <= 1 || triangles.len() < PARALLEL_MIN_TRIANGLES {
        return points(triangles);
    }
    let share = triangles.len().div_ceil(threads).next_multiple_of(GROUP);
    std::thread::scope(|s| {
        let parts: Vec<_> = triangles
            .chunks(share)
            .map(|part| s.spawn(move || points(part)))
            .collect();
        parts
            .into_iter()
            .flat_map(|p| p.join().expect("a crossing search does not panic"))
            .collect()
    })
}

/// Triangles below which [`crossing_points`] searches on one thread: a
/// cloth of about 24 × 16 takes a few hundred microseconds, against tens of
/// microseconds to start a thread.
const PARALLEL_MIN_TRIANGLES: usize = 512;

impl SelfContacts {
    /// Finds which particles are tangled at positions `x`, the ends of the
    /// edges that cross a triangle and the triangle's corners, and returns
    /// where each (edge, triangle) pair crosses ([`crossing_points`]). The near
    /// pairs of the last substep are the candidates while they still cover
    /// `x`; the result is the same either way.
    pub(crate) fn find_tangles(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
    ) -> Vec<Vec3> {
        self.tangled.clear();
        self.tangled.resize(x.len(), false);
        let tangled = &mut self.tangled;
        let crossed = &mut self.crossed;
        crossed.clear();
        scan_crossings(x, triangles, spec, Some(&self.near), |edge, tri, at| {
            crossed.push(Crossing {
                edge,
                triangle: tri,
                at,
            });
            for k in edge.into_iter().chain(tri) {
                tangled[k as usize] = true;
            }
        });
        self.tangles_left = !crossed.is_empty();
        crossed.iter().map(|c| c.at).collect()
    }

    /// The tangled particles, while this substep leaves them out of the
    /// contacts ([`SelfContacts::leave_tangles_this_substep`]).
    pub(crate) fn tangled(&self) -> Option<&[bool]> {
        self.leaving.then_some(&self.tangled[..])
    }

    /// Whether tangles are being left alone: a watch is on, or tangles it
    /// found are still there.
    pub(crate) fn watching(&self) -> bool {
        self.watch > 0 || self.leaving
    }

    /// Leaves tangled particles out of the contacts for the next `substeps`
    /// substeps.
    pub(crate) fn watch_for_tangles(&mut self, substeps: u32) {
        self.watch = self.watch.max(substeps);
    }

    /// Whether this substep leaves tangled particles out of the contacts:
    /// while a watch is on ([`SelfContacts::watch_for_tangles`]; this call
    /// counts one substep of it), and after it for as long as tangles are
    /// still found (a tangle a jerk made is left to come apart, however long
    /// that takes, rather than held by contacts that keep the wrong sides).
    pub(crate) fn leave_tangles_this_substep(&mut self) -> bool {
        self.leaving = self.watch > 0 || (self.leaving && self.tangles_left);
        self.watch = self.watch.saturating_sub(1);
        self.leaving
    }
}

/// The hash's cells for counting crossings: a cell's rest diagonal, about
/// one triangle. (Cells sized from the longest edge would hold the whole
/// cloth once one edge is pulled long; small cells keep a query's cost to
/// the particles really near.)
fn crossing_cell(spec: &ClothSpec) -> f32 {
    let (dx, dy) = spec.spacing();
    crate::solver::portable::hypot(dx, dy)
}

/// Calls `crossing(edge, triangle)` for every (edge, triangle) pair that
/// crosses ([`crossings`]). Each crossing is found from the edge's nearer
/// end `p`, which lies within half the edge `|po|` of the crossing point,
/// and so of the triangle's box: the candidates for a triangle are the
/// particles in its box grown by half the longest edge. Particles with an
/// edge longer than a cell's rest diagonal (pulled long by a jerk) are
/// checked against every triangle instead, so that one long edge does not
/// grow every query to the whole cloth. The candidates come from `near`
/// while its pairs cover that growth, else from a new hash.
pub(super) fn scan_crossings(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    spec: &ClothSpec,
    near: Option<&NearTriangles>,
    mut crossing: impl FnMut([u32; 2], [u32; 3], Vec3),
) {
    // Half the longest edge at each particle.
    let half: Vec<f32> = (0..x.len() as u32)
        .map(|p| {
            let xp = x[p as usize];
            edges_at(p, spec).fold(0.0f32, |m, o| m.max(xp.distance(x[o as usize])))
        })
        .map(|l| 0.5 * l)
        .collect();
    let longest = half.iter().copied().fold(0.0f32, f32::max);
    if longest <= 0.0 || !longest.is_finite() {
        return;
    }
    let grow = longest.min(crossing_cell(spec));
    let near = near.filter(|n| n.covers(x, grow));
    let mut hash = SpatialHash::default();
    if near.is_none() {
        hash.build(x, crossing_cell(spec));
    }
    // A grid cell's two triangles (a group of the near pairs) share one
    // query over the union of their grown boxes.
    let pad = Vec3::splat(grow);
    for (g, tris) in triangles.chunks(GROUP).enumerate() {
        let mut ts = tris.iter().map(|&tri| TriangleCrossing::new(x, tri));
        let mut ts: [Option<TriangleCrossing>; GROUP] =
            std::array::from_fn(|_| ts.next().flatten());
        let Some((lo, hi)) = ts
            .iter()
            .flatten()
            .map(|t| (t.lo, t.hi))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        else {
            continue;
        };
        let mut visit = |p: u32| {
            let reach = half[p as usize];
            if reach > grow {
                return; // in the pass below
            }
            for t in ts.iter_mut().flatten() {
                t.edges_from(p, reach, x, spec, &mut crossing);
            }
        };
        match near {
            Some(n) => n.of_group(g).iter().copied().for_each(&mut visit),
            None => hash.query(lo - pad, hi + pad, &mut visit),
        }
    }
    let far: Vec<u32> = (0..x.len() as u32)
        .filter(|&p| half[p as usize] > grow)
        .collect();
    if far.is_empty() {
        return;
    }
    for &tri in triangles {
        let Some(mut t) = TriangleCrossing::new(x, tri) else {
            continue;
        };
        for &p in &far {
            t.edges_from(p, half[p as usize], x, spec, &mut crossing);
        }
    }
}

/// How much farther than half its edge, relatively, the nearer end of an
/// edge that crosses a triangle's plane may seem to be from that plane:
/// room for rounding (the ends' distances from the plane add up to at
/// most the edge's length).
const PLANE_SLACK: f32 = 1.001;

/// A triangle, with what counting the edges that cross it needs.
struct TriangleCrossing {
    corners: [u32; 3],
    t: Triangle,
    /// Its bounding box.
    lo: Vec3,
    hi: Vec3,
    /// [`edge_margins`], once needed.
    margins: Option<[f32; 3]>,
}

impl TriangleCrossing {
    /// The triangle with corners `tri`; `None` if it is degenerate.
    fn new(x: &[Vec3], tri: [u32; 3]) -> Option<Self> {
        let c = tri.map(|k| x[k as usize]);
        let (lo, hi) = bounds(c, 0.0);
        Some(Self {
            corners: tri,
            t: Triangle::new(c)?,
            lo,
            hi,
            margins: None,
        })
    }

    /// Whether `x` lies in the triangle's box grown by `grow`.
    #[inline(always)]
    fn near_box(&self, x: Vec3, grow: f32) -> bool {
        let grow = Vec3::splat(grow);
        x.cmpge(self.lo - grow).all() && x.cmple(self.hi + grow).all()
    }

    /// Calls `crossing` for every edge of particle `p` that crosses the
    /// triangle, `p` being its nearer end (or as near, and the lower index),
    /// so that each crossing is counted once. `reach` is half the longest
    /// edge at `p`: the nearer end of an edge that crosses lies within half
    /// the edge of the triangle's box and of its plane, so a particle
    /// farther from either is passed over before its edges are measured.
    #[inline]
    fn edges_from(
        &mut self,
        p: u32,
        reach: f32,
        x: &[Vec3],
        spec: &ClothSpec,
        crossing: &mut impl FnMut([u32; 2], [u32; 3], Vec3),
    ) {
        let tri = self.corners;
        let xp = x[p as usize];
        if tri.contains(&p) || !self.near_box(xp, reach) {
            return;
        }
        let dp = self.t.distance(xp);
        if dp.abs() <= ON_PLANE || dp.abs() > reach * PLANE_SLACK + ON_PLANE {
            return;
        }
        for o in edges_at(p, spec) {
            let xo = x[o as usize];
            let d_o = self.t.distance(xo);
            if dp * d_o >= 0.0
                || dp.abs() > d_o.abs()
                || (dp.abs() == d_o.abs() && p > o)
                || tri.contains(&o)
            {
                continue;
            }
            if !self.near_box(xp, 0.5 * xp.distance(xo)) {
                continue;
            }
            let t = &self.t;
            let margins = self.margins.get_or_insert_with(|| edge_margins(t));
            if let Some(at) = crosses_at(xp, xo, (dp, d_o), t, margins) {
                crossing([p, o], tri, xp + (xo - xp) * at);
            }
        }
    }
}
