//! Normality: the normals of neighbours agree (co-normality).
//!
//! The paper prints `δθ = λ (n_a × n_b)`: turn each normal about
//! `n_a × n_b` toward the other. The violation is the angle
//! `C = ∠(n_a, n_b)`; the full correction `λ C` is shared in proportion to the
//! inverse inertias, and each turn is shaped by Eq. 3. Positions do not move.
//! The violation reported is the angle, in radians.

use glam::Vec3;

use super::{Particles, Recorder, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Pair};

/// Projects one pair.
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    pair: Pair,
    weight: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let (ba, bb) = (p.inv_inertia[a], p.inv_inertia[b]);
    let total = ba + bb;
    if total <= 0.0 {
        return;
    }
    let (na, nb) = (normal_of(p.q(a)), normal_of(p.q(b)));
    let axis = na.cross(nb);
    let sin = axis.length();
    if sin <= 1e-9 {
        return;
    }
    let angle = super::atan2(sin, na.dot(nb));
    let axis = axis / sin;
    let full = weight * angle / total;
    if ba > 0.0 {
        turn(p, a, axis * (full * ba), rot, rec);
    }
    if bb > 0.0 {
        turn(p, b, axis * (-full * bb), rot, rec);
    }
}

/// The angle between the two normals, in radians.
#[inline]
pub fn violation(normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (na, nb) = (normal(pair.a as usize), normal(pair.b as usize));
    na.cross(nb).length().atan2(na.dot(nb))
}
