//! Planarity: neighbours share a tangent plane (co-planarity).
//!
//! The paper prints `δx_a = v·n_a`, `δx_b = −v·n_b`, `v = n_a × s_ab`. Read as
//! the gradients of the co-planarity violation `n_a · s` (the distance of `b`
//! from `a`'s tangent plane): moving `b` along `n_a`, `a` against it, and
//! turning `a` about `v = n_a × s` all reduce it. weft projects the same
//! condition as an angle (see [`one_side`]) so that it stays well posed for
//! large violations. Each edge is projected from both ends, `b` into `a`'s
//! plane and `a` into `b`'s. The violation reported is `|n_a · s| / L`, the
//! sine of the angle between the edge and the plane.

use glam::Vec3;

use super::{Particles, Recorder, shift, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Pair};

/// Projects one edge from both ends.
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    pair: Pair,
    weight: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    one_side(p, pair.a as usize, pair.b as usize, weight, rot, rec);
    one_side(p, pair.b as usize, pair.a as usize, weight, rot, rec);
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
    weight: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let n = normal_of(p.q(e));
    let s = p.x(o) - p.x(e);
    let len = s.length();
    if len <= 1e-9 {
        return;
    }
    let dir = s / len;
    let sin = n.dot(dir).clamp(-1.0, 1.0);
    let axis = n.cross(dir);
    let cos = axis.length();
    if cos <= 1e-6 {
        return; // normal along the edge: an unstable balance the others break
    }
    let (axis, across) = (axis / cos, (n - dir * sin) / cos);
    let alpha = super::asin(sin);
    let (we, wo, be) = (p.inv_mass[e], p.inv_mass[o], p.inv_inertia[e]);
    let w = (we + wo) / (len * len) + be;
    if w <= 0.0 {
        return;
    }
    let delta = -weight * alpha / w;
    if wo > 0.0 {
        shift(p, o, across * (wo * delta / len), rec);
    }
    if we > 0.0 {
        shift(p, e, across * (-we * delta / len), rec);
    }
    if be > 0.0 {
        turn(p, e, axis * (be * delta), rot, rec);
    }
}

/// The larger of the two one-sided violations, `|n · s| / L`.
#[inline]
pub fn violation(x: &[Vec3], normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let s = x[b] - x[a];
    normal(a).dot(s).abs().max(normal(b).dot(s).abs()) / pair.rest
}
