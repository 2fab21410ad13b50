//! Self-collision: the cloth's two sides stay apart at its thickness.
//!
//! A **contact** is a particle `p` and a triangle `(a, b, c)` of the grid
//! that `p` is not a corner of. (A triangle beside `p` in a flat or gently
//! bent cloth has `p`'s foot outside it; only a crease sharper than a right
//! angle within one cell brings a neighbour's triangle over `p`, and then the
//! contact is what keeps the crease from passing through itself.) Let
//! `y = β_a x_a + β_b x_b + β_c x_c` be the foot of `p` on the triangle's plane (barycentric `β`), and `n̄` the elements' own normals
//! interpolated there, `n̄ ∝ β_a n_a + β_b n_b + β_c n_c`. The constraint is
//! planarity's `(x_b − x_a) · n_a = 0`, made one-sided and offset by the
//! thickness `h`:
//!
//! ```text
//! C = s (x_p − y) · n̄ − h ≥ 0,   gradients  s n̄  (p),  −β_k s n̄  (k = a, b, c)
//! ```
//!
//! active while the foot lies in the triangle. The side `s = ±1` is the one
//! `p` was on at the **start** of the substep, before the update moved it: a
//! particle that the update carried through the other layer is pushed back
//! to where it came from, not on through. The interpolated element normal is
//! smooth across triangle edges (the flat triangles' normals jump), so a
//! particle sliding over the other layer is pushed in a direction that does
//! not flip from one triangle to the next; where the elements disagree with
//! the triangle (a crumpled cell) the triangle's own normal is used.
//! Positions only: no element is turned.
//!
//! Contacts are found once per substep (`SelfContacts::build`) over the
//! predicted positions with a spatial hash (`broad_phase`) and kept for
//! all the substep's sweeps; they are coloured like every other constraint
//! set, so the threads share them bit-identically. Friction between layers
//! is the colliders' Coulomb model (`apply_friction`).
//!
//! The violation reported is the penetration `h − |(x_p − y) · n|` of the
//! pairs closer than `h` ([`for_each_close`]), and separately the number of
//! grid edges that cross a triangle they share no vertex with
//! ([`crossings`]), which a crossing-free cloth keeps at zero.

use glam::Vec3;

use super::{Particles, Recorder, delta_mu, shift};
use crate::solver::broad_phase::SpatialHash;
use crate::solver::cloth::{ClothSpec, normal_of};
use crate::solver::topology::{Batched, Touches};

/// One particle against one triangle, with the side it keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelfContact {
    /// The particle.
    pub particle: u32,
    /// The triangle's particles.
    pub triangle: [u32; 3],
    /// `+1` or `−1`: the side of the triangle the particle was on at the
    /// substep's start (along its normal `(x_b − x_a) × (x_c − x_a)`).
    pub side: f32,
    /// Which of the triangle's edges lie on the cloth's border: bit `k` for
    /// the edge opposite corner `k` ([`rim`]).
    pub rim: u8,
}

impl Touches for SelfContact {
    fn particles(&self) -> impl Iterator<Item = u32> {
        [
            self.particle,
            self.triangle[0],
            self.triangle[1],
            self.triangle[2],
        ]
        .into_iter()
    }
}

/// How far a barycentric coordinate may fall below 0 with the foot still in
/// the triangle: neighbouring triangles overlap by a sliver, so a particle
/// crossing the edge between two is always under one.
const INSIDE: f32 = 0.01;
/// The same beyond an edge on the cloth's border: half a cell, a hem
/// around the cloth, so that a layer lying along another's border does
/// not slip round it edge first (no face is under either edge there).
const INSIDE_RIM: f32 = 0.5;

/// How much farther beyond a triangle's edges than [`INSIDE`] or
/// [`INSIDE_RIM`] a particle may be, in barycentric terms, to be a contact
/// of the substep: room to come over the triangle during the sweeps. A grid
/// neighbour beside a triangle sits at about −1.
const CANDIDATE: f32 = 0.25;

/// Which edges of `tri` lie on the border of a `weft × warp` grid: bit `k`
/// for the edge opposite corner `k`.
pub fn rim(tri: [u32; 3], spec: &ClothSpec) -> u8 {
    let (w, h) = (spec.weft, spec.warp);
    let on_border = |a: u32, b: u32| {
        let (ai, aj, bi, bj) = (a % w, a / w, b % w, b / w);
        (ai == bi && (ai == 0 || ai == w - 1)) || (aj == bj && (aj == 0 || aj == h - 1))
    };
    (0..3).fold(0, |m, k| {
        let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
        m | (u8::from(on_border(a, b)) << k)
    })
}

/// A triangle, with what every foot on it needs.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    corner: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// The unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    normal: Vec3,
    /// `1 / |(x_b − x_a) × (x_c − x_a)|`, one over twice the area.
    inv_area2: f32,
}

impl Triangle {
    /// The triangle with corners `t`; `None` if it is degenerate.
    #[inline(always)]
    fn new(t: [Vec3; 3]) -> Option<Self> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let cross = e1.cross(e2);
        let area2 = cross.length();
        if area2 <= 1e-12 {
            return None;
        }
        let inv_area2 = area2.recip();
        Some(Self {
            corner: t[0],
            e1,
            e2,
            normal: cross * inv_area2,
            inv_area2,
        })
    }

    /// Signed distance of `p` from the plane, along the normal.
    #[inline(always)]
    fn distance(&self, p: Vec3) -> f32 {
        (p - self.corner).dot(self.normal)
    }

    /// The foot of `p`.
    #[inline(always)]
    fn foot(&self, p: Vec3) -> Foot {
        let v = p - self.corner;
        // Cross products with the normal drop v's normal part: the foot's
        // coordinates.
        let bb = v.cross(self.e2).dot(self.normal) * self.inv_area2;
        let bc = self.e1.cross(v).dot(self.normal) * self.inv_area2;
        Foot {
            bary: [1.0 - bb - bc, bb, bc],
            point: self.corner + self.e1 * bb + self.e2 * bc,
            normal: self.normal,
            distance: v.dot(self.normal),
        }
    }
}

/// A point's foot on a triangle's plane.
#[derive(Clone, Copy, Debug)]
struct Foot {
    /// Barycentric coordinates of the foot.
    bary: [f32; 3],
    /// The foot.
    point: Vec3,
    /// The triangle's unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    normal: Vec3,
    /// Signed distance of the point from the plane, along `normal`.
    distance: f32,
}

impl Foot {
    /// The foot of `p` on triangle `t`; `None` for a degenerate triangle.
    #[inline(always)]
    fn of(p: Vec3, t: [Vec3; 3]) -> Option<Self> {
        Triangle::new(t).map(|t| t.foot(p))
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem, and every edge by `more`.
    #[inline(always)]
    fn within(&self, rim: u8, more: f32) -> bool {
        (0..3).all(|k| {
            let slack = if rim & (1 << k) != 0 {
                INSIDE_RIM
            } else {
                INSIDE
            };
            self.bary[k] >= -(slack + more)
        })
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem.
    #[inline(always)]
    fn inside(&self, rim: u8) -> bool {
        self.within(rim, 0.0)
    }

    /// The elements' normals `n` interpolated at the foot, or the
    /// triangle's where they disagree with it by more than 60°.
    #[inline(always)]
    fn smooth_normal(&self, n: [Vec3; 3]) -> Vec3 {
        let [ba, bb, bc] = self.bary;
        let m = n[0] * ba + n[1] * bb + n[2] * bc;
        let len = m.length();
        if len > 1e-6 && m.dot(self.normal) > 0.5 * len {
            m * len.recip()
        } else {
            self.normal
        }
    }
}

/// Projects one contact, keeping the layers `thickness` apart, with
/// compliance `alpha_t` (`α / Δt²`).
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    c: SelfContact,
    mu: &mut f32,
    thickness: f32,
    alpha_t: f32,
    rec: &mut R,
) {
    let i = c.particle as usize;
    let t = c.triangle.map(|k| k as usize);
    let Some(foot) = Foot::of(p.x(i), t.map(|k| p.x(k))) else {
        return;
    };
    if !foot.inside(c.rim) {
        return;
    }
    let n = foot.smooth_normal(t.map(|k| normal_of(p.q(k))));
    let violation = c.side * (p.x(i) - foot.point).dot(n) - thickness;
    if violation >= 0.0 {
        return;
    }
    let wp = p.inv_mass[i];
    let wt = t.map(|k| p.inv_mass[k]);
    let b = foot.bary;
    let w = generalised_inverse_mass(wp, wt, b);
    if w == 0.0 {
        return;
    }
    // One-sided: the multiplier only ever pushes the layers apart.
    let d = delta_mu(violation, w, alpha_t, *mu).max(-*mu);
    *mu += d;
    let dir = n * (c.side * d);
    if wp > 0.0 {
        shift(p, i, dir * wp, rec);
    }
    for k in 0..3 {
        if wt[k] > 0.0 {
            shift(p, t[k], dir * (-b[k] * wt[k]), rec);
        }
    }
}

/// `w_p + Σ β_k² w_k`: how far a contact's separation moves per unit of its
/// multiplier, for the particle's inverse mass `wp`, the corners' `wt` and
/// the foot's barycentric `b`.
#[inline(always)]
fn generalised_inverse_mass(wp: f32, wt: [f32; 3], b: [f32; 3]) -> f32 {
    wp + b[0] * b[0] * wt[0] + b[1] * b[1] * wt[1] + b[2] * b[2] * wt[2]
}

/// The box around a triangle's corners, grown by `margin`.
#[inline]
fn bounds(t: [Vec3; 3], margin: f32) -> (Vec3, Vec3) {
    (
        t[0].min(t[1]).min(t[2]) - Vec3::splat(margin),
        t[0].max(t[1]).max(t[2]) + Vec3::splat(margin),
    )
}

/// The contacts of one substep, coloured, and the hash that found them.
#[derive(Clone, Debug, Default)]
pub(crate) struct SelfContacts {
    /// The contacts, colour by colour.
    pub set: Batched<SelfContact>,
    hash: SpatialHash,
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

impl SelfContacts {
    /// Finds every particle–triangle pair closer than `reach` (or on the
    /// other side than it started on) at the predicted positions, with the
    /// side each started on, and colours them.
    pub(crate) fn build(
        &mut self,
        layers: &Layers,
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        reach: f32,
    ) {
        let Layers {
            now,
            start,
            inv_mass,
        } = *layers;
        // Cells a triangle's box (a cell's diagonal, grown by the reach) fits
        // in two of along each axis.
        let (dx, dy) = spec.spacing();
        self.hash.build(now, dx.max(dy) + 2.0 * reach);
        let mut found = Vec::new();
        for &tri in triangles {
            let corners = tri.map(|k| now[k as usize]);
            let Some(t_now) = Triangle::new(corners) else {
                continue;
            };
            let (lo, hi) = bounds(corners, reach);
            let rim = rim(tri, spec);
            let driven = tri.iter().all(|&k| inv_mass[k as usize] == 0.0);
            let mut t_start = None;
            self.hash.query(lo, hi, |p| {
                let x = now[p as usize];
                if !(x.cmpge(lo).all() && x.cmple(hi).all())
                    || tri.contains(&p)
                    || (driven && inv_mass[p as usize] == 0.0)
                {
                    return;
                }
                // Over the triangle, or near enough to come over it in the
                // sweeps; a neighbour beside it (a coordinate near −1) is not.
                let f_now = t_now.foot(x);
                if !f_now.within(rim, CANDIDATE) {
                    return;
                }
                let t_start =
                    t_start.get_or_insert_with(|| Triangle::new(tri.map(|k| start[k as usize])));
                let Some(t_start) = t_start else {
                    return;
                };
                let side = if t_start.distance(start[p as usize]) >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
                if f_now.distance.abs() < reach || f_now.distance * side < 0.0 {
                    found.push(SelfContact {
                        particle: p,
                        triangle: tri,
                        side,
                        rim,
                    });
                }
            });
        }
        self.set = Batched::coloured(found, now.len());
    }
}

/// Friction between layers: the colliders' Coulomb model. Each contact that
/// pushed in the substep (multiplier `mu > 0`) removes the tangential motion
/// of its particle relative to the triangle's point under it, up to
/// `friction` times the distance it pushed them apart, shared in proportion
/// to inverse mass. One thread, in contact order.
pub(crate) fn apply_friction(
    x: &mut [Vec3],
    start: &[Vec3],
    inv_mass: &[f32],
    contacts: &[SelfContact],
    mu: &[f32],
    friction: f32,
) {
    if friction <= 0.0 {
        return;
    }
    for (c, &m) in contacts.iter().zip(mu) {
        if m <= 0.0 {
            continue;
        }
        let i = c.particle as usize;
        let t = c.triangle.map(|k| k as usize);
        let Some(foot) = Foot::of(x[i], t.map(|k| x[k])) else {
            continue;
        };
        if !foot.inside(c.rim) {
            continue;
        }
        let b = foot.bary;
        let (wp, wt) = (inv_mass[i], t.map(|k| inv_mass[k]));
        let w = generalised_inverse_mass(wp, wt, b);
        if w == 0.0 {
            continue;
        }
        let moved = |k: usize| x[k] - start[k];
        let rel = moved(i) - (moved(t[0]) * b[0] + moved(t[1]) * b[1] + moved(t[2]) * b[2]);
        let n = foot.normal;
        let tangential = rel - n * rel.dot(n);
        let len = tangential.length();
        if len <= 1e-12 {
            continue;
        }
        let limit = friction * m * w;
        let slip = tangential * ((limit / len).min(1.0) / w);
        x[i] -= slip * wp;
        for k in 0..3 {
            x[t[k]] += slip * (b[k] * wt[k]);
        }
    }
}

/// Calls `f(p, triangle, depth)` for every particle–triangle pair (`p` not
/// a corner) closer than `thickness`, with its foot in the triangle:
/// `depth = thickness − |distance|`, how far the pair is inside the
/// thickness. Only positions are read.
pub fn for_each_close(
    x: &[Vec3],
    triangles: &[[u32; 3]],
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
    for &tri in triangles {
        let corners = tri.map(|k| x[k as usize]);
        let (lo, hi) = bounds(corners, h);
        let rim = rim(tri, spec);
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
/// from `u`: its ends on opposite sides of the triangle's plane and the
/// crossing point inside the triangle, each by more than [`ON_PLANE`].
/// `None` otherwise: an edge that only touches the triangle, or lies in its
/// plane (two layers pressed flat on the ground), does not cross.
fn segment_crosses(u: Vec3, v: Vec3, t: &Triangle) -> Option<f32> {
    let (du, dv) = (t.distance(u), t.distance(v));
    if du * dv >= 0.0 || du.abs() <= ON_PLANE || dv.abs() <= ON_PLANE {
        return None;
    }
    let at = du / (du - dv);
    let foot = t.foot(u + (v - u) * at);
    // Barycentric `b_k` times twice the area over the opposite edge: the
    // distance from that edge.
    let corners = [t.corner, t.corner + t.e1, t.corner + t.e2];
    let inside = (0..3).all(|k| {
        let edge = corners[(k + 2) % 3].distance(corners[(k + 1) % 3]);
        foot.bary[k] > ON_PLANE * edge * t.inv_area2
    });
    inside.then_some(at)
}

/// How close to a triangle's plane or edges, in metres, a point counts as
/// on them rather than on a side: 1 µm, far below any thickness and far
/// above `f32` rounding at the scale of a cloth.
pub const ON_PLANE: f32 = 1e-6;

/// The grid's edges (weft, warp, and the diagonal that splits each cell into
/// its two triangles) that leave particle `p` towards higher indices, then
/// towards lower ones: every edge of the triangle mesh at `p`.
fn edges_at(p: u32, spec: &ClothSpec) -> impl Iterator<Item = u32> {
    let (w, h) = (spec.weft as i64, spec.warp as i64);
    let (i, j) = (p as i64 % w, p as i64 / w);
    [(1, 0), (0, 1), (1, 1), (-1, 0), (0, -1), (-1, -1)]
        .into_iter()
        .filter(move |(di, dj)| (0..w).contains(&(i + di)) && (0..h).contains(&(j + dj)))
        .map(move |(di, dj)| ((j + dj) * w + i + di) as u32)
}

/// How many (edge, triangle) pairs of the cloth's mesh cross, among pairs
/// that share no particle: 0 for a cloth that does not pass through itself.
/// Each crossing is found from the edge's end nearer the crossing point,
/// which lies within half the longest edge of the triangle.
pub fn crossings(x: &[Vec3], triangles: &[[u32; 3]], spec: &ClothSpec) -> usize {
    let longest = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| x[a as usize].distance(x[b as usize]))
        .fold(0.0f32, f32::max);
    if longest <= 0.0 || !longest.is_finite() {
        return 0;
    }
    // Cells the query boxes (a triangle grown by half the longest edge) fit
    // in two of along each axis.
    let mut hash = SpatialHash::default();
    hash.build(x, 2.0 * longest);
    let mut count = 0;
    for &tri in triangles {
        let corners = tri.map(|k| x[k as usize]);
        let Some(t) = Triangle::new(corners) else {
            continue;
        };
        let (lo, hi) = bounds(corners, 0.5 * longest);
        hash.query(lo, hi, |p| {
            let xp = x[p as usize];
            if !(xp.cmpge(lo).all() && xp.cmple(hi).all()) || tri.contains(&p) {
                return;
            }
            let dp = t.distance(xp);
            for o in edges_at(p, spec) {
                if tri.contains(&o) || dp * t.distance(x[o as usize]) >= 0.0 {
                    continue;
                }
                if let Some(at) = segment_crosses(x[p as usize], x[o as usize], &t)
                    && (at < 0.5 || (at == 0.5 && p < o))
                {
                    count += 1;
                }
            }
        });
    }
    count
}
