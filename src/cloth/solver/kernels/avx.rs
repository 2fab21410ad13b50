//! Eight lanes in one AVX register ([`F8`]), and sixteen in two ([`F16`],
//! for long batches), for the copy of the kernels that
//! [`project_range`](super::project_range) runs where the processor has
//! AVX2.
//!
//! `wide::f32x8` picks its registers when it is compiled (two SSE
//! registers, unless every crate is built for AVX), so it cannot give a
//! copy chosen at run time one AVX register a value. This type does, for
//! exactly the operations the kernels use ([`Lane`]).
//!
//! **The same bits as [`Sse`](super::lanes::Sse).** Every operation is an
//! IEEE addition, subtraction, multiplication, division or square root
//! (correctly rounded in any register; nothing fused into a multiply-add),
//! a comparison, or a bit operation; `min` and `max` are `minps`/`maxps`
//! with a NaN on the right ignored, as `wide`'s.
//!
//! **Only inside AVX2 code.** The methods use AVX and AVX2 instructions
//! through `core::arch` and are `#[inline(always)]`, so that they become
//! instructions in the function compiled with
//! `#[target_feature(enable = "avx2")]` they are inlined into. Called from
//! anywhere else they would be calls, or fault on a processor without AVX2:
//! only `project_range`'s AVX2 copy uses them, after checking.

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

use super::lanes::{LANES, Lane, WIDE_LANES, chunks_of, each};

/// Eight `f32`s in one AVX register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct F8(__m256);

impl F8 {
    /// The lanes `v`, in a constant.
    const fn of(v: [f32; LANES]) -> Self {
        // SAFETY: the same size, and any bits are a valid `__m256`.
        unsafe { std::mem::transmute(v) }
    }
}

/// `Lane`'s conversions to and from `[f32; $n]` for a register type that
/// is exactly `$n` `f32`s: `F8` (`repr(transparent)` over `__m256`) and
/// `F16` (`repr(C)` over two `F8`, no padding). Any bits are valid both as
/// `f32`s and as registers.
macro_rules! as_floats {
    ($n:expr) => {
        #[inline(always)]
        fn new(v: [f32; $n]) -> Self {
            // SAFETY: the same size; see the macro's docs.
            unsafe { std::mem::transmute(v) }
        }
        #[inline(always)]
        fn to_array(self) -> [f32; $n] {
            // SAFETY: as `new`.
            unsafe { std::mem::transmute(self) }
        }
        #[inline(always)]
        fn as_array(&self) -> &[f32; $n] {
            // SAFETY: as `new`; `f32`'s alignment is at most the register's.
            unsafe { &*(self as *const Self).cast::<[f32; $n]>() }
        }
        #[inline(always)]
        fn as_mut_array(&mut self) -> &mut [f32; $n] {
            // SAFETY: as `as_array`.
            unsafe { &mut *(self as *mut Self).cast::<[f32; $n]>() }
        }
    };
}

/// Ordered comparisons (false where either lane is NaN), whose right side
/// may be a lane value or an `f32`: `name: predicate` of `_mm256_cmp_ps`.
macro_rules! compare {
    ($($name:ident: $predicate:ident,)*) => {
        $(
            #[inline(always)]
            fn $name(self, o: impl Into<Self>) -> Self {
                // SAFETY: see `impl Lane for F8`.
                unsafe { Self(_mm256_cmp_ps::<$predicate>(self.0, o.into().0)) }
            }
        )*
    };
}

// SAFETY (every `unsafe` block below): the instructions are AVX or AVX2,
// which the processor has wherever these run (see the module docs).
impl Lane for F8 {
    chunks_of!(LANES, each);
    const ZERO: Self = Self::of([0.0; LANES]);
    const ONE: Self = Self::of([1.0; LANES]);
    const PI: Self = Self::of([std::f32::consts::PI; LANES]);
    const FRAC_PI_2: Self = Self::of([std::f32::consts::FRAC_PI_2; LANES]);

    as_floats!(LANES);
    #[inline(always)]
    fn splat(v: f32) -> Self {
        unsafe { Self(_mm256_set1_ps(v)) }
    }
    compare! {
        simd_lt: _CMP_LT_OQ,
        simd_le: _CMP_LE_OQ,
        simd_gt: _CMP_GT_OQ,
        simd_ge: _CMP_GE_OQ,
        simd_eq: _CMP_EQ_OQ,
    }
    #[inline(always)]
    fn is_nan(self) -> Self {
        unsafe { Self(_mm256_cmp_ps::<_CMP_UNORD_Q>(self.0, self.0)) }
    }
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        unsafe { Self(_mm256_blendv_ps(f.0, t.0, self.0)) }
    }
    #[inline(always)]
    fn to_bitmask(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.to_bitmask() != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.to_bitmask() == 0xff
    }
    #[inline(always)]
    fn none(self) -> bool {
        self.to_bitmask() == 0
    }
    #[inline(always)]
    fn abs(self) -> Self {
        unsafe { Self(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)) }
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        unsafe {
            let bit = _mm256_set1_ps(-0.0);
            Self(_mm256_or_ps(
                _mm256_andnot_ps(bit, self.0),
                _mm256_and_ps(bit, sign.0),
            ))
        }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        o.is_nan()
            .select(self, unsafe { Self(_mm256_max_ps(self.0, o.0)) })
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        o.is_nan()
            .select(self, unsafe { Self(_mm256_min_ps(self.0, o.0)) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { Self(_mm256_sqrt_ps(self.0)) }
    }
    #[inline(always)]
    fn pow2(self, bias: i32) -> Self {
        unsafe {
            let bits = _mm256_sub_epi32(_mm256_castps_si256(self.0), _mm256_set1_epi32(bias));
            Self(_mm256_castsi256_ps(_mm256_slli_epi32::<23>(bits)))
        }
    }
}

impl From<f32> for F8 {
    #[inline(always)]
    fn from(v: f32) -> Self {
        Self::splat(v)
    }
}

/// `impl $op for F8` by the instruction `$instr`.
macro_rules! binary {
    ($op:ident, $method:ident, $instr:ident) => {
        impl $op for F8 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                // SAFETY: see `impl Lane for F8`.
                unsafe { Self($instr(self.0, o.0)) }
            }
        }
    };
}
binary!(Add, add, _mm256_add_ps);
binary!(Sub, sub, _mm256_sub_ps);
binary!(Mul, mul, _mm256_mul_ps);
binary!(Div, div, _mm256_div_ps);
binary!(BitAnd, bitand, _mm256_and_ps);
binary!(BitOr, bitor, _mm256_or_ps);

impl BitOrAssign for F8 {
    #[inline(always)]
    fn bitor_assign(&mut self, o: Self) {
        *self = *self | o;
    }
}

impl Neg for F8 {
    type Output = Self;
    /// The sign bit flipped, as `wide`'s.
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: see `impl Lane for F8`.
        unsafe { Self(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))) }
    }
}

impl Not for F8 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        // SAFETY: see `impl Lane for F8`.
        unsafe {
            Self(_mm256_xor_ps(
                self.0,
                _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
            ))
        }
    }
}

/// Sixteen `f32`s in two AVX registers: the lanes of a long batch's chunks
/// ([`project_range`](super::project_range)). Each operation is [`F8`]'s on
/// both halves, so a lane's bits do not depend on the half it is in.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct F16(F8, F8);

impl F16 {
    /// Both halves `v`.
    const fn halves(v: F8) -> Self {
        Self(v, v)
    }
}

/// Trait methods that apply [`F8`]'s method of the same name to both
/// halves, with the arguments' halves.
macro_rules! halves {
    ($(fn $name:ident($($arg:ident),*);)*) => {
        $(
            #[inline(always)]
            fn $name(self, $($arg: Self),*) -> Self {
                Self(self.0.$name($($arg.0),*), self.1.$name($($arg.1),*))
            }
        )*
    };
}

/// Comparisons on both halves, whose right side may be a lane value or an
/// `f32`.
macro_rules! compare_halves {
    ($($name:ident),*) => {
        $(
            #[inline(always)]
            fn $name(self, o: impl Into<Self>) -> Self {
                let o = o.into();
                Self(self.0.$name(o.0), self.1.$name(o.1))
            }
        )*
    };
}

impl Lane for F16 {
    chunks_of!(WIDE_LANES, std::array::from_fn);
    const ZERO: Self = Self::halves(F8::ZERO);
    const ONE: Self = Self::halves(F8::ONE);
    const PI: Self = Self::halves(F8::PI);
    const FRAC_PI_2: Self = Self::halves(F8::FRAC_PI_2);

    as_floats!(WIDE_LANES);
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Self::halves(F8::splat(v))
    }
    compare_halves!(simd_lt, simd_le, simd_gt, simd_ge, simd_eq);
    halves! {
        fn is_nan();
        fn select(t, f);
        fn abs();
        fn copysign(sign);
        fn max(o);
        fn min(o);
        fn sqrt();
    }
    #[inline(always)]
    fn to_bitmask(self) -> u32 {
        self.0.to_bitmask() | self.1.to_bitmask() << LANES
    }
    #[inline(always)]
    fn any(self) -> bool {
        (self.0 | self.1).any()
    }
    #[inline(always)]
    fn all(self) -> bool {
        (self.0 & self.1).all()
    }
    #[inline(always)]
    fn none(self) -> bool {
        (self.0 | self.1).none()
    }
    #[inline(always)]
    fn pow2(self, bias: i32) -> Self {
        Self(self.0.pow2(bias), self.1.pow2(bias))
    }
}

impl From<f32> for F16 {
    #[inline(always)]
    fn from(v: f32) -> Self {
        Self::splat(v)
    }
}

/// `impl $op for F16` by [`F8`]'s on both halves.
macro_rules! binary_halves {
    ($($op:ident, $method:ident;)*) => {
        $(
            impl $op for F16 {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    Self(self.0.$method(o.0), self.1.$method(o.1))
                }
            }
        )*
    };
}
binary_halves! {
    Add, add;
    Sub, sub;
    Mul, mul;
    Div, div;
    BitAnd, bitand;
    BitOr, bitor;
}

impl BitOrAssign for F16 {
    #[inline(always)]
    fn bitor_assign(&mut self, o: Self) {
        *self = *self | o;
    }
}

impl Neg for F16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(-self.0, -self.1)
    }
}

impl Not for F16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0, !self.1)
    }
}

#[cfg(test)]
mod tests {
    use super::super::lanes::math::{exp_neg, scale};
    use super::super::lanes::{
        LANES, Lane, Q4, V3, WIDE_LANES, atan, atan2, clamp_unit, forced, live, turn_by,
    };
    use super::super::{Avx, Avx16, Sse};
    use crate::solver::forced_rotation::ForcedRotation;

    /// The lane functions' results' bits in lane type `L`, lane by lane.
    fn lane_bits<L: Lane>(t: &[f32], y: &[f32], x: &[f32]) -> Vec<[u32; 10]> {
        let rot = ForcedRotation { phi: 0.7, h: 1e-4 };
        let lanes = |v: &[f32]| L::new(*L::chunk(v));
        let (t, y, x) = (lanes(t), lanes(y), lanes(x));
        let q = Q4 {
            x: y,
            y: x,
            z: t,
            w: L::ONE,
        };
        let r = V3 {
            x: t * L::splat(0.01),
            y: y * L::splat(0.01),
            z: x * L::splat(0.01),
        };
        let (turned, series) = turn_by(q, r);
        let results = [
            atan(t),
            atan2(y, x),
            scale(&rot, t.abs(), x.abs()),
            exp_neg(t.abs()),
            forced(
                &rot,
                t.abs(),
                y * L::splat(1e-3),
                x.abs(),
                L::simd_gt(x, 0.0),
            ),
            clamp_unit(t),
            turned.x,
            turned.w,
            series,
            q.normal().z,
        ];
        (0..L::N)
            .map(|k| results.map(|v| v.at(k).to_bits()))
            .collect()
    }

    #[test]
    fn the_avx_lanes_give_the_bits_of_the_sse_lanes() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for i in 0..2000 {
            let t0 = (i as f32 - 1000.0) * 0.0037 + 1e-4;
            let t: [f32; WIDE_LANES] =
                std::array::from_fn(|k| t0 * [1.0, -1.0, 0.01, 40.0][k % 4] + k as f32 * 1e-3);
            let y: [f32; WIDE_LANES] =
                std::array::from_fn(|k| [t0, t0, -t0, 0.3, f32::NAN, -0.0, 1e-30, t0][k % 8]);
            let x: [f32; WIDE_LANES] = std::array::from_fn(|k| {
                [1.0, -0.5, 0.0, t0, 2.0, -1.0, t0 * 3.0, -0.0][(k + k / 8) % 8]
            });
            // Sixteen lanes are eight and eight.
            let (lo, hi) = (0..LANES, LANES..WIDE_LANES);
            let mut sse = lane_bits::<Sse>(&t[lo.clone()], &y[lo.clone()], &x[lo.clone()]);
            sse.extend(lane_bits::<Sse>(
                &t[hi.clone()],
                &y[hi.clone()],
                &x[hi.clone()],
            ));
            let mut avx = lane_bits::<Avx>(&t[lo.clone()], &y[lo.clone()], &x[lo]);
            avx.extend(lane_bits::<Avx>(&t[hi.clone()], &y[hi.clone()], &x[hi]));
            assert_eq!(sse, avx, "{t0}");
            assert_eq!(sse, lane_bits::<Avx16>(&t, &y, &x), "{t0}");
        }
    }

    #[test]
    fn sixteen_lanes_mask_and_count_like_eight() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for n in 0..=WIDE_LANES {
            let mask = live::<Avx16>(n);
            assert_eq!(mask.to_bitmask(), (1u32 << n) - 1, "{n} live");
            assert_eq!(mask.any(), n > 0);
            assert_eq!(mask.none(), n == 0);
            assert_eq!(mask.all(), n == WIDE_LANES);
        }
        let mut v = Avx16::splat(1.0);
        v.set(11, -2.0);
        assert_eq!(v.at(11), -2.0);
        assert_eq!(
            v.abs().to_array(),
            [
                1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0
            ]
        );
        assert_eq!(v.simd_lt(0.0).to_bitmask(), 1 << 11);
    }
}
