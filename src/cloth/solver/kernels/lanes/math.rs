//! The arctangent, Eq. 3's forced rotation and its exponential, and the
//! multiplier change, in every lane: weft's own arithmetic, operation for
//! operation as the scalar code, so that a lane gives the scalar bits.

use super::Lane;
use crate::solver::forced_rotation::ForcedRotation;
use crate::solver::kernels::angles::{self, ATAN_POLY, SMALL_ANGLE_FLOOR};

/// [`atan`](crate::solver::angles::atan) in every lane.
#[inline(always)]
pub(crate) fn atan<F: Lane>(t: F) -> F {
    let a = t.abs();
    // As the scalar `square_above_subnormal`.
    let floor = a.max(F::splat(SMALL_ANGLE_FLOOR));
    let t2 = floor * floor;
    let small =
        t * (F::ONE - t2 * (F::splat(1.0 / 3.0) - t2 * (F::splat(0.2) - t2 * F::splat(1.0 / 7.0))));
    let is_small = a.simd_lt(0.05);
    // A nearly flat cloth: every lane's angle is small (the common case).
    if is_small.all() {
        return small;
    }
    // The small lanes keep `small` and run the polynomial on ½ instead: the
    // powers of their tiny `a` would be subnormal numbers (the sheet lying
    // flat beside a fold), about a hundred cycles each on many x86 cores.
    let a = is_small.select(F::splat(0.5), a);
    // Beyond 1, `π/2 − atan(1/a)`: one polynomial serves both ranges (the
    // division only where a lane needs it).
    let steep = a.simd_gt(1.0);
    let u = if steep.any() {
        steep.select(F::ONE / a, a)
    } else {
        a
    };
    let z = u * u;
    let z2 = z * z;
    let c = ATAN_POLY.map(F::splat);
    let low = (c[0] + c[1] * z) + (c[2] + c[3] * z) * z2;
    let high = (c[4] + c[5] * z) + (c[6] + c[7] * z) * z2;
    let poly = u * (low + high * (z2 * z2));
    let wide = steep.select(F::FRAC_PI_2 - poly, poly).copysign(t);
    is_small.select(small, wide)
}

/// [`atan2`](crate::solver::angles::atan2) in every lane: in lanes for `x ≠ 0`, alone for
/// the rest (`x = 0` or NaN).
#[inline(always)]
pub(crate) fn atan2<F: Lane>(y: F, x: F) -> F {
    let r = y / x;
    let right = x.simd_gt(0.0);
    let angle = atan(right.select(r, r.abs()));
    let mut out = right.select(angle, (F::PI - angle).copysign(y));
    let odd = !(right | x.simd_lt(0.0));
    if odd.any() {
        let bits = odd.to_bitmask();
        for k in (0..F::N).filter(|k| bits & (1 << k) != 0) {
            out.set(k, angles::atan2(y.at(k), x.at(k)));
        }
    }
    out
}

/// [`delta_mu`](crate::solver::kernels::delta_mu) in every lane.
#[inline(always)]
pub(crate) fn delta_mu<F: Lane>(c: F, w: F, alpha_t: F, mu: F) -> F {
    (-c - alpha_t * mu) / (w + alpha_t)
}

/// [`ForcedRotation::scale`] in every lane, case by case as the scalar
/// code (`limit`, then the fraction).
#[inline(always)]
pub(crate) fn scale<F: Lane>(rot: &ForcedRotation, violation: F, full: F) -> F {
    let (phi, h) = (F::splat(rot.phi), F::splat(rot.h));
    // As the scalar test, the product left out under `h` (a zero factor,
    // so that it is never subnormal).
    let below = if rot.phi > 0.0 {
        violation.simd_lt(h)
    } else {
        F::ZERO
    };
    let product = full * below.select(F::ZERO, violation);
    // Nothing asked (or NaN), or the envelope's lower bound lets it all
    // through: the common case.
    let whole = !full.simd_gt(0.0)
        | (violation.simd_gt(0.0) & !below & product.simd_le(phi * (violation - h)));
    if whole.all() {
        return F::ONE;
    }
    let ratio = h / violation;
    // Lanes past 80 take 0 below; capping their ratio keeps exp_neg from
    // making subnormals that are thrown away.
    let envelope = ratio
        .simd_le(0.0)
        .select(phi, phi * exp_neg(ratio.min(F::splat(80.0))));
    let mut angle = ratio.simd_ge(80.0).select(F::ZERO, full.min(envelope));
    // No violation (or NaN): the envelope is closed (h > 0) or Φ (h = 0).
    let closed = if rot.h > 0.0 { F::ZERO } else { full.min(phi) };
    angle = violation.simd_gt(0.0).select(angle, closed);
    let fraction = angle.simd_ge(full).select(F::ONE, angle / full);
    whole.select(F::ONE, fraction)
}

/// A chunk's multiplier changes `d` shaped by Eq. 3 ([`scale`]) for
/// constraints violated by `violation` whose largest turn is `beta · |d|`,
/// in the lanes of `on`; a change under [`NEGLIGIBLE_CHANGE`] (or a cut to
/// under `NEGLIGIBLE_CHANGE` of the change asked) is dropped.
///
/// Eq. 3 lets through only `exp(−h / violation)` of the turn asked for a
/// violation far under `h`: for the tiny violations of a cloth at rest that
/// is `10⁻³⁰` of it and less, so the change, the multiplier, the moves and
/// the turns that follow would all be subnormal numbers (about a hundred
/// cycles each on many x86 cores, see `rotation::FOURTH_ORDER`) for moves far
/// under what an `f32` position can hold. Dropping them changes results
/// only in those bits (`docs/method.md`, "No subnormal numbers where Eq. 3
/// closes").
#[inline(always)]
pub(crate) fn forced<F: Lane>(rot: &ForcedRotation, violation: F, d: F, beta: F, on: F) -> F {
    let cut = F::splat(NEGLIGIBLE_CHANGE);
    let fraction = scale(rot, violation, on.select(beta * d.abs(), F::ZERO));
    let d = d * fraction.simd_lt(cut).select(F::ZERO, fraction);
    d.abs().simd_lt(cut).select(F::ZERO, d)
}

/// The smallest multiplier change (radians, for the turning families) that
/// [`forced`] keeps.
pub(crate) const NEGLIGIBLE_CHANGE: f32 = 1e-20;

/// [`exp_neg`](crate::solver::forced_rotation::exp_neg) in every lane,
/// operation for operation.
#[inline(always)]
pub(crate) fn exp_neg<F: Lane>(r: F) -> F {
    use crate::solver::forced_rotation::{
        EXP_LN2_HI, EXP_LN2_LO, EXP_SHIFTER, EXP_SHIFTER_BITS, exp_poly,
    };
    let shifter = F::splat(EXP_SHIFTER);
    let t = -r * F::splat(std::f32::consts::LOG2_E) + shifter;
    let k = t - shifter;
    let f = (-r - k * F::splat(EXP_LN2_HI)) - k * F::splat(EXP_LN2_LO);
    let two_k = t.pow2(EXP_SHIFTER_BITS - 127);
    exp_poly(f, F::splat) * two_k
}

/// `f32::clamp(v, -1, 1)` in every lane (NaN stays NaN).
#[inline(always)]
pub(crate) fn clamp_unit<F: Lane>(v: F) -> F {
    let v = v.simd_lt(-1.0).select(F::splat(-1.0), v);
    v.simd_gt(1.0).select(F::ONE, v)
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};

    use super::super::turn_by;
    use super::super::{LANES, Q4, V3, each, live};
    use super::*;
    use wide::f32x8 as F;

    #[test]
    fn forced_drops_negligible_changes_and_keeps_the_rest() {
        let rot = ForcedRotation { phi: 0.7, h: 1e-4 };
        let on = live(LANES);
        // Violations far under h: Eq. 3 leaves less than 1e-20 of the
        // change, which is dropped; well above h the change goes through.
        let tiny = forced(&rot, F::splat(1e-7), F::splat(1e-3), F::ONE, on);
        assert_eq!(tiny.to_array(), [0.0; LANES]);
        let whole = forced(&rot, F::splat(0.5), F::splat(1e-3), F::ONE, on);
        assert_eq!(whole.to_array(), [1e-3; LANES]);
        // A change already under the floor is dropped whatever Eq. 3 says.
        let small = forced(&rot, F::splat(0.5), F::splat(1e-25), F::ONE, on);
        assert_eq!(small.to_array(), [0.0; LANES]);
        // Nothing in the result is subnormal, across violations and changes.
        for i in 0..400 {
            let v = 10f32.powf(-12.0 + i as f32 * 0.03);
            for d in [1e-3f32, 1e-9, -1e-15, 3e-19] {
                let out = forced(&rot, F::splat(v), F::splat(d), F::splat(50.0), on);
                assert!(out.to_array().iter().all(|x| !x.is_subnormal()), "{v} {d}");
            }
        }
    }

    #[test]
    fn lanes_match_the_scalar_functions_bit_for_bit() {
        let rot = ForcedRotation { phi: 0.7, h: 1e-4 };
        for i in 0..2000 {
            let t = (i as f32 - 1000.0) * 0.0037 + 1e-4;
            // Small, moderate and steep arguments; every quadrant; Eq. 3
            // letting a turn through, cutting it, and nothing asked.
            let ts = each(|k| t * [1.0, -1.0, 0.01, 40.0][k % 4] + k as f32 * 1e-3);
            let (y, x) = (
                each(|k| [t, t, -t, 0.3][k % 4]),
                each(|k| [1.0, -0.5, 0.0, t][k % 4]),
            );
            let full = each(|k| [0.1, 2.0, 0.0, t.abs()][k % 4]);
            let a = atan(F::new(ts)).to_array();
            let b = atan2(F::new(y), F::new(x)).to_array();
            let s = scale(&rot, F::new(ts.map(f32::abs)), F::new(full)).to_array();
            for k in 0..LANES {
                assert_eq!(a[k].to_bits(), angles::atan(ts[k]).to_bits());
                assert_eq!(b[k].to_bits(), angles::atan2(y[k], x[k]).to_bits());
                assert_eq!(s[k].to_bits(), rot.scale(ts[k].abs(), full[k]).to_bits());
            }
        }
        // A flat sheet beside a fold: tiny angles (whose powers would be
        // subnormal) in the lanes beside wide and steep ones.
        for wide in [0.07, -0.6, 3.0, 1e4] {
            let ts = each(|k| [1e-30, wide, -1e-20, 1e-40, 0.0, -0.0, 2e-13, wide][k % 8]);
            let a = atan(F::new(ts)).to_array();
            for k in 0..LANES {
                assert_eq!(a[k].to_bits(), angles::atan(ts[k]).to_bits());
            }
        }
        let q = Quat::from_xyzw(0.3, -0.2, 0.5, 0.7).normalize();
        let r = Vec3::new(0.01, -0.02, 0.015);
        let q4 = Q4 {
            x: F::splat(q.x),
            y: F::splat(q.y),
            z: F::splat(q.z),
            w: F::splat(q.w),
        };
        let r4 = V3 {
            x: F::splat(r.x),
            y: F::splat(r.y),
            z: F::splat(r.z),
        };
        let (t, ok) = turn_by(q4, r4);
        assert!(ok.all());
        let want = crate::solver::rotation::turn_by(q, r);
        assert_eq!(
            t.lane(2).to_array().map(f32::to_bits),
            want.to_array().map(f32::to_bits)
        );
        let n = crate::solver::rotation::normal_of(q);
        assert_eq!(
            q4.normal().lane(1).to_array().map(f32::to_bits),
            n.to_array().map(f32::to_bits)
        );
    }

    #[test]
    fn exp_and_eq3_in_lanes_match_the_scalar_code_and_the_standard_library() {
        use crate::solver::forced_rotation::exp_neg as scalar_exp_neg;
        let mut worst = 0.0f64;
        let n = 20_000;
        for i in 0..n {
            let r = each(|k| (i * LANES + k) as f32 * 87.0 / (n * LANES) as f32);
            let e = exp_neg(F::new(r)).to_array();
            for k in 0..LANES {
                assert_eq!(
                    e[k].to_bits(),
                    scalar_exp_neg(r[k]).to_bits(),
                    "exp(-{})",
                    r[k]
                );
                let want = (-f64::from(r[k])).exp();
                worst = worst.max(((f64::from(e[k]) - want) / want).abs());
            }
        }
        assert!(worst < 2.5e-7, "largest relative error {worst}");
        let rots = [(0.7, 1e-4), (0.7, 0.0), (3.0, 0.05), (0.0, 1e-4)];
        for (phi, h) in rots {
            let rot = ForcedRotation { phi, h };
            for i in 0..1000 {
                // Violations from 1e-8 to 1e2 rad; turns asked of every
                // size; and no violation, a negative one, NaN, nothing asked.
                let v = each(|k| 10f32.powf(-8.0 + (i * LANES + k) as f32 * 1.25e-3));
                let v = each(|k| [v[k], v[k], v[k], [0.0, -1.0, f32::NAN, v[k]][i % 4]][k % 4]);
                let full = each(|k| v[k].abs() * [1.0, 0.3, 30.0, 1.0][k % 4]);
                let full = each(|k| {
                    if k == 5 {
                        [0.0, f32::NAN, -1.0, 2.0][i % 4]
                    } else {
                        full[k]
                    }
                });
                let s = scale(&rot, F::new(v), F::new(full)).to_array();
                for k in 0..LANES {
                    let want = rot.scale(v[k], full[k]);
                    assert_eq!(
                        s[k].to_bits(),
                        want.to_bits(),
                        "v {} full {}",
                        v[k],
                        full[k]
                    );
                }
            }
        }
    }
}
