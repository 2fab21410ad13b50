//! `Lane` for `wide::f32x8` ([`Sse`]): eight lanes in two SSE registers
//! (one AVX register in a build that enables AVX for every crate), the
//! lanes of the kernels' portable copy. Each operation is `wide`'s own;
//! [`avx`](super::avx) gives the same bits in one AVX register.

use super::Sse;
use super::lanes::{LANES, Lane, chunks_of, each};

/// Trait methods that are `wide`'s methods of the same name and signature.
macro_rules! wide_s {
    ($(fn $name:ident($($arg:ident: $ty:ty),*) -> $out:ty;)*) => {
        $(
            #[inline(always)]
            fn $name(self, $($arg: $ty),*) -> $out {
                wide::f32x8::$name(self, $($arg),*)
            }
        )*
    };
}

/// Comparisons, whose right side may be a lane value or an `f32`.
macro_rules! compare {
    ($($name:ident),*) => {
        $(
            #[inline(always)]
            fn $name(self, o: impl Into<Self>) -> Self {
                wide::f32x8::$name(self, o.into())
            }
        )*
    };
}

impl Lane for Sse {
    chunks_of!(LANES, each);
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
    fn as_array(&self) -> &[f32; LANES] {
        wide::f32x8::as_array(self)
    }
    #[inline(always)]
    fn as_mut_array(&mut self) -> &mut [f32; LANES] {
        wide::f32x8::as_mut_array(self)
    }
    compare!(simd_lt, simd_le, simd_gt, simd_ge, simd_eq);
    wide_s! {
        fn to_array() -> [f32; LANES];
        fn is_nan() -> Self;
        fn select(t: Self, f: Self) -> Self;
        fn to_bitmask() -> u32;
        fn any() -> bool;
        fn all() -> bool;
        fn none() -> bool;
        fn abs() -> Self;
        fn copysign(sign: Self) -> Self;
        fn max(o: Self) -> Self;
        fn min(o: Self) -> Self;
        fn sqrt() -> Self;
    }
    #[inline(always)]
    fn pow2(self, bias: i32) -> Self {
        let bits: wide::i32x8 = bytemuck::cast(self);
        bytemuck::cast((bits - wide::i32x8::splat(bias)) << 23)
    }
}
