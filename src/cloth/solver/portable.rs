//! The transcendental functions the simulation uses, with the same bits on
//! every machine.
//!
//! `f32::sin`, `f32::atan2`, `f32::powf` and the like call the platform's C
//! math library, and those differ in the last bit between libraries and
//! between versions of one (glibc itself has replaced several of its
//! single-precision functions between releases). A run on one machine would
//! then not replay bit
//! for bit on another: a recording made on a developer's machine would fail
//! `weft replay` in CI.
//!
//! So whatever feeds a step (the update, the bodies' motion, the wind, the
//! cloth's placement) computes its sines, arctangents and powers here, with
//! the `libm` crate: musl's algorithms written in Rust, in IEEE arithmetic
//! alone. glam's rotations about an axis and its Euler angles call the
//! platform's sine too, so this module builds them as well. The kernels use
//! weft's own `atan` (`kernels::lanes::math`) and Eq. 3's
//! [`exp`](super::forced_rotation), for speed, which are portable in the same
//! way. `clippy.toml` disallows the platform's versions, so a new call to
//! one fails `cargo clippy`.
//!
//! ```
//! use weft_cloth::solver::portable;
//!
//! let q = portable::rotation_z(std::f32::consts::FRAC_PI_2);
//! assert!((q * glam::Vec3::X).abs_diff_eq(glam::Vec3::Y, 1e-6));
//! ```

use glam::Quat;

/// `sin(x)`.
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// `cos(x)`.
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// `(sin(x), cos(x))`.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    libm::sincosf(x)
}

/// `atan2(y, x)`, in `[-π, π]`.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// `x^y`.
#[inline]
pub fn powf(x: f32, y: f32) -> f32 {
    libm::powf(x, y)
}

/// `√(x² + y²)`, without overflow or underflow on the way.
#[inline]
pub fn hypot(x: f32, y: f32) -> f32 {
    libm::hypotf(x, y)
}

/// The rotation by `angle` radians about X (as glam's `Quat::from_rotation_x`).
#[inline]
pub fn rotation_x(angle: f32) -> Quat {
    let (s, c) = sin_cos(0.5 * angle);
    Quat::from_xyzw(s, 0.0, 0.0, c)
}

/// The rotation by `angle` radians about Y (as glam's `Quat::from_rotation_y`).
#[inline]
pub fn rotation_y(angle: f32) -> Quat {
    let (s, c) = sin_cos(0.5 * angle);
    Quat::from_xyzw(0.0, s, 0.0, c)
}

/// The rotation by `angle` radians about Z (as glam's `Quat::from_rotation_z`).
#[inline]
pub fn rotation_z(angle: f32) -> Quat {
    let (s, c) = sin_cos(0.5 * angle);
    Quat::from_xyzw(0.0, 0.0, s, c)
}

/// The rotation of XYZ Euler angles in radians, as glam's
/// `Quat::from_euler(EulerRot::XYZ, x, y, z)`: about X by `x`, then about
/// the turned Y by `y`, then about the twice-turned Z by `z`.
pub fn euler_xyz(x: f32, y: f32, z: f32) -> Quat {
    rotation_x(x) * rotation_y(y) * rotation_z(z)
}

#[cfg(test)]
mod tests {

    use super::*;
    use glam::{EulerRot, Vec3};

    #[test]
    fn functions_agree_with_the_platforms_to_rounding() {
        for k in -200..=200 {
            let x = k as f32 * 0.0731;
            assert!((sin(x) - x.sin()).abs() <= 2e-7, "sin {x}");
            assert!((cos(x) - x.cos()).abs() <= 2e-7, "cos {x}");
            assert_eq!(sin_cos(x), (sin(x), cos(x)), "sin_cos {x}");
            for y in [-3.0f32, -0.2, 0.0, 1e-6, 0.7, 5.0] {
                let a = atan2(x, y);
                assert!((a - x.atan2(y)).abs() <= 3e-7, "atan2 {x} {y}");
                assert!(
                    (hypot(x, y) - x.hypot(y)).abs() <= 1e-6 * x.hypot(y),
                    "hypot"
                );
            }
            let base = 0.5 + (k + 200) as f32 * 1.2e-3;
            let p = powf(base, 1.0 / 8.0);
            assert!((p - base.powf(1.0 / 8.0)).abs() <= 1.2e-7, "powf {base}");
        }
    }

    #[test]
    fn rotations_are_glams() {
        for k in -20..=20 {
            let a = k as f32 * 0.31;
            let close = |p: Quat, q: Quat| p.abs_diff_eq(q, 1e-6) || p.abs_diff_eq(-q, 1e-6);
            assert!(close(rotation_x(a), Quat::from_rotation_x(a)), "x {a}");
            assert!(close(rotation_y(a), Quat::from_rotation_y(a)), "y {a}");
            assert!(close(rotation_z(a), Quat::from_rotation_z(a)), "z {a}");
            let (x, y, z) = (a, 0.7 - 0.4 * a, 1.9 * a - 0.3);
            let (ours, glams) = (euler_xyz(x, y, z), Quat::from_euler(EulerRot::XYZ, x, y, z));
            assert!(close(ours, glams), "euler {x} {y} {z}: {ours:?} {glams:?}");
            let v = Vec3::new(0.3, -1.2, 0.8);
            assert!((ours * v).abs_diff_eq(glams * v, 1e-5));
        }
    }
}
