//! The adjust phase's geometric constraints (§3.3), one module per family.
//!
//! Every family is a scalar violation `C` of a pair of particles whose
//! gradient reproduces the vectors printed in the paper:
//!
//! | family | violation `C` | gradient in position | gradient in rotation |
//! |---|---|---|---|
//! | stretch | `|s| − L` | `∓ ŝ` | — |
//! | planarity | `n_a · s` | `∓ n_a` | `n_a × s` (the paper's `v`) |
//! | normality | `∠(n_a, n_b)` | — | `n_a × n_b` |
//! | curvature | sagitta `n̂ · (x_m − ½(x_a + x_b))`, bend angle | `n̂`, `−½ n̂` | `(n_a + n_b) × s` |
//!
//! with `s = x_b − x_a` and `n̂` the normalised `n_a + n_b`. A projection changes positions and orientations as
//! little as possible in the metric of mass and inertia (§3.4): with inverse
//! masses `w`, inverse inertias `β` and gradients `g`, the multiplier is
//! `Δ = −λ C / Σ (w|g_x|² + β|g_θ|²)`, each particle moves by `w g_x Δ` and
//! turns by `β g_θ Δ`, the turn shaped by Eq. 3 ([`ForcedRotation`]).

pub mod curvature;
pub mod normality;
pub mod planarity;
pub mod stretch;

use glam::{Quat, Vec3};

use super::{cloth::rotate, forced_rotation::ForcedRotation};

/// Mutable views of what a projection reads and writes.
pub(crate) struct Particles<'a> {
    pub x: &'a mut [Vec3],
    pub q: &'a mut [Quat],
    pub inv_mass: &'a [f32],
    pub inv_inertia: &'a [f32],
}

/// Receives the corrections a projection applies (for diagnostics).
pub(crate) trait Recorder {
    /// Whether anything is recorded; lets the compiler drop the calls.
    const ON: bool;
    fn moved(&mut self, i: usize, dx: Vec3);
    fn turned(&mut self, i: usize, axis_angle: Vec3);
}

/// The recorder used when diagnostics are off: records nothing.
pub(crate) struct NoRecord;

impl Recorder for NoRecord {
    const ON: bool = false;
    #[inline(always)]
    fn moved(&mut self, _: usize, _: Vec3) {}
    #[inline(always)]
    fn turned(&mut self, _: usize, _: Vec3) {}
}

/// Turns particle `i` by the forced rotation for the requested rotation
/// vector `omega` (axis × full angle).
#[inline]
pub(crate) fn turn<R: Recorder>(
    p: &mut Particles,
    i: usize,
    omega: Vec3,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let full = omega.length();
    // Written so that NaN also returns: a non-finite state is reported by
    // the step, never turned into a panic here.
    if !(full > 1e-12) {
        return;
    }
    let angle = rot.angle(full);
    if !(angle > 0.0) {
        return;
    }
    let axis = omega / full;
    p.q[i] = rotate(p.q[i], axis * angle);
    if R::ON {
        rec.turned(i, axis * angle);
    }
}

/// Moves particle `i` by `dx`.
#[inline]
pub(crate) fn shift<R: Recorder>(p: &mut Particles, i: usize, dx: Vec3, rec: &mut R) {
    p.x[i] += dx;
    if R::ON {
        rec.moved(i, dx);
    }
}
