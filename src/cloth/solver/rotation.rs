//! Rotation maths of the oriented particles: a particle's normal from its
//! orientation, and turning an orientation by a rotation vector (axis ×
//! angle) exactly, by a half-angle series for the small turns that are by
//! far the most common. A leaf: the cloth, the update phase and the SIMD
//! kernels all turn particles with these, and it uses nothing of theirs.

use glam::{Quat, Vec3};

/// The local +Z axis of a unit quaternion, without a full rotation.
#[inline]
pub fn normal_of(q: Quat) -> Vec3 {
    Vec3::new(
        2.0 * (q.x * q.z + q.w * q.y),
        2.0 * (q.y * q.z - q.w * q.x),
        1.0 - 2.0 * (q.x * q.x + q.y * q.y),
    )
}

/// Rotates `q` by the rotation vector `r` (axis × angle), exactly, and
/// renormalises.
///
/// A non-finite `r` gives a non-finite quaternion (never a panic), for the
/// step to report.
#[inline]
pub fn rotate(q: Quat, r: Vec3) -> Quat {
    turn_by(q, r).normalize()
}

/// Rotates `q` by the rotation vector `r` without renormalising: the turn
/// `(cos ½θ, sin ½θ · axis)` is a unit quaternion to rounding, so the result
/// keeps `q`'s length to about 1e-7.
///
/// Small angles, by far the most common, use the half-angle series of
/// `(cos ½θ, sin ½θ · axis)` to fourth order (error below 1e-9 for
/// θ < 0.05), avoiding the trigonometric calls.
#[inline]
pub fn turn_by(q: Quat, r: Vec3) -> Quat {
    let t2 = angle_squared(r);
    let d = if t2 < 0.0025 {
        // cos(θ/2) ≈ 1 − θ²/8 + θ⁴/384,  sin(θ/2)/θ ≈ ½ − θ²/48 + θ⁴/3840
        // (Multiplied by the reciprocals: a division by a constant that is
        // not a power of two stays a division.)
        let (mut c, mut s) = (1.0 - t2 * (1.0 / 8.0), 0.5 - t2 * (1.0 / 48.0));
        if t2 >= FOURTH_ORDER {
            let t4 = t2 * t2;
            (c, s) = (c + t4 * (1.0 / 384.0), s + t4 * (1.0 / 3840.0));
        }
        Quat::from_xyzw(r.x * s, r.y * s, r.z * s, c)
    } else if t2.is_finite() {
        let t = t2.sqrt();
        let (s, c) = super::portable::sin_cos(0.5 * t);
        let r = r * (s / t);
        Quat::from_xyzw(r.x, r.y, r.z, c)
    } else {
        return Quat::from_xyzw(f32::NAN, f32::NAN, f32::NAN, f32::NAN);
    };
    d * q
}

/// `θ² = |r|²` for [`turn_by`], leaving out the components under
/// [`NEGLIGIBLE_TURN`]: their squares (under `10⁻³⁰`) would be subnormal for
/// the tiny turns of a cloth at rest, and leaving them out changes no
/// result. Where `θ²` is under `10⁻⁸` the series' factors round to exactly 1
/// and ½ whatever its value; above, the left-out squares are far under
/// half a unit in its last place and the sum rounds the same.
#[inline(always)]
pub(crate) fn angle_squared(r: Vec3) -> f32 {
    let kept = |v: f32| if v.abs() < NEGLIGIBLE_TURN { 0.0 } else { v };
    Vec3::new(kept(r.x), kept(r.y), kept(r.z)).length_squared()
}

/// A component of a turn's rotation vector under this is left out of `θ²`
/// ([`angle_squared`]).
pub(crate) const NEGLIGIBLE_TURN: f32 = 1e-15;

/// The smallest `θ²` whose fourth-order terms in [`turn_by`]'s series
/// change a result: below it `θ⁴/384 < 3·10⁻¹¹`, far under half a unit in
/// the last place of `cos ½θ ≈ 1` (`3·10⁻⁸`) and of `sin ½θ / θ ≈ ½`
/// (`1.5·10⁻⁸`), so adding them rounds back to the second-order values, bit
/// for bit. Leaving them out there is not for accuracy but for speed: for
/// the tiny turns of a cloth at rest (`θ` below about `10⁻⁹`) `θ⁴` is
/// subnormal, and on many x86 cores every operation that makes or reads a
/// subnormal takes a microcode assist of about a hundred cycles.
pub(crate) const FOURTH_ORDER: f32 = 1e-4;
