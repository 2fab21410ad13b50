//! Projecting constraints: the state the threads share, colour batch by
//! colour batch, eight or sixteen constraints at a time.
//!
//! Every family's kernel (in `families/`) projects a chunk of constraints
//! of one colour side by side in SIMD lanes ([`lanes`]); here is what runs
//! it: [`project_batches`] walks a constraint set's colour batches, shares
//! each batch's blocks between the crew's threads ([`Crew::claim`]), and
//! hands each block to the kernel in chunks, in the lane type of the copy
//! compiled for the processor ([`Kernel`], made by [`kernel!`]).
//! [`Shared`] and [`Particles`] are the state and multipliers the threads
//! write under the colour discipline; a [`Recorder`] takes the forced
//! rotations for the diagnostics; [`angles`] is the arctangent and the
//! turn toward a normal that every kernel shares.

pub(crate) mod angles;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx;
pub(crate) mod lanes;
mod sse;

use std::ops::Range;

use glam::{Quat, Vec3};

use super::rotation::turn_by;
use super::team::Crew;
#[cfg(doc)]
use lanes::LANES;
use lanes::{Array, Lane, WIDE_LANES};

/// Eight lanes of `wide`: two SSE registers (one AVX register in a build
/// that enables AVX for every crate); its [`Lane`] is in `sse.rs`.
pub(crate) type Sse = wide::f32x8;

/// Eight lanes in one AVX register, for the copy of the kernels compiled
/// for AVX2.
#[cfg(target_arch = "x86_64")]
pub(crate) type Avx = avx::F8;

/// Sixteen lanes in two AVX registers, for the long batches' chunks in the
/// copy of the kernels compiled for AVX2.
#[cfg(target_arch = "x86_64")]
pub(crate) type Avx16 = avx::F16;

/// Elsewhere the AVX2 copy is never chosen; its kernels use [`Sse`].
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Avx = Sse;

/// See [`Avx`].
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Avx16 = Sse;

/// A slice that the threads of a parallel region write element by element.
///
/// Sound only under the colour discipline: within a colour batch, no two
/// threads touch the same element (each constraint, and so its multiplier,
/// belongs to one thread's share; no two constraints of a batch share a
/// free particle), and a [`Crew::barrier`] separates batches.
pub(crate) struct Shared<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: see the type's documentation: concurrent access is to distinct
// elements only.
unsafe impl<T: Send> Sync for Shared<'_, T> {}
unsafe impl<T: Send> Send for Shared<'_, T> {}

impl<'a, T> Shared<'a, T> {
    /// A view of `slice`, borrowed for `'a`.
    pub fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: std::marker::PhantomData,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Element `i`, to read and write.
    ///
    /// # Safety
    /// `i < len`, and no other thread accesses element `i` until the next
    /// barrier.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn get(&self, i: usize) -> &mut T {
        debug_assert!(i < self.len);
        // SAFETY: the caller's promise.
        unsafe { &mut *self.ptr.add(i) }
    }

    /// Elements `range`, to read and write.
    ///
    /// # Safety
    /// `range` within `0..len`, and no other thread accesses these elements
    /// until the next barrier.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn slice(&self, range: Range<usize>) -> &mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked); exclusive by the caller's promise.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }
}

/// What a projection reads and writes: positions and orientations through
/// per-index accessors, masses and inertias as slices.
///
/// One view is shared by every thread of the adjust phase's region (see
/// [`Shared`]). Driven particles may be read by many constraints of a batch
/// (tether anchors), but no projection writes a particle with zero inverse
/// mass or inertia.
pub(crate) struct Particles<'a> {
    pub x: Shared<'a, Vec3>,
    q: Shared<'a, Quat>,
    pub inv_mass: &'a [f32],
    pub inv_inertia: &'a [f32],
}

impl<'a> Particles<'a> {
    /// A view of the state, borrowed for `'a`.
    pub fn new(
        x: &'a mut [Vec3],
        q: &'a mut [Quat],
        inv_mass: &'a [f32],
        inv_inertia: &'a [f32],
    ) -> Self {
        assert!(x.len() == q.len() && x.len() == inv_mass.len() && x.len() == inv_inertia.len());
        // Every index a projection uses comes from the topology or the
        // tethers, both built for this cloth and checked when built
        // (`Topology::grid`, `stretch::tethers`): in bounds by construction.
        Self {
            x: Shared::new(x),
            q: Shared::new(q),
            inv_mass,
            inv_inertia,
        }
    }

    /// Position of particle `i`.
    #[inline(always)]
    pub fn x(&self, i: usize) -> Vec3 {
        // SAFETY: in bounds; exclusive per batch (see `Shared`).
        unsafe { *self.x.get(i) }
    }

    /// Orientation of particle `i`.
    #[inline(always)]
    pub fn q(&self, i: usize) -> Quat {
        // SAFETY: in bounds; exclusive per batch (see `Shared`).
        unsafe { *self.q.get(i) }
    }

    /// Inverse mass of particle `i`.
    #[inline(always)]
    pub fn inv_mass_of(&self, i: usize) -> f32 {
        debug_assert!(i < self.inv_mass.len());
        // SAFETY: in bounds (see `new`); read-only.
        unsafe { *self.inv_mass.get_unchecked(i) }
    }

    /// Inverse inertia of particle `i`.
    #[inline(always)]
    pub fn inv_inertia_of(&self, i: usize) -> f32 {
        debug_assert!(i < self.inv_inertia.len());
        // SAFETY: in bounds (see `new`); read-only.
        unsafe { *self.inv_inertia.get_unchecked(i) }
    }

    #[inline(always)]
    fn set_x(&self, i: usize, v: Vec3) {
        // SAFETY: in bounds; exclusive per batch (see `Shared`).
        unsafe { *self.x.get(i) = v }
    }

    #[inline(always)]
    fn set_q(&self, i: usize, v: Quat) {
        // SAFETY: in bounds; exclusive per batch (see `Shared`).
        unsafe { *self.q.get(i) = v }
    }
}

/// Receives the forced rotations a projection applies (for diagnostics:
/// the largest one). Each thread has its own recorder. What each particle
/// is moved and turned by is read off its state around each family's sweep
/// instead (see `adjust`), which costs the kernels nothing.
pub(crate) trait Recorder: Send + Sync {
    /// Whether anything is recorded; lets the compiler drop the calls.
    const ON: bool;
    /// A turn by the rotation vector `omega` (axis × angle).
    fn turned(&mut self, omega: Vec3);
    /// Turns by the rotation vectors `omega`, in the lanes of `mask`.
    fn turned_lanes<F: lanes::Lane>(&mut self, omega: lanes::V3<F>, mask: F);
    /// A recorder for another thread.
    fn fork(&self) -> Self;
    /// Takes in what a forked recorder gathered (order does not matter).
    fn join(&mut self, other: Self);
}

/// The recorder used when diagnostics are off: records nothing.
#[derive(Clone, Copy)]
pub(crate) struct NoRecord;

impl Recorder for NoRecord {
    const ON: bool = false;
    #[inline(always)]
    fn turned(&mut self, _: Vec3) {}
    #[inline(always)]
    fn turned_lanes<F: lanes::Lane>(&mut self, _: lanes::V3<F>, _: F) {}
    fn fork(&self) -> Self {
        NoRecord
    }
    fn join(&mut self, _: Self) {}
}

/// The XPBD step of one constraint: the change of its multiplier `μ` for a
/// violation `c`, a generalised inverse mass `w` and a compliance
/// `alpha_t = α / Δt²`.
#[inline(always)]
pub(crate) fn delta_mu(c: f32, w: f32, alpha_t: f32, mu: f32) -> f32 {
    (-c - alpha_t * mu) / (w + alpha_t)
}

/// A kernel in every lane type: the same projection of a chunk of
/// constraints (their items, their multipliers, how many are live, the
/// recorder), once with [`Sse`], and with [`Avx`] and
/// [`Avx16`] for [`project_range`]'s AVX2 copy. Made by [`kernel!`],
/// which writes the closure once.
pub(crate) struct Kernel<S, A, W> {
    sse: S,
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx: A,
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx16: W,
}

/// A kernel's signature in lane type `L`: a chunk of items, their
/// multipliers, how many are live, the recorder.
pub(crate) trait Project<L: Lane, T: Copy, M: Copy, R>:
    Fn(&Array<L, T>, &mut Array<L, M>, usize, &mut R)
{
}

impl<L: Lane, T: Copy, M: Copy, R, P> Project<L, T, M, R> for P where
    P: Fn(&Array<L, T>, &mut Array<L, M>, usize, &mut R)
{
}

impl<S, A, W> Kernel<S, A, W> {
    /// The kernel `sse` in [`Sse`], `avx` in [`Avx`] and
    /// `avx16` in [`Avx16`].
    pub(crate) fn new<T: Copy, M: Copy, R>(sse: S, avx: A, avx16: W) -> Self
    where
        S: Fn(&Array<Sse, T>, &mut Array<Sse, M>, usize, &mut R),
        A: Fn(&Array<Avx, T>, &mut Array<Avx, M>, usize, &mut R),
        W: Fn(&Array<Avx16, T>, &mut Array<Avx16, M>, usize, &mut R),
    {
        Self { sse, avx, avx16 }
    }
}

/// The [`Kernel`] of a closure `|items, mu, live, rec| …` in which `F` is
/// the lane type:
///
/// ```ignore
/// project_batches(crew, &set.items, &mu, &set.batches, rec,
///     kernel!(|c, m, n, _| stretch::project::<F>(p, c, m, n, alpha_t)));
/// ```
///
/// (Each closure is `#[inline(always)]`, so that the kernel is inlined
/// into the copy of the chunk loop compiled for its registers.)
macro_rules! kernel {
    (|$c:ident, $m:ident, $n:ident, $r:pat_param| $body:expr) => {
        $crate::solver::kernels::Kernel::new(
            #[inline(always)]
            |$c, $m, $n, $r| {
                #[allow(dead_code)]
                type F = $crate::solver::kernels::Sse;
                $body
            },
            #[inline(always)]
            |$c, $m, $n, $r| {
                #[allow(dead_code)]
                type F = $crate::solver::kernels::Avx;
                $body
            },
            #[inline(always)]
            |$c, $m, $n, $r| {
                #[allow(dead_code)]
                type F = $crate::solver::kernels::Avx16;
                $body
            },
        )
    };
}
pub(crate) use kernel;

/// Projects `items` colour batch by colour batch with `kernel`, each with
/// its own multiplier in `mu` (same index). The threads of `crew` take
/// blocks of each batch as they come free ([`Crew::claim`]) and wait for
/// each other before the next: within a batch the order does not matter (no
/// shared particles), and a constraint's projection does not depend on the
/// thread or the lane it runs in, so the result is bit-identical for any
/// number of threads and any split. The kernel is handed the share
/// in chunks of constraints with their multipliers, for the kernels that
/// project a chunk side by side ([`lanes`]), in the lane type of the copy
/// that [`project_range`] picks.
///
/// A run of small batches (a heap of contacts ends in dozens of colours of
/// a few constraints each) is projected by thread 0 alone, batch after
/// batch, with one barrier at its end: the same projections in the same
/// order, without a barrier per batch that costs more than sharing saves.
pub(crate) fn project_batches<T, M, R, S, A, W>(
    crew: &Crew,
    items: &[T],
    mu: &Shared<M>,
    batches: &[Range<usize>],
    rec: &mut R,
    kernel: Kernel<S, A, W>,
) where
    T: Copy,
    M: Copy,
    R: Recorder,
    S: Project<Sse, T, M, R>,
    A: Project<Avx, T, M, R>,
    W: Project<Avx16, T, M, R>,
{
    assert_eq!(items.len(), mu.len());
    let small = |b: &Range<usize>| b.len() < SOLO_BATCH;
    let mut rest = batches;
    while let Some(first) = rest.first() {
        let run = if small(first) {
            rest.iter().take_while(|b| small(b)).count()
        } else {
            1
        };
        let (now, later) = rest.split_at(run);
        rest = later;
        if run > 1 {
            if crew.index() == 0 {
                for b in now {
                    project_range(items, mu, b.clone(), rec, &kernel, Width::Narrow);
                }
            }
        } else {
            let block = claim_block(first.len(), crew.size());
            while let Some(mine) = crew.claim(first.len(), block) {
                let share = first.start + mine.start..first.start + mine.end;
                project_range(items, mu, share, rec, &kernel, Width::Wide);
            }
        }
        crew.barrier();
    }
}

/// Batches under this many constraints, one after another, are projected
/// by one thread ([`project_batches`]), in chunks of [`LANES`]; longer ones
/// are shared, in chunks of [`WIDE_LANES`] where the processor has AVX2.
const SOLO_BATCH: usize = 256;

/// The chunks [`project_range`] takes: [`LANES`] constraints, or
/// [`WIDE_LANES`] in the AVX2 copy (a long batch's share; its remainder in
/// chunks of [`LANES`]). Sixteen lanes are 5–10 % faster steps on the big
/// sheets and slower on a small cloth, whose batches are short
/// (BENCHMARKS.md, "Measured design choices").
#[derive(Clone, Copy, PartialEq)]
enum Width {
    Narrow,
    Wide,
}

/// The blocks a crew of `size` claims a batch of `len` constraints in
/// ([`Crew::claim`]): about four a thread, so that a thread that meets cheap
/// constraints (small angles: no steep arctangent, no cut by Eq. 3) takes
/// more of them, in whole chunks of [`WIDE_LANES`]; and at most [`MAX_BLOCK`],
/// so that the thread that takes a big batch's last block does not keep the
/// other waiting for long (a 256 × 256 sheet's batches are 32 768 edges).
fn claim_block(len: usize, size: usize) -> usize {
    len.div_ceil(4 * size)
        .min(MAX_BLOCK)
        .next_multiple_of(WIDE_LANES)
}

/// The largest block [`claim_block`] hands out: 3 % faster steps at
/// 256 × 256 than blocks of a quarter of a thread's share, the same at
/// 64 × 64 and 128 × 128 (BENCHMARKS.md, "Measured design choices").
const MAX_BLOCK: usize = 512;

/// Projects `items[range]` chunk by chunk ([`project_batches`]), in AVX
/// registers where the processor has AVX2 ([`avx2`]): the chunk loop, with
/// the kernel inlined into it, is compiled twice, once for any processor
/// with [`Sse`] and once for AVX2 with [`Avx`], and, for a
/// [`Width::Wide`] range, [`Avx16`] first.
#[inline(always)]
fn project_range<T, M, R, S, A, W>(
    items: &[T],
    mu: &Shared<M>,
    range: Range<usize>,
    rec: &mut R,
    kernel: &Kernel<S, A, W>,
    width: Width,
) where
    T: Copy,
    M: Copy,
    R: Recorder,
    S: Project<Sse, T, M, R>,
    A: Project<Avx, T, M, R>,
    W: Project<Avx16, T, M, R>,
{
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        // SAFETY: the processor has AVX2.
        return unsafe { project_range_avx2(items, mu, range, rec, kernel, width) };
    }
    let _ = width; // The portable copy has eight lanes only.
    project_chunks::<Sse, _, _, _>(items, mu, range, rec, &kernel.sse)
}

/// [`project_range`]'s chunk loops compiled for AVX2: a wide range in
/// chunks of [`WIDE_LANES`] and the rest in chunks of [`LANES`].
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn project_range_avx2<T, M, R, S, A, W>(
    items: &[T],
    mu: &Shared<M>,
    mut range: Range<usize>,
    rec: &mut R,
    kernel: &Kernel<S, A, W>,
    width: Width,
) where
    T: Copy,
    M: Copy,
    R: Recorder,
    A: Project<Avx, T, M, R>,
    W: Project<Avx16, T, M, R>,
{
    if width == Width::Wide {
        range.start = project_whole::<Avx16, _, _, _>(items, mu, range.clone(), rec, &kernel.avx16);
    }
    project_chunks::<Avx, _, _, _>(items, mu, range, rec, &kernel.avx)
}

/// Whether the kernels run in AVX registers: the processor has AVX2, and
/// `WEFT_SIMD` is not `baseline` (which keeps them in SSE registers, to
/// compare the two; the results are the same bit for bit). Decided once.
#[cfg(target_arch = "x86_64")]
fn avx2() -> bool {
    static AVX2: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVX2.get_or_init(|| {
        std::arch::is_x86_feature_detected!("avx2")
            && std::env::var_os("WEFT_SIMD").is_none_or(|v| v != "baseline")
    })
}

/// Projects `items[range]` in chunks of `L::N` with `project`, the last one
/// padded; inlined into each copy of [`project_range`].
#[inline(always)]
fn project_chunks<L: Lane, T: Copy, M: Copy, R: Recorder>(
    items: &[T],
    mu: &Shared<M>,
    range: Range<usize>,
    rec: &mut R,
    project: &impl Project<L, T, M, R>,
) {
    let tail = project_whole::<L, _, _, _>(items, mu, range.clone(), rec, project)..range.end;
    if tail.is_empty() {
        return;
    }
    // The tail, padded with copies of its first constraint, which the
    // kernels compute but never write.
    // SAFETY: as in `project_whole`.
    let mu_tail = unsafe { mu.slice(tail.clone()) };
    let (tail, first, first_mu) = (&items[tail.clone()], items[tail.start], mu_tail[0]);
    let chunk = L::each(|k| tail.get(k).copied().unwrap_or(first));
    let mut m = L::each(|k| mu_tail.get(k).copied().unwrap_or(first_mu));
    project(&chunk, &mut m, tail.len(), rec);
    mu_tail.copy_from_slice(&m.as_ref()[..tail.len()]);
}

/// Projects the whole chunks of `L::N` at the start of `items[range]` with
/// `project`, and returns where the rest starts.
#[inline(always)]
fn project_whole<L: Lane, T: Copy, M: Copy, R: Recorder>(
    items: &[T],
    mu: &Shared<M>,
    range: Range<usize>,
    rec: &mut R,
    project: &impl Project<L, T, M, R>,
) -> usize {
    let end = range.start + range.len() / L::N * L::N;
    if end == range.start {
        return end;
    }
    // SAFETY: within `mu` (same length as `items`, checked); shares are
    // disjoint, so these multipliers are this thread's until the barrier.
    let mus = unsafe { mu.slice(range.start..end) };
    let chunks = items[range.start..end].chunks_exact(L::N);
    for (chunk, m) in chunks.zip(mus.chunks_exact_mut(L::N)) {
        project(L::chunk(chunk), L::chunk_mut(m), L::N, rec);
    }
    end
}

/// Turns particle `i` by the rotation vector `omega` (axis × angle), which
/// the caller has already shaped with Eq. 3. The turn is exact but the
/// quaternion is not renormalised here: its length drifts by rounding only
/// (about 1e-7 per turn), and the solver renormalises every orientation once
/// per substep.
#[inline]
pub(crate) fn turn<R: Recorder>(p: &Particles, i: usize, omega: Vec3, rec: &mut R) {
    p.set_q(i, turn_by(p.q(i), omega));
    if R::ON {
        rec.turned(omega);
    }
}

/// Moves particle `i` by `dx`.
#[inline]
pub(crate) fn shift(p: &Particles, i: usize, dx: Vec3) {
    p.set_x(i, p.x(i) + dx);
}
