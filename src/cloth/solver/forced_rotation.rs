//! The forced rotation of §3.4: how far one correction may turn an element.
//!
//! A constraint asks for a full corrective rotation of angle `θ*` (the
//! inertia-weighted projection of its violation). The paper shapes the angle
//! actually applied with its adjustment function, Eq. 3:
//!
//! ```text
//! θ = min(θ*, Φ · exp(−h / θ*))
//! ```
//!
//! The envelope `Φ · exp(−h / ζ)` is the paper's; weft reads its garbled
//! argument as the dimensionless violation `ζ` (radians), and never turns
//! past the full correction. So:
//! - `h = 0` gives the Φ-capped full correction `min(θ*, Φ)`;
//! - a larger `h` suppresses small corrections (the envelope goes to 0 as
//!   `θ* → 0`) while large ones still approach `Φ`;
//! - no forced rotation ever exceeds `Φ`.
//!
//! weft evaluates the envelope at the constraint's violation `ζ` (an angle)
//! and caps the turn one projection asks for, `θ*`:
//! `θ = min(θ*, Φ · exp(−h / ζ))` ([`ForcedRotation::limit`]); for a rigid
//! constraint projected at once `θ* = ζ`, which is the formula above.
//!
//! When Eq. 3 cuts a turn to a fraction `θ / θ*` of what the constraint
//! asked, the constraint's whole correction (its translations too) is cut by
//! the same fraction ([`ForcedRotation::scale`]), so a constraint never moves
//! positions for a turn it did not make.
//!
//! `h` is an angle, so its default ([`DEFAULT_WIDTH`]) is one number that
//! does not depend on the grid's resolution, the substeps or the material:
//! violations below about `h / 9` (1e-5 rad at the default `Φ = π/4`) are
//! left alone, far below anything visible. See `docs/method.md`.

/// The default envelope width `h`, in radians.
pub const DEFAULT_WIDTH: f32 = 1e-4;

/// Eq. 3 with its two parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForcedRotation {
    /// Cap on one forced rotation, `Φ ∈ [0, π]`.
    pub phi: f32,
    /// Width of the envelope, `h ≥ 0`.
    pub h: f32,
}

impl ForcedRotation {
    /// Eq. 3 for a constraint whose violation is the angle `violation` and
    /// which asks for a turn of `full`: the angle applied,
    /// `min(full, Φ · exp(−h / violation))`.
    ///
    /// The envelope's argument is the violation, as in the paper, not the
    /// size of one sweep's correction: a soft constraint corrects a little
    /// per sweep, more sweeps correct less each time, and neither may change
    /// which violations Eq. 3 lets through.
    #[inline]
    pub fn limit(&self, violation: f32, full: f32) -> f32 {
        if full.is_nan() || full <= 0.0 {
            return 0.0;
        }
        if violation.is_nan() || violation <= 0.0 {
            // No violation: the envelope is closed (h > 0) or Φ (h = 0).
            return if self.h > 0.0 {
                0.0
            } else {
                full.min(self.phi)
            };
        }
        // exp(−r) ≥ 1 − r with r = h / violation: when even that lower bound
        // of the envelope is above the full correction, the min is the full
        // correction (exact, and by far the common case; multiplied through
        // by the violation, so without a division). Under `h` the right
        // side is negative (for Φ > 0) and the test fails without the
        // product, which for the tiny violations of a cloth at rest would be
        // subnormal (see `rotation::FOURTH_ORDER`).
        let below = violation < self.h && self.phi > 0.0;
        if !below && full * violation <= self.phi * (violation - self.h) {
            return full;
        }
        let ratio = self.h / violation;
        let envelope = if ratio <= 0.0 {
            self.phi
        } else if ratio >= 80.0 {
            // exp(−80) ≈ 2e-35: nothing is left of the correction.
            return 0.0;
        } else {
            self.phi * exp_neg(ratio)
        };
        full.min(envelope)
    }

    /// Eq. 3 where the turn asked for is the whole violation (a rigid
    /// constraint projected at once): `min(θ*, Φ · exp(−h / θ*))`.
    #[inline]
    pub fn angle(&self, full: f32) -> f32 {
        self.limit(full, full)
    }

    /// The fraction of a requested turn `full` that Eq. 3 lets through for
    /// a constraint violated by `violation`, in `[0, 1]`; 1 when nothing is
    /// asked.
    #[inline]
    pub fn scale(&self, violation: f32, full: f32) -> f32 {
        // Written so that NaN gives 1: a non-finite state is reported by the
        // step, never turned into a panic or silently zeroed here.
        if full.is_nan() || full <= 0.0 {
            return 1.0;
        }
        let angle = self.limit(violation, full);
        if angle >= full { 1.0 } else { angle / full }
    }
}

/// `exp(−r)` for `0 ≤ r ≤ 87`, without a libm call: `2^k · e^f` with `k`
/// the integer nearest `−r / ln 2` and `|f| ≤ ln 2 / 2`, `e^f` by its Taylor
/// polynomial of degree 7 (truncation below 1e-8, relative error within
/// 2 ulp). Pure IEEE arithmetic, so it is the same on every machine and
/// the SIMD lanes reproduce it bit for bit ([`lanes::math::exp_neg`]).
///
/// [`lanes::math::exp_neg`]: super::kernels::lanes::math::exp_neg
#[inline]
pub(crate) fn exp_neg(r: f32) -> f32 {
    let t = -r * std::f32::consts::LOG2_E + EXP_SHIFTER;
    let k = t - EXP_SHIFTER;
    let f = (-r - k * EXP_LN2_HI) - k * EXP_LN2_LO;
    let two_k = f32::from_bits(((t.to_bits() as i32 - EXP_SHIFTER_BITS + 127) << 23) as u32);
    exp_poly(f, |v| v) * two_k
}

/// Adding `1.5 · 2^23` rounds an `f32` of magnitude below `2^22` to an
/// integer, which is then the low bits of the sum's representation.
pub(crate) const EXP_SHIFTER: f32 = 12_582_912.0;
/// [`EXP_SHIFTER`]'s bits.
pub(crate) const EXP_SHIFTER_BITS: i32 = 0x4b40_0000;
/// `ln 2` in two parts: the first exact in 9 bits (so `k · EXP_LN2_HI` is
/// exact), the second the rest.
pub(crate) const EXP_LN2_HI: f32 = 0.693_359_4;
/// See [`EXP_LN2_HI`].
pub(crate) const EXP_LN2_LO: f32 = -2.121_944_4e-4;

/// `e^f` for `|f| ≤ ln 2 / 2`: `Σ fⁿ/n!` up to `n = 7`, by Horner's scheme,
/// in `f32` or in lanes (`c` makes a constant).
#[inline(always)]
pub(crate) fn exp_poly<T>(f: T, c: impl Fn(f32) -> T) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Output = T>,
{
    let p = c(1.0 / 720.0) + f * (c(1.0 / 5040.0));
    let p = c(1.0 / 120.0) + f * p;
    let p = c(1.0 / 24.0) + f * p;
    let p = c(1.0 / 6.0) + f * p;
    let p = c(0.5) + f * p;
    let p = c(1.0) + f * p;
    c(1.0) + f * p
}
