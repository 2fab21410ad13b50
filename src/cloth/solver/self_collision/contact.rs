//! The self-contact: a particle kept on its side of a triangle, at the
//! cloth's thickness, and friction between the layers.
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
//!
//! Friction between layers is the colliders' Coulomb model
//! ([`apply_friction`]). The family that projects the contacts is
//! [`families::self_collision`](crate::solver::families::self_collision).

use glam::Vec3;

use crate::solver::kernels::{Particles, delta_mu, shift};
use crate::solver::rotation::normal_of;
use crate::solver::topology::Touches;

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
    /// the edge opposite corner `k` (used by `least`).
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
pub(super) const INSIDE: f32 = 0.01;
/// The same beyond an edge on the cloth's border: half a cell, a hem
/// around the cloth, so that a layer lying along another's border does
/// not slip round it edge first (no face is under either edge there).
pub(super) const INSIDE_RIM: f32 = 0.5;

/// A triangle, with what every foot on it needs.
#[derive(Clone, Copy, Debug)]
pub(super) struct Triangle {
    pub(super) corner: Vec3,
    pub(super) e1: Vec3,
    pub(super) e2: Vec3,
    /// The unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    pub(super) normal: Vec3,
    /// `1 / |(x_b − x_a) × (x_c − x_a)|`, one over twice the area.
    pub(super) inv_area2: f32,
}

impl Triangle {
    /// The triangle with corners `t`; `None` if it is degenerate.
    #[inline(always)]
    pub(super) fn new(t: [Vec3; 3]) -> Option<Self> {
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
    pub(super) fn distance(&self, p: Vec3) -> f32 {
        (p - self.corner).dot(self.normal)
    }

    /// The foot of `p`.
    #[inline(always)]
    pub(super) fn foot(&self, p: Vec3) -> Foot {
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

/// The lowest barycentric coordinate at corner `k` of a foot within the
/// triangle: below 0 by [`INSIDE`], or [`INSIDE_RIM`] if the edge opposite
/// `k` is on the border (`rim`), and by `more`.
#[inline(always)]
pub(super) fn least(rim: u8, k: usize, more: f32) -> f32 {
    let slack = if rim & (1 << k) != 0 {
        INSIDE_RIM
    } else {
        INSIDE
    };
    -(slack + more)
}

/// A point's foot on a triangle's plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct Foot {
    /// Barycentric coordinates of the foot.
    pub(super) bary: [f32; 3],
    /// The foot.
    pub(super) point: Vec3,
    /// The triangle's unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    pub(super) normal: Vec3,
    /// Signed distance of the point from the plane, along `normal`.
    pub(super) distance: f32,
}

impl Foot {
    /// The foot of `p` on triangle `t`; `None` for a degenerate triangle.
    #[inline(always)]
    pub(super) fn of(p: Vec3, t: [Vec3; 3]) -> Option<Self> {
        Triangle::new(t).map(|t| t.foot(p))
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem, and every edge by `more`.
    #[inline(always)]
    pub(super) fn within(&self, rim: u8, more: f32) -> bool {
        (0..3).all(|k| self.bary[k] >= least(rim, k, more))
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem.
    #[inline(always)]
    pub(super) fn inside(&self, rim: u8) -> bool {
        self.within(rim, 0.0)
    }

    /// The elements' normals `n` interpolated at the foot, or the
    /// triangle's where they disagree with it by more than 60°.
    #[inline(always)]
    pub(super) fn smooth_normal(&self, n: [Vec3; 3]) -> Vec3 {
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
pub(crate) fn project(p: &Particles, c: SelfContact, mu: &mut f32, thickness: f32, alpha_t: f32) {
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
        shift(p, i, dir * wp);
    }
    for k in 0..3 {
        if wt[k] > 0.0 {
            shift(p, t[k], dir * (-b[k] * wt[k]));
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
pub(super) fn bounds(t: [Vec3; 3], margin: f32) -> (Vec3, Vec3) {
    (
        t[0].min(t[1]).min(t[2]) - Vec3::splat(margin),
        t[0].max(t[1]).max(t[2]) + Vec3::splat(margin),
    )
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
