//! The floating origin: where the solver's coordinates are measured from.
//!
//! Positions are `f32`. Measured from the world's origin, a cloth 1 km out
//! is stored to 60 µm and one 20 km out to 2 mm, and every sum the solver
//! forms rounds at that scale: the same flag moves differently at different
//! places. So the solver measures every position (particles, bodies,
//! colliders) from an **origin** `O` kept in `f64`, which the scene moves
//! with whatever carries the cloth (docs/method.md, "The frame of
//! reference"). A particle's world position is `x_w = O + x`.
//!
//! Over a step the origin moves from `O₀` to `O₁`, by `D = (O₁ − O₀) / s`
//! in each of the `s` substeps. A particle's stored previous position is
//! measured from the origin of its own time, so `x − x_prev` is its motion
//! relative to the origin, and its world motion is `x − x_prev + D_prev`
//! (`D_prev` the origin's motion over the substep before). The update of
//! §3.2 in world coordinates,
//!
//! ```text
//! x_w(t+Δt) = x_w + r_w + k (x_w − x_w,prev − r_w) + a Δt²
//! ```
//!
//! (`r_w` the carrier's motion, which moves with the origin as every body's
//! does: `r_w = r + D_prev`), measured from the origin at `t + Δt`, is
//!
//! ```text
//! x(t+Δt) = x + r + k (x − x_prev − r) + a Δt² + (D_prev − D)
//! ```
//!
//! the same update plus the **frame's kick** `D_prev − D = −a_O Δt²`, the
//! fictitious force of an accelerating frame. Only air drag sees world
//! velocity, `(x − x_prev + D_prev) / Δt`. Everything else the solver does
//! compares positions of one time, or differences of positions each
//! measured from its own time's origin, and is unchanged.
//!
//! `D` is one value for all the substeps of a step, so only a step's first
//! substep can be kicked. A carrier at constant velocity moves the origin
//! by the same `D` every step up to the rounding of `f64` sums (10⁻¹² m at
//! 20 km); a kick below [`KICK_FLOOR`] is that rounding, not motion, and is
//! dropped. So a cloth on a carrier at constant velocity, anywhere, is
//! computed with exactly the arithmetic of the same cloth on a carrier at
//! rest at the world's origin, bit for bit.

use glam::{DVec3, Vec3};

/// A kick (metres per substep, squared in time) below which the origin's
/// motion is taken as constant: 10⁻⁹ m is an acceleration of 2·10⁻⁴ m/s² at
/// 480 substeps a second, a thousand times the rounding of an `f64` origin
/// 20 km out.
pub const KICK_FLOOR: f64 = 1e-9;

/// The origin and how it moved in the last step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// Where the solver's coordinates are measured from, in world
    /// coordinates.
    pub origin: DVec3,
    /// How far the origin moved in each substep of the last step.
    pub shift: DVec3,
}

/// How the origin moves in one step, as the update needs it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct FrameStep {
    /// The origin's motion in each substep of this step.
    pub shift: DVec3,
    /// Its motion in each substep of the step before.
    pub before: DVec3,
    /// The origin at the step's start.
    pub from: DVec3,
}

impl FrameStep {
    /// The origin after `k` of the step's substeps.
    pub fn origin_after(&self, k: u32) -> DVec3 {
        self.from + self.shift * k as f64
    }

    /// The frame's kick on substep `sub`: `D_prev − D` on the first, zero
    /// after it; below [`KICK_FLOOR`], zero.
    pub fn kick(&self, sub: u32) -> Vec3 {
        let kick = self.before - self.shift;
        if sub > 0 || kick.abs().max_element() < KICK_FLOOR {
            Vec3::ZERO
        } else {
            kick.as_vec3()
        }
    }

    /// The origin's motion over the substep before substep `sub` (what air
    /// drag adds to a particle's motion to see its world velocity).
    pub fn before(&self, sub: u32) -> Vec3 {
        if sub == 0 { self.before } else { self.shift }.as_vec3()
    }
}

impl Frame {
    /// The step that moves the origin to `to` in `substeps` substeps. The
    /// first step of a run takes the origin's motion as already under way
    /// (a cloth starts moving with its carrier).
    pub(crate) fn step_to(&self, to: DVec3, substeps: u32, first: bool) -> FrameStep {
        let shift = (to - self.origin) / substeps as f64;
        FrameStep {
            shift,
            before: if first { shift } else { self.shift },
            from: self.origin,
        }
    }

    /// The frame after `step`, at `to`.
    pub(crate) fn after(step: &FrameStep, to: DVec3) -> Self {
        Self {
            origin: to,
            shift: step.shift,
        }
    }

    /// A point given in world coordinates, measured from the origin.
    pub fn local(&self, world: DVec3) -> Vec3 {
        (world - self.origin).as_vec3()
    }

    /// A point measured from the origin, in world coordinates.
    pub fn world(&self, local: Vec3) -> DVec3 {
        self.origin + local.as_dvec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_motion_kicks_nothing_anywhere() {
        for start in [0.0, 1e3, 2e4] {
            let mut frame = Frame {
                origin: DVec3::new(start, 0.3, 1.2),
                ..Frame::default()
            };
            for n in 0..2000u32 {
                let to = DVec3::new(start + 14.0 * (n + 1) as f64 / 60.0, 0.3, 1.2);
                let step = frame.step_to(to, 8, n == 0);
                assert_eq!(step.kick(0), Vec3::ZERO, "start {start}, step {n}");
                frame = Frame::after(&step, to);
            }
        }
    }

    #[test]
    fn braking_kicks_forward_by_the_change_of_motion() {
        let frame = Frame {
            origin: DVec3::ZERO,
            shift: DVec3::new(0.01, 0.0, 0.0),
        };
        let step = frame.step_to(DVec3::new(0.04, 0.0, 0.0), 8, false);
        let kick = step.kick(0);
        assert!((kick.x - 0.005).abs() < 1e-9, "{kick}");
        assert_eq!(step.kick(1), Vec3::ZERO);
    }
}
