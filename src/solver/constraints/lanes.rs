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
//! benchmark sheets (BENCHMARKS.md, "the kernels in AVX registers",
//! "Sixteen lanes in two AVX registers"). A small cloth's short batches keep
//! eight: two registers a value spill more, and its particles stay in cache.
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

use std::ops::{Add, BitAnd, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

use glam::{Quat, Vec3};

use super::{ATAN_POLY, NoRecord, Particles, Recorder, SMALL_ANGLE_FLOOR, shift, turn};
use crate::solver::cloth::{FOURTH_ORDER, NEGLIGIBLE_TURN};
use crate::solver::forced_rotation::ForcedRotation;

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
    /// `2^k` for the `k` that [`exp_neg`] left in the low bits of `self`
    /// (`self`'s bits as an integer, less `bias`, shifted into the exponent).
    fn pow2(self, bias: i32) -> Self;
}

/// Eight lanes of `wide`: two SSE registers (one AVX register in a build
/// that enables AVX for every crate); its [`Lane`] is in `constraints/sse.rs`.
pub(crate) type Sse = wide::f32x8;

/// Eight lanes in one AVX register, for the copy of the kernels compiled
/// for AVX2.
#[cfg(target_arch = "x86_64")]
pub(crate) type Avx = super::avx::F8;

/// Sixteen lanes in two AVX registers, for the long batches' chunks in the
/// copy of the kernels compiled for AVX2.
#[cfg(target_arch = "x86_64")]
pub(crate) type Avx16 = super::avx::F16;

/// Elsewhere the AVX2 copy is never chosen; its kernels use [`Sse`].
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Avx = Sse;

/// See [`Avx`].
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Avx16 = Sse;

/// The particle indices of one role (say, every constraint's first end)
/// across a chunk of `F::N` constraints.
#[derive(Clone, Copy)]
pub(crate) struct Chunk<F: Lane> {
    idx: F::Array<usize>,
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

impl<F: Lane> Chunk<F> {
    /// The indices `f(item)` of a chunk's constraints.
    #[inline(always)]
    pub(crate) fn of<T: Copy>(items: &F::Array<T>, f: impl Fn(T) -> u32) -> Self {
        Self {
            idx: F::each(|k| f(items.as_ref()[k]) as usize),
        }
    }

    /// The particle index in lane `k`.
    #[inline(always)]
    pub(crate) fn at(&self, k: usize) -> usize {
        self.idx.as_ref()[k]
    }

    /// Each lane's inverse mass.
    #[inline(always)]
    pub(crate) fn inv_mass(&self, p: &Particles) -> F {
        F::new(F::each(|k| p.inv_mass_of(self.at(k))))
    }

    /// Each lane's inverse inertia.
    #[inline(always)]
    pub(crate) fn inv_inertia(&self, p: &Particles) -> F {
        F::new(F::each(|k| p.inv_inertia_of(self.at(k))))
    }

    /// Each lane's position.
    #[inline(always)]
    pub(crate) fn x(&self, p: &Particles) -> V3<F> {
        V3::from_lanes(F::each(|k| p.x(self.at(k))))
    }

    /// Each lane's orientation.
    #[inline(always)]
    pub(crate) fn q(&self, p: &Particles) -> Q4<F> {
        let q = F::each(|k| p.q(self.at(k)));
        let q = q.as_ref();
        Q4 {
            x: F::new(F::each(|k| q[k].x)),
            y: F::new(F::each(|k| q[k].y)),
            z: F::new(F::each(|k| q[k].z)),
            w: F::new(F::each(|k| q[k].w)),
        }
    }

    /// Moves each lane's particle by its `dx`, in the lanes of `mask`.
    #[inline(always)]
    pub(crate) fn shift(&self, p: &Particles, dx: V3<F>, mask: F) {
        let bits = mask.to_bitmask();
        for k in 0..F::N {
            if bits & (1 << k) != 0 {
                shift(p, self.at(k), dx.lane(k));
            }
        }
    }

    /// Turns each lane's particle, whose orientation was `q`, by the
    /// rotation vector `omega`, in the lanes of `mask` (as
    /// [`super::turn`]).
    #[inline(always)]
    pub(crate) fn turn<R: Recorder>(
        &self,
        p: &Particles,
        q: Q4<F>,
        omega: V3<F>,
        mask: F,
        rec: &mut R,
    ) {
        let bits = mask.to_bitmask();
        if bits == 0 {
            return;
        }
        if R::ON {
            rec.turned_lanes(omega, mask);
        }
        let (turned, series) = turn_by(q, omega);
        let series = series.to_bitmask();
        for k in 0..F::N {
            if bits & (1 << k) == 0 {
                continue;
            }
            let i = self.at(k);
            if series & (1 << k) == 0 {
                turn(p, i, omega.lane(k), &mut NoRecord);
                continue;
            }
            p.set_q(i, turned.lane(k));
        }
    }
}

/// A chunk's positions held in lanes while a kernel moves them more than
/// once, written back once at the end ([`Held::put`]). Each move is the
/// same addition [`Chunk::shift`] makes in memory, so the result is too.
#[derive(Clone, Copy)]
pub(crate) struct Held<F: Lane> {
    pub x: V3<F>,
    /// The lanes moved so far.
    moved: F,
}

impl<F: Lane> Held<F> {
    /// The chunk's positions.
    #[inline(always)]
    pub(crate) fn of(p: &Particles, chunk: &Chunk<F>) -> Self {
        Self {
            x: chunk.x(p),
            moved: F::ZERO,
        }
    }

    /// Moves each lane's position by its `dx`, in the lanes of `mask`.
    #[inline(always)]
    pub(crate) fn shift(&mut self, dx: V3<F>, mask: F) {
        self.x = V3::select(mask, self.x + dx, self.x);
        self.moved |= mask;
    }

    /// Writes the moved lanes' positions back.
    #[inline(always)]
    pub(crate) fn put(&self, p: &Particles, chunk: &Chunk<F>) {
        let bits = self.moved.to_bitmask();
        for k in (0..F::N).filter(|k| bits & (1 << k) != 0) {
            p.set_x(chunk.at(k), self.x.lane(k));
        }
    }
}

/// A vector per lane.
#[derive(Clone, Copy)]
pub(crate) struct V3<F: Lane> {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl<F: Lane> V3<F> {
    #[inline(always)]
    fn from_lanes(v: F::Array<Vec3>) -> Self {
        let v = v.as_ref();
        Self {
            x: F::new(F::each(|k| v[k].x)),
            y: F::new(F::each(|k| v[k].y)),
            z: F::new(F::each(|k| v[k].z)),
        }
    }

    /// `v` in every lane.
    #[inline(always)]
    pub(crate) fn splat(v: Vec3) -> Self {
        Self {
            x: F::splat(v.x),
            y: F::splat(v.y),
            z: F::splat(v.z),
        }
    }

    /// `values[idx[k]]` in each lane `k`.
    #[inline(always)]
    pub(crate) fn gather(values: &[Vec3], idx: &F::Array<u32>) -> Self {
        Self::from_lanes(F::each(|k| values[idx.as_ref()[k] as usize]))
    }

    /// Lane `k`'s vector.
    #[inline(always)]
    pub(crate) fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x.at(k), self.y.at(k), self.z.at(k))
    }

    /// Sets lane `k`'s vector.
    #[inline(always)]
    pub(crate) fn set_lane(&mut self, k: usize, v: Vec3) {
        self.x.set(k, v.x);
        self.y.set(k, v.y);
        self.z.set(k, v.z);
    }

    /// `a` in the lanes of `mask`, `b` elsewhere.
    #[inline(always)]
    pub(crate) fn select(mask: F, a: Self, b: Self) -> Self {
        Self {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }

    /// Set in the lanes whose point lies in the box `[lo, hi]`, bounds
    /// included (as glam's `x.cmpge(lo).all() && x.cmple(hi).all()`).
    #[inline(always)]
    pub(crate) fn in_box(self, lo: Self, hi: Self) -> F {
        self.x.simd_ge(lo.x)
            & self.y.simd_ge(lo.y)
            & self.z.simd_ge(lo.z)
            & self.x.simd_le(hi.x)
            & self.y.simd_le(hi.y)
            & self.z.simd_le(hi.z)
    }

    /// As glam's `Vec3::dot`.
    #[inline(always)]
    pub(crate) fn dot(self, o: Self) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// As glam's `Vec3::cross`.
    #[inline(always)]
    pub(crate) fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// As glam's `Vec3::length_squared`.
    #[inline(always)]
    pub(crate) fn length_squared(self) -> F {
        self.dot(self)
    }

    /// As glam's `Vec3::length`.
    #[inline(always)]
    pub(crate) fn length(self) -> F {
        self.dot(self).sqrt()
    }
}

impl<F: Lane> std::ops::Add for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<F: Lane> std::ops::Sub for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<F: Lane> std::ops::Mul<F> for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: F) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// A quaternion per lane.
#[derive(Clone, Copy)]
pub(crate) struct Q4<F: Lane> {
    pub x: F,
    pub y: F,
    pub z: F,
    pub w: F,
}

impl<F: Lane> Q4<F> {
    #[inline(always)]
    fn lane(&self, k: usize) -> Quat {
        Quat::from_xyzw(self.x.at(k), self.y.at(k), self.z.at(k), self.w.at(k))
    }

    /// Each lane's normal (as [`normal_of`](crate::solver::cloth::normal_of)).
    #[inline(always)]
    pub(crate) fn normal(&self) -> V3<F> {
        let two = F::splat(2.0);
        V3 {
            x: two * (self.x * self.z + self.w * self.y),
            y: two * (self.y * self.z - self.w * self.x),
            z: F::ONE - two * (self.x * self.x + self.y * self.y),
        }
    }

    /// `self * q`, with glam's order of operations for `Quat`'s product.
    #[inline(always)]
    fn mul(self, q: Self) -> Self {
        let l = self;
        Self {
            x: (l.w * q.x + l.x * q.w) + (l.y * q.z - l.z * q.y),
            y: (l.w * q.y - l.x * q.z) + (l.y * q.w + l.z * q.x),
            z: (l.w * q.z + l.x * q.y) + (l.z * q.w - l.y * q.x),
            w: (l.w * q.w - l.x * q.x) - (l.y * q.y + l.z * q.z),
        }
    }
}

/// [`turn_by`](crate::solver::cloth::turn_by) by its half-angle series, in
/// every lane; the mask says which lanes are within the series' range (the
/// others need the scalar turn). The fourth-order terms only where they
/// count ([`FOURTH_ORDER`]): elsewhere `θ⁴` would be subnormal for the tiny
/// turns of a resting cloth.
#[inline(always)]
fn turn_by<F: Lane>(q: Q4<F>, r: V3<F>) -> (Q4<F>, F) {
    // As the scalar `angle_squared`: components under NEGLIGIBLE_TURN left out.
    let kept = |v: F| v.abs().simd_lt(NEGLIGIBLE_TURN).select(F::ZERO, v);
    let t2 = V3 {
        x: kept(r.x),
        y: kept(r.y),
        z: kept(r.z),
    }
    .length_squared();
    let (c, s) = (
        F::ONE - t2 * F::splat(1.0 / 8.0),
        F::splat(0.5) - t2 * F::splat(1.0 / 48.0),
    );
    let fourth = t2.simd_ge(FOURTH_ORDER);
    let (c, s) = if fourth.none() {
        (c, s)
    } else {
        // At least FOURTH_ORDER² in every lane, so never subnormal; the
        // lanes below keep the second-order values.
        let t2 = t2.max(F::splat(FOURTH_ORDER));
        let t4 = t2 * t2;
        (
            fourth.select(c + t4 * F::splat(1.0 / 384.0), c),
            fourth.select(s + t4 * F::splat(1.0 / 3840.0), s),
        )
    };
    let d = Q4 {
        x: r.x * s,
        y: r.y * s,
        z: r.z * s,
        w: c,
    };
    (d.mul(q), t2.simd_lt(0.0025))
}

/// [`atan`](super::atan) in every lane.
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

/// [`atan2`](super::atan2) in every lane: in lanes for `x ≠ 0`, alone for
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
            out.set(k, super::atan2(y.at(k), x.at(k)));
        }
    }
    out
}

/// [`delta_mu`](super::delta_mu) in every lane.
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
/// cycles each on many x86 cores, see `cloth::FOURTH_ORDER`) for moves far
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

/// `f32::clamp(v, -1, 1)` in every lane (NaN stays NaN).
#[inline(always)]
pub(crate) fn clamp_unit<F: Lane>(v: F) -> F {
    let v = v.simd_lt(-1.0).select(F::splat(-1.0), v);
    v.simd_gt(1.0).select(F::ONE, v)
}

#[cfg(test)]
mod tests {
    use super::Sse as F;
    use super::*;

    #[test]
    fn live_sets_every_bit_of_the_first_lanes_only() {
        for n in 0..=LANES {
            let bits = live::<F>(n).to_array().map(f32::to_bits);
            for (k, b) in bits.into_iter().enumerate() {
                assert_eq!(b, if k < n { u32::MAX } else { 0 }, "{n} live, lane {k}");
            }
        }
    }

    /// The lane functions' results' bits in lane type `L`, lane by lane.
    #[cfg(target_arch = "x86_64")]
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
    #[cfg(target_arch = "x86_64")]
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
    #[cfg(target_arch = "x86_64")]
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
                assert_eq!(a[k].to_bits(), super::super::atan(ts[k]).to_bits());
                assert_eq!(b[k].to_bits(), super::super::atan2(y[k], x[k]).to_bits());
                assert_eq!(s[k].to_bits(), rot.scale(ts[k].abs(), full[k]).to_bits());
            }
        }
        // A flat sheet beside a fold: tiny angles (whose powers would be
        // subnormal) in the lanes beside wide and steep ones.
        for wide in [0.07, -0.6, 3.0, 1e4] {
            let ts = each(|k| [1e-30, wide, -1e-20, 1e-40, 0.0, -0.0, 2e-13, wide][k % 8]);
            let a = atan(F::new(ts)).to_array();
            for k in 0..LANES {
                assert_eq!(a[k].to_bits(), super::super::atan(ts[k]).to_bits());
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
        let want = crate::solver::cloth::turn_by(q, r);
        assert_eq!(
            t.lane(2).to_array().map(f32::to_bits),
            want.to_array().map(f32::to_bits)
        );
        let n = crate::solver::cloth::normal_of(q);
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
