//! Normality: the normals of neighbours agree (co-normality), and the cloth
//! resists in-plane shear.
//!
//! The paper prints `δθ = λ (n_a × n_b)`: turn each normal about
//! `n_a × n_b` toward the other. The violation is the angle
//! `C = ∠(n_a, n_b)` on every weft and warp edge, with rotational gradients
//! `∓ (n_a × n_b) / |n_a × n_b|`; positions do not move. Each turn is shaped
//! by Eq. 3. The violation reported is the angle, in radians.
//!
//! The paper pairs normality with shear ("normality & shear"), and so does
//! weft: the same weight sets the stiffness of the cell diagonals, soft
//! distance constraints ([`super::stretch::project`]) that let the weave
//! shear the way cloth does instead of holding it square like a board.
//!
//! Two normals pointing exactly apart have `n_a × n_b = 0`, which would make
//! a flipped element a fixed point; there the turn is about the axis
//! `n_a × ŝ` (any axis across `n_a` flips it back), by the full angle `π`.

use glam::Vec3;

use super::{Particles, Recorder, delta_mu, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Pair};

/// Projects the normals of one edge toward each other, with compliance
/// `alpha_t` (`α / Δt²`, for a square cell).
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    pair: Pair,
    mu: &mut f32,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let (ba, bb) = (p.inv_inertia[a], p.inv_inertia[b]);
    let w = ba + bb;
    if w <= 0.0 {
        return;
    }
    let (na, nb) = (normal_of(p.q(a)), normal_of(p.q(b)));
    let Some((axis, angle)) = axis_angle(na, nb, p.x(b) - p.x(a)) else {
        return;
    };
    let mut d = delta_mu(angle, w, alpha_t / pair.aspect, *mu);
    // Gradients: −axis at a, +axis at b; the larger turn is Eq. 3's to shape.
    d *= rot.scale(angle, ba.max(bb) * d.abs());
    *mu += d;
    if ba > 0.0 {
        turn(p, a, axis * (-ba * d), rec);
    }
    if bb > 0.0 {
        turn(p, b, axis * (bb * d), rec);
    }
}

/// The unit axis that turns `na` toward `nb`, and the angle between them;
/// `None` when they agree. Exactly opposite normals turn about `na × edge`.
#[inline(always)]
fn axis_angle(na: Vec3, nb: Vec3, edge: Vec3) -> Option<(Vec3, f32)> {
    let axis = na.cross(nb);
    let sin = axis.length();
    if sin > 1e-9 {
        return Some((axis * sin.recip(), super::atan2(sin, na.dot(nb))));
    }
    if na.dot(nb) >= 0.0 {
        return None;
    }
    let across = na
        .cross(edge)
        .try_normalize()
        .unwrap_or_else(|| na.any_orthonormal_vector());
    Some((across, std::f32::consts::PI))
}

/// The angle between the two normals, in radians.
#[inline]
pub fn violation(normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (na, nb) = (normal(pair.a as usize), normal(pair.b as usize));
    na.cross(nb).length().atan2(na.dot(nb))
}
