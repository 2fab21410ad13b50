//! Sixteen `f32` lanes of weft's own ([`Floats`]), and the choice, at run
//! time, of the widest registers the processor has for them
//! ([`has_avx2`]).
//!
//! A lane value is a plain array, and every operation is written lane by
//! lane: the compiler turns each into vector instructions, sized by the
//! target features of the function it is inlined into. So the same kernels
//! run in four 128-bit SSE registers per value in a build for any x86-64,
//! and in two 256-bit AVX2 registers where
//! [`project_batches`](super::project_batches) calls a copy compiled with
//! `#[target_feature(enable = "avx2")]` (checked once with
//! `is_x86_feature_detected!`). A crate whose lanes are picked by
//! `cfg(target_feature)` at compile time (as `wide`'s are) cannot do that
//! without building every crate for AVX2. Two registers per value rather
//! than one keep two independent chains of the kernels' long dependent
//! computations in flight (BENCHMARKS.md: 8 lanes in one AVX2 register were
//! no faster than in two SSE ones).
//!
//! **The same bits either way.** Lane operations are IEEE addition,
//! subtraction, multiplication, division and square root (correctly
//! rounded, in any register), comparisons, and bit operations; nothing is
//! fused into a multiply-add (Rust never contracts `a * b + c`, and FMA is
//! not enabled) and nothing is approximated (no `rcpps`). `min` and `max`
//! are those of SSE (`minps`: the second operand when either is NaN or
//! both are zero), with the NaN fix-up `wide` made, so results are those
//! of the lanes they replace, bit for bit.
//!
//! Masks are lanes too: all bits set where true, none where false.

use std::ops::{Add, BitAnd, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

/// Lanes in a value ([`super::lanes::LANES`]).
pub(crate) const WIDTH: usize = 16;

/// Sixteen `f32`s, one per lane.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Floats([f32; N]);

const N: usize = WIDTH;

/// The mask bits of a true lane.
const TRUE: u32 = u32::MAX;

impl Floats {
    /// 0 in every lane.
    pub(crate) const ZERO: Self = Self([0.0; N]);
    /// 1 in every lane.
    pub(crate) const ONE: Self = Self([1.0; N]);
    /// π in every lane.
    pub(crate) const PI: Self = Self([std::f32::consts::PI; N]);
    /// π/2 in every lane.
    pub(crate) const FRAC_PI_2: Self = Self([std::f32::consts::FRAC_PI_2; N]);

    /// The lanes `v`.
    #[inline(always)]
    pub(crate) const fn new(v: [f32; N]) -> Self {
        Self(v)
    }

    /// `v` in every lane.
    #[inline(always)]
    pub(crate) const fn splat(v: f32) -> Self {
        Self([v; N])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub(crate) fn to_array(self) -> [f32; N] {
        self.0
    }

    /// The lanes, borrowed.
    #[inline(always)]
    pub(crate) fn as_array(&self) -> &[f32; N] {
        &self.0
    }

    /// The lanes, borrowed to change.
    #[inline(always)]
    pub(crate) fn as_mut_array(&mut self) -> &mut [f32; N] {
        &mut self.0
    }

    /// `f` of each lane.
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        let mut out = self.0;
        for v in &mut out {
            *v = f(*v);
        }
        Self(out)
    }

    /// `f` of each pair of lanes.
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        let mut out = self.0;
        for (v, w) in out.iter_mut().zip(o.0) {
            *v = f(*v, w);
        }
        Self(out)
    }

    /// `f` of each pair of lanes' bits.
    #[inline(always)]
    fn zip_bits(self, o: Self, f: impl Fn(u32, u32) -> u32) -> Self {
        self.zip(o, |a, b| f32::from_bits(f(a.to_bits(), b.to_bits())))
    }

    /// The mask of the lanes where `f` holds.
    #[inline(always)]
    fn test(self, o: Self, f: impl Fn(f32, f32) -> bool) -> Self {
        self.zip(o, |a, b| f32::from_bits(if f(a, b) { TRUE } else { 0 }))
    }

    /// The integer `f` makes of each lane's bits, as a lane's bits.
    #[inline(always)]
    pub(crate) fn map_bits(self, f: impl Fn(i32) -> i32) -> Self {
        self.map(|v| f32::from_bits(f(v.to_bits() as i32) as u32))
    }

    /// `|v|`: the sign bit cleared.
    #[inline(always)]
    pub(crate) fn abs(self) -> Self {
        self.map(f32::abs)
    }

    /// The correctly rounded square root.
    #[inline(always)]
    pub(crate) fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }

    /// `self` with the sign of `sign`.
    #[inline(always)]
    pub(crate) fn copysign(self, sign: Self) -> Self {
        self.zip(sign, f32::copysign)
    }

    /// The smaller lane, as SSE's `minps` (`o` when either is NaN or both
    /// are zero) except that a NaN `o` gives `self`.
    #[inline(always)]
    pub(crate) fn min(self, o: Self) -> Self {
        self.zip(o, |a, b| if b.is_nan() || a < b { a } else { b })
    }

    /// The larger lane, as SSE's `maxps` (`o` when either is NaN or both
    /// are zero) except that a NaN `o` gives `self`.
    #[inline(always)]
    pub(crate) fn max(self, o: Self) -> Self {
        self.zip(o, |a, b| if b.is_nan() || a > b { a } else { b })
    }

    /// The mask of the NaN lanes.
    #[inline(always)]
    pub(crate) fn is_nan(self) -> Self {
        self.test(self, |a, b| a != b)
    }

    /// The mask of the lanes where `self < o` (false for NaN).
    #[inline(always)]
    pub(crate) fn simd_lt(self, o: impl Into<Self>) -> Self {
        self.test(o.into(), |a, b| a < b)
    }

    /// The mask of the lanes where `self ≤ o` (false for NaN).
    #[inline(always)]
    pub(crate) fn simd_le(self, o: impl Into<Self>) -> Self {
        self.test(o.into(), |a, b| a <= b)
    }

    /// The mask of the lanes where `self > o` (false for NaN).
    #[inline(always)]
    pub(crate) fn simd_gt(self, o: impl Into<Self>) -> Self {
        self.test(o.into(), |a, b| a > b)
    }

    /// The mask of the lanes where `self ≥ o` (false for NaN).
    #[inline(always)]
    pub(crate) fn simd_ge(self, o: impl Into<Self>) -> Self {
        self.test(o.into(), |a, b| a >= b)
    }

    /// The mask of the lanes where `self = o` (false for NaN).
    #[inline(always)]
    pub(crate) fn simd_eq(self, o: impl Into<Self>) -> Self {
        self.test(o.into(), |a, b| a == b)
    }

    /// For a mask: `if_true` in its lanes, `if_false` elsewhere.
    #[inline(always)]
    pub(crate) fn select(self, if_true: Self, if_false: Self) -> Self {
        let picked = self.zip_bits(if_true, |m, t| m & t);
        let other = self.zip_bits(if_false, |m, f| !m & f);
        picked | other
    }

    /// For a mask: bit `k` set for lane `k` true (the sign bits; `movmskps`
    /// on x86-64, which the compiler does not make of the loop).
    #[inline(always)]
    pub(crate) fn to_bitmask(self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, _mm_movemask_ps};
            // SAFETY: sixteen `f32`s are four `__m128`s, bit for bit; SSE
            // is part of x86-64.
            let mask = |v: __m128| unsafe { _mm_movemask_ps(v) } as u32;
            let [a, b, c, d]: [__m128; 4] = unsafe { std::mem::transmute(self.0) };
            mask(a) | mask(b) << 4 | mask(c) << 8 | mask(d) << 12
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let mut bits = 0;
            for (k, v) in self.0.into_iter().enumerate() {
                bits |= (v.to_bits() >> 31) << k;
            }
            bits
        }
    }

    /// For a mask: whether every lane is true.
    #[inline(always)]
    pub(crate) fn all(self) -> bool {
        self.to_bitmask() == (1 << N) - 1
    }

    /// For a mask: whether some lane is true.
    #[inline(always)]
    pub(crate) fn any(self) -> bool {
        self.to_bitmask() != 0
    }

    /// For a mask: whether no lane is true.
    #[inline(always)]
    pub(crate) fn none(self) -> bool {
        !self.any()
    }
}

impl From<f32> for Floats {
    #[inline(always)]
    fn from(v: f32) -> Self {
        Self::splat(v)
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for Floats {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}

lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl Neg for Floats {
    type Output = Self;
    /// The sign bit flipped.
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|v| -v)
    }
}

impl BitAnd for Floats {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        self.zip_bits(o, |a, b| a & b)
    }
}

impl BitOr for Floats {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        self.zip_bits(o, |a, b| a | b)
    }
}

impl BitOrAssign for Floats {
    #[inline(always)]
    fn bitor_assign(&mut self, o: Self) {
        *self = *self | o;
    }
}

impl Not for Floats {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        self.map(|v| f32::from_bits(!v.to_bits()))
    }
}

/// Whether this processor has AVX2 (checked once; always false off x86-64).
#[inline]
pub(crate) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && !forced_baseline()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether `WEFT_SIMD=baseline` asks for the baseline kernels even where
/// AVX2 is available (to compare the two, as the tests do).
#[cfg(target_arch = "x86_64")]
fn forced_baseline() -> bool {
    static BASELINE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *BASELINE.get_or_init(|| std::env::var("WEFT_SIMD").is_ok_and(|v| v == "baseline"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes(f: impl Fn(usize) -> f32) -> Floats {
        Floats::new(std::array::from_fn(f))
    }

    #[test]
    fn min_and_max_are_those_of_sse_with_a_nan_right_side_ignored() {
        let nan = f32::NAN;
        let pick = |v: [f32; 8]| lanes(|k| v[k % 8]);
        let a = pick([1.0, 2.0, nan, 0.0, -0.0, 3.0, nan, -1.0]);
        let b = pick([2.0, 1.0, 5.0, -0.0, 0.0, nan, nan, -1.0]);
        let bits = |v: Floats| v.to_array().map(f32::to_bits);
        // NaN on the left: the right side; zeros: the right side; NaN on
        // the right: the left side.
        let min = pick([1.0, 1.0, 5.0, -0.0, 0.0, 3.0, nan, -1.0]);
        let max = pick([2.0, 2.0, 5.0, -0.0, 0.0, 3.0, nan, -1.0]);
        assert_eq!(bits(a.min(b)), bits(min));
        assert_eq!(bits(a.max(b)), bits(max));
    }

    #[test]
    fn masks_select_compare_and_count() {
        let a = lanes(|k| k as f32);
        let m = a.simd_lt(3.0);
        assert_eq!(m.to_bitmask(), 0b0000_0111);
        assert!(m.any() && !m.all() && !m.none());
        assert!((!m | m).all());
        assert!((!m & m).none());
        let picked = m.select(Floats::ONE, Floats::ZERO).to_array();
        assert_eq!(
            picked,
            std::array::from_fn(|k| if k < 3 { 1.0 } else { 0.0 })
        );
        assert_eq!(a.simd_ge(13.0).to_bitmask(), 0b1110_0000_0000_0000);
        assert_eq!(Floats::splat(f32::NAN).simd_le(1.0).to_bitmask(), 0);
        assert_eq!(Floats::splat(f32::NAN).is_nan().to_bitmask(), 0xffff);
    }

    #[test]
    fn arithmetic_is_the_scalar_arithmetic_in_every_lane() {
        let a = lanes(|k| 0.3 + k as f32 * 1.7);
        let b = lanes(|k| -2.1 + k as f32 * 0.9);
        let (x, y) = (a.to_array(), b.to_array());
        for k in 0..N {
            assert_eq!((a + b).to_array()[k], x[k] + y[k]);
            assert_eq!((a - b).to_array()[k], x[k] - y[k]);
            assert_eq!((a * b).to_array()[k], x[k] * y[k]);
            assert_eq!((a / b).to_array()[k], x[k] / y[k]);
            assert_eq!((-b).to_array()[k].to_bits(), (-y[k]).to_bits());
            assert_eq!(b.abs().to_array()[k], y[k].abs());
            assert_eq!(a.sqrt().to_array()[k], x[k].sqrt());
            assert_eq!(a.copysign(b).to_array()[k], x[k].copysign(y[k]));
        }
        assert_eq!((-Floats::ZERO).to_array()[0].to_bits(), (-0.0f32).to_bits());
    }
}
