//! A pull: one particle drawn towards a point by a spring, as a hand
//! grabbing the cloth would (the debugger's Ctrl-drag).
//!
//! A [`Pull`] names a particle, a **target** in world coordinates and a
//! stiffness `k` (N/m). The solver measures positions from a floating
//! origin ([`super::frame`]), so the target is kept in `f64` world
//! coordinates and brought into the solver's frame at every substep, from
//! the origin at that substep's end: a pull holds its point in the world
//! while the carrier moves the origin under it.
//!
//! The spring is a soft constraint `C(x) = |x − t|` projected once a
//! substep, right after the update and before the constraint families, in
//! the manner of XPBD with compliance `α = 1/k` and a multiplier that
//! starts from zero each substep:
//!
//! ```text
//! Δx = (t − x) · k h² / (m + k h²)
//! ```
//!
//! (`h` the substep, `m` the particle's mass). For a soft spring
//! (`k h² ≪ m`) that is the displacement the force `k (t − x)` gives in one
//! substep; for a stiff one it tends to moving the particle onto the
//! target, never past it, so no stiffness makes the step unstable. The
//! families then pull the rest of the cloth after it. A particle held by
//! an attachment (no inverse mass) does not move. The arithmetic is the
//! same `f32` operations in the same order every time: a pull replays bit
//! for bit.
//!
//! ```
//! use glam::{DVec3, Vec3};
//! use weft_cloth::solver::pull::Pull;
//!
//! let pull = Pull { particle: 0, target: DVec3::new(1.0, 0.0, 0.0), stiffness: 1e9 };
//! let mut x = [Vec3::ZERO];
//! pull.apply(&mut x, &[1e-3], &[1e3], DVec3::ZERO, 1.0 / 480.0);
//! // A stiff spring moves the particle almost onto its target.
//! assert!((x[0].x - 1.0).abs() < 1e-3);
//! ```

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::range::{Range, RangeError};

/// How far from the world's origin a target may be, per component (m).
const TARGET: Range = Range::components(1e7).unit(" m");
/// The spring's stiffness (N/m).
const STIFFNESS: Range = Range::above(0.0, 1e9).unit(" N/m");

/// One particle pulled towards a point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pull {
    /// The particle's index in the cloth.
    pub particle: usize,
    /// Where it is pulled to, in world coordinates (m).
    pub target: DVec3,
    /// The spring's stiffness `k` (N/m).
    pub stiffness: f32,
}

impl Pull {
    /// Checks the pull against a cloth of `particles` particles; the first
    /// problem, under its key (`pull.particle`, `pull.target`,
    /// `pull.stiffness`).
    pub fn validate(&self, particles: usize) -> Result<(), RangeError> {
        let last = particles.saturating_sub(1) as f32;
        let index = u32::try_from(self.particle).unwrap_or(u32::MAX);
        Range::new(0.0, last).check_count("pull.particle", index)?;
        TARGET.check_each("pull.target", &self.target.as_vec3().to_array())?;
        STIFFNESS.check("pull.stiffness", self.stiffness)
    }

    /// Moves the pulled particle of `position` (measured from `origin`, in
    /// world coordinates) towards the target by one substep of `h`
    /// seconds' spring (see the module's docs). `mass` and `inv_mass` are
    /// per particle; with no inverse mass nothing moves.
    pub fn apply(
        &self,
        position: &mut [Vec3],
        mass: &[f32],
        inv_mass: &[f32],
        origin: DVec3,
        h: f32,
    ) {
        let i = self.particle;
        if inv_mass[i] == 0.0 {
            return;
        }
        let target = (self.target - origin).as_vec3();
        let a = self.stiffness * h * h;
        let share = a / (mass[i] + a);
        position[i] += (target - position[i]) * share;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pull_is_checked_against_the_cloth() {
        let pull = Pull {
            particle: 3,
            target: DVec3::new(1.0, 2.0, 3.0),
            stiffness: 10.0,
        };
        assert!(pull.validate(4).is_ok());
        assert_eq!(pull.validate(3).unwrap_err().key, "pull.particle");
        let far = Pull {
            target: DVec3::new(0.0, f64::NAN, 0.0),
            ..pull
        };
        assert!(far.validate(4).unwrap_err().not_finite);
        let slack = Pull {
            stiffness: 0.0,
            ..pull
        };
        assert_eq!(slack.validate(4).unwrap_err().key, "pull.stiffness");
    }

    #[test]
    fn the_target_is_measured_from_the_origin() {
        // The same pull 10 km out, the origin there: the same motion.
        let origin = DVec3::new(1e4, -2e4, 5.0);
        let near = Pull {
            particle: 0,
            target: DVec3::new(0.5, 0.0, 0.25),
            stiffness: 50.0,
        };
        let far = Pull {
            target: near.target + origin,
            ..near
        };
        let (mut a, mut b) = ([Vec3::ZERO], [Vec3::ZERO]);
        near.apply(&mut a, &[1e-3], &[1e3], DVec3::ZERO, 1.0 / 480.0);
        far.apply(&mut b, &[1e-3], &[1e3], origin, 1.0 / 480.0);
        assert_eq!(a, b);
        assert!(a[0].x > 0.0 && a[0].z > 0.0, "{a:?}");
    }

    #[test]
    fn a_held_particle_does_not_move() {
        let pull = Pull {
            particle: 0,
            target: DVec3::ONE,
            stiffness: 1e6,
        };
        let mut x = [Vec3::ZERO];
        pull.apply(&mut x, &[1e-3], &[0.0], DVec3::ZERO, 1.0 / 480.0);
        assert_eq!(x[0], Vec3::ZERO);
    }
}
