//! Angles without libm: the arctangent the kernels use, and the axis and
//! angle that turn one normal toward another.

use glam::Vec3;

use super::lanes::{self, Lane};

/// The unit axis that turns the normal `n` toward `target` (of any length)
/// and the angle between them, for normality and facing, which handle in
/// lanes the lanes where `|n × target| > tiny` and call this for the rest:
/// `None` when they agree (or `target` vanishes); exactly opposite, the
/// axis is `n × hint` (any axis across `n` where `hint` lies along it), by
/// the full angle `π`, so that a flipped element has a way back.
#[inline(always)]
pub(crate) fn axis_angle(n: Vec3, target: Vec3, hint: Vec3, tiny: f32) -> Option<(Vec3, f32)> {
    let axis = n.cross(target);
    let sin = axis.length();
    if sin > tiny {
        return Some((axis * sin.recip(), atan2(sin, n.dot(target))));
    }
    if n.dot(target) >= 0.0 {
        return None;
    }
    let across = n
        .cross(hint)
        .try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector());
    Some((across, std::f32::consts::PI))
}

/// [`axis_angle`] lane by lane: the regular case in lanes, the lanes of
/// `on` where `|n × target| ≤ tiny` alone, with `hint(k)` for lane `k`;
/// a lane whose normal already agrees is switched off in `on`.
#[inline(always)]
pub(crate) fn axis_angle_lanes<F: Lane>(
    n: lanes::V3<F>,
    target: lanes::V3<F>,
    tiny: f32,
    on: &mut F,
    hint: impl Fn(usize) -> Vec3,
) -> (lanes::V3<F>, F) {
    let axis = n.cross(target);
    let sin = axis.length();
    let mut axis = axis * (F::ONE / sin);
    let mut angle = lanes::atan2(sin, n.dot(target));
    let odd = *on & !sin.simd_gt(tiny);
    if odd.any() {
        let bits = odd.to_bitmask();
        for k in (0..F::N).filter(|k| bits & (1 << k) != 0) {
            match axis_angle(n.lane(k), target.lane(k), hint(k), tiny) {
                Some((ax, an)) => {
                    axis.set_lane(k, ax);
                    angle.set(k, an);
                }
                None => on.set(k, 0.0),
            }
        }
    }
    (axis, angle)
}

/// `atan2(y, x)`, without a libm call: [`atan`] of `y / x` with the
/// quadrant restored. Pure arithmetic, so the same on every machine. NaN in,
/// NaN out.
#[inline]
pub(crate) fn atan2(y: f32, x: f32) -> f32 {
    if x > 0.0 {
        return atan(y / x);
    }
    if x.is_nan() || y.is_nan() {
        return f32::NAN;
    }
    if x == 0.0 {
        return if y == 0.0 {
            0.0
        } else {
            std::f32::consts::FRAC_PI_2.copysign(y)
        };
    }
    // x < 0: the angle lies in the second or third quadrant.
    let a = std::f32::consts::PI - atan((y / x).abs());
    a.copysign(y)
}

/// `atan(t)`: the series `t − t³/3 + t⁵/5 − t⁷/7` for the small angles that
/// dominate (`|t| < 0.05`, error below 1e-10), and elsewhere a polynomial in
/// `t²` on `|t| ≤ 1` (least-squares fit, error below 2e-7 rad in `f32`),
/// evaluated by Estrin's scheme (half the dependent multiplications of
/// Horner's), with `atan(t) = π/2 − atan(1/t)` beyond. NaN in, NaN out.
#[inline]
pub(crate) fn atan(t: f32) -> f32 {
    let a = t.abs();
    if a < 0.05 {
        let t2 = square_above_subnormal(a);
        return t * (1.0 - t2 * (1.0 / 3.0 - t2 * (0.2 - t2 * (1.0 / 7.0))));
    }
    if a > 1.0 {
        return atan_steep(a).copysign(t);
    }
    atan_poly(a).copysign(t)
}

/// `t²` for the series of a small angle, from `max(|t|, 10⁻¹⁰)`: below
/// `10⁻⁴` the series' factor rounds to exactly 1 whatever `t²` is, so the
/// floor changes no result, and it keeps `t²` of a flat cloth's angles
/// (`10⁻²⁰` and less) from being subnormal (see `rotation::FOURTH_ORDER`).
#[inline(always)]
fn square_above_subnormal(a: f32) -> f32 {
    let a = a.max(SMALL_ANGLE_FLOOR);
    a * a
}

/// The floor of [`square_above_subnormal`].
pub(crate) const SMALL_ANGLE_FLOOR: f32 = 1e-10;

/// `atan(u)` for `0 ≤ u ≤ 1` by the fitted polynomial, in Estrin's scheme.
#[inline(always)]
fn atan_poly(u: f32) -> f32 {
    let z = u * u;
    let z2 = z * z;
    let c = &ATAN_POLY;
    let low = (c[0] + c[1] * z) + (c[2] + c[3] * z) * z2;
    let high = (c[4] + c[5] * z) + (c[6] + c[7] * z) * z2;
    u * (low + high * (z2 * z2))
}

/// `atan(a)` for `a > 1`, rare in the kernels: out of line, so that its
/// division is not computed ahead on the common path.
#[cold]
#[inline(never)]
fn atan_steep(a: f32) -> f32 {
    std::f32::consts::FRAC_PI_2 - atan_poly(a.recip())
}

/// `atan(t) / t` as a polynomial in `t²` on `[0, 1]`, lowest power first.
pub(crate) const ATAN_POLY: [f32; 8] = [
    0.999_999_34,
    -0.333_298_6,
    0.199_465_66,
    -0.139_086_28,
    0.096_421_905,
    -0.055_912_21,
    0.021_862_866,
    -0.004_054_539_4,
];

#[cfg(test)]
mod tests {
    use super::{atan, atan2};

    #[test]
    fn atan_and_atan2_match_the_standard_library() {
        let mut worst = 0.0f32;
        for i in -2000..=2000 {
            let t = i as f32 * 0.01 + 0.0031;
            worst = worst.max((atan(t) - t.atan()).abs());
            for j in -40..=40 {
                let (y, x) = (t, j as f32 * 0.25 + 0.001);
                worst = worst.max((atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 5e-7, "largest error {worst}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(1.0, 0.0), std::f32::consts::FRAC_PI_2);
        assert_eq!(atan2(-1.0, 0.0), -std::f32::consts::FRAC_PI_2);
        assert!((atan2(0.0, -1.0) - std::f32::consts::PI).abs() < 1e-6);
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
        assert!(atan(f32::NAN).is_nan());
    }
}
