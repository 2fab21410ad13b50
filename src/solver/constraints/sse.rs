//! `Lane` for `wide::f32x8` ([`Sse`]): eight lanes in two SSE registers
//! (one AVX register in a build that enables AVX for every crate), the
//! lanes of the kernels' portable copy. Each operation is `wide`'s own;
//! [`avx`](super::avx) gives the same bits in one AVX register.

use super::lanes::{LANES, Lane, Sse};

impl Lane for Sse {
    const ZERO: Self = wide::f32x8::ZERO;
    const ONE: Self = wide::f32x8::ONE;
    const PI: Self = wide::f32x8::PI;
    const FRAC_PI_2: Self = wide::f32x8::FRAC_PI_2;
    #[inline(always)]
    fn new(v: [f32; LANES]) -> Self {
        wide::f32x8::new(v)
    }
    #[inline(always)]
    fn splat(v: f32) -> Self {
        wide::f32x8::splat(v)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        wide::f32x8::to_array(self)
    }
    #[inline(always)]
    fn as_array(&self) -> &[f32; LANES] {
        wide::f32x8::as_array(self)
    }
    #[inline(always)]
    fn as_mut_array(&mut self) -> &mut [f32; LANES] {
        wide::f32x8::as_mut_array(self)
    }
    #[inline(always)]
    fn simd_lt(self, o: impl Into<Self>) -> Self {
        wide::f32x8::simd_lt(self, o.into())
    }
    #[inline(always)]
    fn simd_le(self, o: impl Into<Self>) -> Self {
        wide::f32x8::simd_le(self, o.into())
    }
    #[inline(always)]
    fn simd_gt(self, o: impl Into<Self>) -> Self {
        wide::f32x8::simd_gt(self, o.into())
    }
    #[inline(always)]
    fn simd_ge(self, o: impl Into<Self>) -> Self {
        wide::f32x8::simd_ge(self, o.into())
    }
    #[inline(always)]
    fn simd_eq(self, o: impl Into<Self>) -> Self {
        wide::f32x8::simd_eq(self, o.into())
    }
    #[inline(always)]
    fn is_nan(self) -> Self {
        wide::f32x8::is_nan(self)
    }
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        wide::f32x8::select(self, t, f)
    }
    #[inline(always)]
    fn to_bitmask(self) -> u32 {
        wide::f32x8::to_bitmask(self)
    }
    #[inline(always)]
    fn any(self) -> bool {
        wide::f32x8::any(self)
    }
    #[inline(always)]
    fn all(self) -> bool {
        wide::f32x8::all(self)
    }
    #[inline(always)]
    fn none(self) -> bool {
        wide::f32x8::none(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        wide::f32x8::abs(self)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        wide::f32x8::copysign(self, sign)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        wide::f32x8::max(self, o)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        wide::f32x8::min(self, o)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        wide::f32x8::sqrt(self)
    }
    #[inline(always)]
    fn pow2(self, bias: i32) -> Self {
        let bits: wide::i32x8 = bytemuck::cast(self);
        bytemuck::cast((bits - wide::i32x8::splat(bias)) << 23)
    }
}
