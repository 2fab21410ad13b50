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
//! distance constraints (`stretch::project`) that let the weave
//! shear the way cloth does instead of holding it square like a board.
//!
//! Two normals pointing exactly apart have `n_a × n_b = 0`, which would make
//! a flipped element a fixed point; there the turn is about the axis
//! `n_a × ŝ` (any axis across `n_a` flips it back), by the full angle `π`.

use glam::Vec3;

use super::lanes::{self, Chunk, Lane};
use super::{Particles, Recorder};
use crate::solver::{forced_rotation::ForcedRotation, topology::Pair};

/// Projects the normals of up to `F::N` edges of one
/// colour toward each other, side by side, with compliance `alpha_t`
/// (`α / Δt²`, for a square cell).
#[inline(always)]
pub(crate) fn project<F: Lane, R: Recorder>(
    p: &Particles,
    pairs: &F::Array<Pair>,
    mu: &mut F::Array<f32>,
    live: usize,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, b) = (
        Chunk::<F>::of(pairs, |c| c.a),
        Chunk::<F>::of(pairs, |c| c.b),
    );
    let (ba, bb) = (a.inv_inertia(p), b.inv_inertia(p));
    let w = ba + bb;
    let mut on = lanes::live::<F>(live) & !w.simd_le(0.0);
    if on.none() {
        return;
    }
    let (qa, qb) = (a.q(p), b.q(p));
    let (na, nb) = (qa.normal(), qb.normal());
    // `axis_angle`, lane by lane: the regular case in lanes, the rest alone.
    let axis = na.cross(nb);
    let sin = axis.length();
    let mut axis = axis * (F::ONE / sin);
    let mut angle = lanes::atan2(sin, na.dot(nb));
    let odd = on & !sin.simd_gt(1e-9);
    if odd.any() {
        let bits = odd.to_bitmask();
        for k in (0..F::N).filter(|k| bits & (1 << k) != 0) {
            let edge = p.x(b.at(k)) - p.x(a.at(k));
            match axis_angle(na.lane(k), nb.lane(k), edge) {
                Some((ax, an)) => {
                    axis.set_lane(k, ax);
                    angle.set(k, an);
                }
                None => on.set(k, 0.0),
            }
        }
    }
    let mut m = lanes::load::<F>(mu);
    let d = lanes::delta_mu(
        angle,
        w,
        F::splat(alpha_t) / lanes::field::<F, _>(pairs, |c| c.aspect),
        m,
    );
    // Gradients: −axis at a, +axis at b; the larger turn is Eq. 3's to shape.
    let d = lanes::forced(rot, angle, d, ba.max(bb), on);
    m = on.select(m + d, m);
    lanes::store(m, mu);
    a.turn(p, qa, axis * (-ba * d), on & ba.simd_gt(0.0), rec);
    b.turn(p, qb, axis * (bb * d), on & bb.simd_gt(0.0), rec);
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
