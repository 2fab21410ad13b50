//! Eight or sixteen constraints at a time: SIMD lanes over a colour batch.
//!
//! The kernels are chains of dependent operations (a length, a reciprocal,
//! an angle, a division for `Δμ`, a turn), so one constraint at a time
//! leaves the core waiting on latencies. The constraints of a colour batch
//! share no free particle, so eight or sixteen of them can be projected side by
//! side: their inputs are gathered into lanes ([`V3`], [`Q4`], one
//! [`Lane`] value per component), every operation runs on all lanes at
//! once, and the results are scattered back constraint by constraint.
//!
//! **Three lane types, one kernel.** The kernels are generic over the lane
//! type, whose width (`Lane::N`) sets the chunk's (`Lane::Array`), and
//! compiled three times: with [`Sse`] (`wide::f32x8`, two SSE registers a
//! value) for any processor; and in a copy of the chunk loops compiled for
//! AVX2, which [`project_range`](super::project_range) takes where the
//! processor has it, with [`Avx`] (eight lanes in one AVX register) and
//! [`Avx16`] (sixteen in two, for the batches long enough to be shared
//! between threads). The same bits in all three; against `Sse`, 2–4 %
//! faster steps for eight AVX lanes and another 5–10 % for sixteen on the
//! benchmark sheets (BENCHMARKS.md, "Measured design choices"). A small
//! cloth's short batches keep eight: two registers a value spill more, and
//! its particles stay in cache.
//!
//! **Same result as one at a time.** Every lane runs exactly the operations,
//! in exactly the order, of the scalar formula it stands for (IEEE addition,
//! multiplication, division and square root are correctly rounded whether
//! done in a lane or alone; the arctangent and Eq. 3's exponential are
//! weft's own arithmetic, repeated here operation for operation), and the
//! rare branches (a turn past the series' range, a degenerate edge, `atan2`
//! on the axis) are handed to the scalar code for the lanes that take them.
//! So a
//! constraint's correction does not depend on which chunk, lane or thread
//! projects it, and results stay bit-identical for any number of threads.
//!
//! A chunk shorter than its lanes (the end of a thread's share) is padded
//! with copies of its first constraint, which are computed and never
//! written (see [`live`] and [`project_batches`](super::project_batches)).
//!
//! Here: the [`Lane`] trait and the lane types, and loading and storing a
//! chunk's fields and multipliers. [`chunk`]: a chunk's particles gathered
//! into lanes and scattered back. [`vectors`]: [`V3`], [`Q4`] and the
//! half-angle turn. [`math`]: the arctangent, Eq. 3 and the multiplier
//! change.

mod chunk;
pub(crate) mod math;
mod vectors;

use std::ops::{Add, BitAnd, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

pub(crate) use chunk::{Chunk, Held};
pub(crate) use math::{atan, atan2, clamp_unit, delta_mu, forced};
#[cfg(test)]
pub(crate) use vectors::turn_by;
pub(crate) use vectors::{Q4, V3};

/// Constraints projected side by side: a chunk of [`Sse`] or [`Avx`].
pub(crate) const LANES: usize = 8;

/// Constraints projected side by side in a long batch's chunks, in the
/// AVX2 copy: a chunk of [`Avx16`].
pub(crate) const WIDE_LANES: usize = 16;

/// A chunk's worth of `T` in lane type `L`: `[T; L::N]`.
pub(crate) type Array<L, T> = <L as Lane>::Array<T>;

/// One `f32` per lane, `N` of them: what the kernels compute in. A
/// mask is a lane value too, all bits set where true. Three types implement
/// it, with the same results bit for bit: [`Sse`] for any x86-64 (and other
/// processors), and [`Avx`] and [`Avx16`] in the copy of the kernels
/// compiled for AVX2 ([`project_range`](super::project_range)).
pub(crate) trait Lane:
    Copy
    + From<f32>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitOrAssign
    + Not<Output = Self>
{
    /// How many lanes: [`LANES`], or [`WIDE_LANES`] for [`Avx16`].
    const N: usize;
    /// `N` values of `T`, one per lane: `[T; N]`.
    type Array<T: Copy>: Copy + AsRef<[T]> + AsMut<[T]>;
    /// `[f(0), f(1), …]`, one per lane.
    fn each<T: Copy>(f: impl FnMut(usize) -> T) -> Self::Array<T>;
    /// `items` (exactly `N` of them) as an array.
    fn chunk<T: Copy>(items: &[T]) -> &Self::Array<T>;
    /// `items` (exactly `N` of them) as an array, to change.
    fn chunk_mut<T: Copy>(items: &mut [T]) -> &mut Self::Array<T>;
    /// 0 in every lane.
    const ZERO: Self;
    /// 1 in every lane.
    const ONE: Self;
    /// π in every lane.
    const PI: Self;
    /// π/2 in every lane.
    const FRAC_PI_2: Self;
    /// The lanes `v`.
    fn new(v: Self::Array<f32>) -> Self;
    /// `v` in every lane.
    fn splat(v: f32) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> Self::Array<f32>;
    /// The lanes, borrowed.
    fn as_array(&self) -> &Self::Array<f32>;
    /// The lanes, borrowed to change.
    fn as_mut_array(&mut self) -> &mut Self::Array<f32>;
    /// Lane `k`.
    #[inline(always)]
    fn at(&self, k: usize) -> f32 {
        self.as_array().as_ref()[k]
    }
    /// Sets lane `k` to `v`.
    #[inline(always)]
    fn set(&mut self, k: usize, v: f32) {
        self.as_mut_array().as_mut()[k] = v;
    }
    /// The mask of `self < o` (false where either is NaN); and so on.
    fn simd_lt(self, o: impl Into<Self>) -> Self;
    /// See [`Lane::simd_lt`].
    fn simd_le(self, o: impl Into<Self>) -> Self;
    /// See [`Lane::simd_lt`].
    fn simd_gt(self, o: impl Into<Self>) -> Self;
    /// See [`Lane::simd_lt`].
    fn simd_ge(self, o: impl Into<Self>) -> Self;
    /// See [`Lane::simd_lt`].
    fn simd_eq(self, o: impl Into<Self>) -> Self;
    /// The mask of the NaN lanes.
    fn is_nan(self) -> Self;
    /// `t` in the lanes of the mask `self`, `f` elsewhere.
    fn select(self, t: Self, f: Self) -> Self;
    /// Bit `k` set where lane `k` of the mask `self` is.
    fn to_bitmask(self) -> u32;
    /// Whether any lane of the mask is set.
    fn any(self) -> bool;
    /// Whether every lane of the mask is set.
    fn all(self) -> bool;
    /// Whether no lane of the mask is set.
    fn none(self) -> bool;
    /// `|v|`: the sign bit cleared.
    fn abs(self) -> Self;
    /// `self` with the sign bit of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// The larger, as SSE's `maxps` with a NaN in `o` ignored.
    fn max(self, o: Self) -> Self;
    /// The smaller, as SSE's `minps` with a NaN in `o` ignored.
    fn min(self, o: Self) -> Self;
    /// The correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `2^k` for the `k` that [`exp_neg`](math::exp_neg) left in the low bits of `self`
    /// (`self`'s bits as an integer, less `bias`, shifted into the exponent).
    fn pow2(self, bias: i32) -> Self;
}

/// [`Lane`]'s chunk items for a type of `$n` lanes, built by `$each`:
/// `[T; $n]`, borrowed from a slice of exactly `$n` items.
macro_rules! chunks_of {
    ($n:expr, $each:path) => {
        const N: usize = $n;
        type Array<T: Copy> = [T; $n];
        #[inline(always)]
        fn each<T: Copy>(f: impl FnMut(usize) -> T) -> [T; $n] {
            $each(f)
        }
        #[inline(always)]
        fn chunk<T: Copy>(items: &[T]) -> &[T; $n] {
            items.try_into().expect("a whole chunk")
        }
        #[inline(always)]
        fn chunk_mut<T: Copy>(items: &mut [T]) -> &mut [T; $n] {
            items.try_into().expect("a whole chunk")
        }
    };
}
pub(crate) use chunks_of;

/// `[f(0), f(1), …]`, one per lane of an eight-lane type.
#[inline(always)]
pub(crate) fn each<U>(mut f: impl FnMut(usize) -> U) -> [U; LANES] {
    [f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)]
}

/// The mask of the first `live` lanes.
#[inline(always)]
pub(crate) fn live<F: Lane>(live: usize) -> F {
    let lane = F::new(F::each(|k| k as f32));
    lane.simd_lt(F::splat(live as f32))
}

/// `f(item)` of each of a chunk's constraints, in its lane.
#[inline(always)]
pub(crate) fn field<F: Lane, T: Copy>(items: &F::Array<T>, f: impl Fn(T) -> f32) -> F {
    F::new(F::each(|k| f(items.as_ref()[k])))
}

/// `f(m)` of each of a chunk's multipliers, in its lane.
#[inline(always)]
pub(crate) fn load_with<F: Lane, M: Copy>(mu: &F::Array<M>, f: impl Fn(&M) -> f32) -> F {
    F::new(F::each(|k| f(&mu.as_ref()[k])))
}

/// A chunk's multipliers, one per lane.
#[inline(always)]
pub(crate) fn load<F: Lane>(mu: &F::Array<f32>) -> F {
    F::new(*mu)
}

/// Writes the lanes of `v` back to a chunk's multipliers.
#[inline(always)]
pub(crate) fn store<F: Lane>(v: F, mu: &mut F::Array<f32>) {
    *mu = v.to_array();
}

/// A chunk's pairs of multipliers (a constraint with two parts), as two
/// lane values.
#[inline(always)]
pub(crate) fn load_pairs<F: Lane>(mu: &F::Array<[f32; 2]>) -> [F; 2] {
    [
        load_with::<F, _>(mu, |m| m[0]),
        load_with::<F, _>(mu, |m| m[1]),
    ]
}

/// Writes two lane values back to a chunk's pairs of multipliers.
#[inline(always)]
pub(crate) fn store_pairs<F: Lane>(v: [F; 2], mu: &mut F::Array<[f32; 2]>) {
    *mu = F::each(|k| [v[0].at(k), v[1].at(k)]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8 as F;

    #[test]
    fn live_sets_every_bit_of_the_first_lanes_only() {
        for n in 0..=LANES {
            let bits = live::<F>(n).to_array().map(f32::to_bits);
            for (k, b) in bits.into_iter().enumerate() {
                assert_eq!(b, if k < n { u32::MAX } else { 0 }, "{n} live, lane {k}");
            }
        }
    }
}
