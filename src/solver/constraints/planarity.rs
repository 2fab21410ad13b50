//! Planarity: neighbours share a tangent plane (co-planarity).
//!
//! The paper prints `δx_a = v·n_a`, `δx_b = −v·n_b`, `v = n_a × s_ab`. Read as
//! the gradients of the co-planarity violation `n_a · s` (the distance of `b`
//! from `a`'s tangent plane): moving `b` along `n_a`, `a` against it, and
//! turning `a` about `v = n_a × s` all reduce it. weft projects the same
//! condition as an angle (see [`one_side`]) so that it stays well posed for
//! large violations. Each edge is projected from both ends, `b` into `a`'s
//! plane and `a` into `b`'s. The violation reported is that angle, in
//! radians (the larger of the two ends).
//!
//! Planarity ties each normal to the surface around it; together with
//! normality (neighbouring normals agree) this resists bending too, on top
//! of curvature: with both rigid, a cloth could not bend at all. Their
//! default weights are soft enough that curvature's weight sets the drape
//! (`docs/method.md` has the ablation).

use glam::Vec3;

use super::{Particles, Recorder, delta_mu, shift, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Pair};

/// Projects one edge from both ends, with compliance `alpha_t` (`α / Δt²`,
/// for a square cell); `mu` holds the two sides' multipliers.
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    pair: Pair,
    mu: &mut [f32; 2],
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let alpha_t = alpha_t / pair.aspect;
    let (a, b) = (pair.a as usize, pair.b as usize);
    one_side(p, a, b, &mut mu[0], alpha_t, rot, rec);
    one_side(p, b, a, &mut mu[1], alpha_t, rot, rec);
}

/// The angle `α = asin(n · ŝ)` of the edge `e → o` out of `e`'s tangent
/// plane, with the unit rotation axis `n × ŝ / |n × ŝ|` and the unit
/// direction `n⊥` of the normal across the edge. `None` when the edge is
/// degenerate or the normal lies along it (an unstable balance the other
/// families break).
#[inline(always)]
fn out_of_plane(n: Vec3, s: Vec3) -> Option<(f32, Vec3, Vec3, f32)> {
    let len = s.length();
    if len <= 1e-9 {
        return None;
    }
    let dir = s * len.recip();
    let sin = n.dot(dir).clamp(-1.0, 1.0);
    let axis = n.cross(dir);
    let cos = axis.length();
    if cos <= 1e-6 {
        return None;
    }
    let inv_cos = cos.recip();
    Some((
        super::atan(sin * inv_cos),
        axis * inv_cos,
        (n - dir * sin) * inv_cos,
        len,
    ))
}

/// Brings `o` into the tangent plane of `e`.
///
/// The constraint is the angle `α = asin(n · ŝ)` of the edge out of the plane
/// (the same zero set as `n · s`). Its gradients stay useful even when the
/// normal lies along the edge: in rotation, the unit axis `n × ŝ / |n × ŝ|`;
/// in position, `n⊥ / |s|` with `n⊥` the normal made perpendicular to the
/// edge, so the edge turns instead of shortening and never fights the length
/// limit.
#[inline]
fn one_side<R: Recorder>(
    p: &Particles,
    e: usize,
    o: usize,
    mu: &mut f32,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let Some((alpha, axis, across, len)) = out_of_plane(normal_of(p.q(e)), p.x(o) - p.x(e)) else {
        return;
    };
    let (we, wo, be) = (p.inv_mass[e], p.inv_mass[o], p.inv_inertia[e]);
    let inv_len = len.recip();
    let w = (we + wo) * inv_len * inv_len + be;
    if w <= 0.0 {
        return;
    }
    let mut d = delta_mu(alpha, w, alpha_t, *mu);
    d *= rot.scale(alpha.abs(), be * d.abs());
    *mu += d;
    let step = across * (d * inv_len);
    if wo > 0.0 {
        shift(p, o, step * wo, rec);
    }
    if we > 0.0 {
        shift(p, e, step * -we, rec);
    }
    if be > 0.0 {
        turn(p, e, axis * (be * d), rec);
    }
}

/// The larger of the two one-sided angles `|α|` that the projection removes,
/// in radians.
#[inline]
pub fn violation(x: &[Vec3], normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let side = |e: usize, o: usize| out_of_plane(normal(e), x[o] - x[e]).map_or(0.0, |v| v.0.abs());
    side(a, b).max(side(b, a))
}
