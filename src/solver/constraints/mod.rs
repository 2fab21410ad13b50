//! The adjust phase's geometric constraints (§3.3), one module per family.
//!
//! Every family is a scalar violation `C` of two or three particles whose
//! gradient reproduces the vectors printed in the paper:
//!
//! | family | violation `C` | gradient in position | gradient in rotation |
//! |---|---|---|---|
//! | stretch | `|s| − L` (and tethers, one-sided) | `∓ ŝ` | — |
//! | planarity | `α = asin(n_a · ŝ)`, zero iff `n_a · s = 0` | `∓ n⊥ / |s|` | unit `n_a × ŝ` (the paper's `v`) |
//! | normality | `∠(n_a, n_b)`; shear: diagonal `|s| − L` | —; `∓ ŝ` | `n_a × n_b`; — |
//! | curvature | sagitta angle `2 n̂⊥ · (x_m − ½(x_a + x_b)) / L`; bend angle | `n̂⊥`, `−½ n̂⊥` | `(n_a + n_b) × s` |
//!
//! with `s = x_b − x_a`, `n⊥` the normal made perpendicular to the edge and
//! `n̂⊥` the normalised `n_a + n_b` made perpendicular to the chord.
//!
//! **Projection (§3.4, in compliance form).** A correction changes positions
//! and orientations as little as possible in the metric of mass and inertia.
//! With inverse masses `w`, inverse inertias `β` and gradients `g`, each
//! constraint keeps a multiplier `μ` over the substep (XPBD, Macklin et al.
//! 2016) and every sweep applies
//!
//! ```text
//! Δμ = (−C − α̃ μ) / (Σ w|g_x|² + Σ β|g_θ|² + α̃),   α̃ = α / Δt²
//! ```
//!
//! moving each particle by `w g_x Δμ` and turning it by `β g_θ Δμ`. The
//! compliance `α` comes from the family's weight `λ` (see
//! [`Weights`](super::Weights)): `λ = 1` is rigid (`α = 0`, plain projection),
//! smaller weights are softer. Because `α` is a physical compliance, the
//! stiffness a weight gives does not change with iterations or substeps.
//! Every turn is shaped by Eq. 3 ([`ForcedRotation::scale`]); when Eq. 3 cuts
//! a turn, the constraint's `Δμ`, and with it its translations, is cut by
//! the same fraction.

pub mod curvature;
pub mod normality;
pub mod planarity;
pub mod stretch;

use glam::{Quat, Vec3};

use super::cloth::turn_by;
#[cfg(doc)]
use super::forced_rotation::ForcedRotation;

/// What a projection reads and writes: positions and orientations through
/// per-index accessors, masses and inertias as slices.
///
/// One view is shared by every thread projecting a colour batch. That is
/// sound because of the colouring: no two constraints of a batch touch the
/// same free particle, so no element is written by one thread while another
/// reads or writes it. Driven particles may be read by many constraints of a
/// batch (tether anchors), but no projection writes a particle with zero
/// inverse mass or inertia.
pub(crate) struct Particles<'a> {
    x: *mut Vec3,
    q: *mut Quat,
    len: usize,
    pub inv_mass: &'a [f32],
    pub inv_inertia: &'a [f32],
    _borrow: std::marker::PhantomData<&'a mut [Vec3]>,
}

// SAFETY: see the type's documentation: concurrent access is to distinct
// elements only, which the colour batches guarantee.
unsafe impl Sync for Particles<'_> {}

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
        // tethers, both built for this cloth and checked in debug builds
        // (`Topology::grid`, `stretch::tethers`): in bounds by construction.
        Self {
            len: x.len(),
            x: x.as_mut_ptr(),
            q: q.as_mut_ptr(),
            inv_mass,
            inv_inertia,
            _borrow: std::marker::PhantomData,
        }
    }

    /// Position of particle `i`.
    #[inline(always)]
    pub fn x(&self, i: usize) -> Vec3 {
        debug_assert!(i < self.len);
        // SAFETY: in bounds; exclusive per batch (see the type's docs).
        unsafe { *self.x.add(i) }
    }

    /// Orientation of particle `i`.
    #[inline(always)]
    pub fn q(&self, i: usize) -> Quat {
        debug_assert!(i < self.len);
        // SAFETY: in bounds; exclusive per batch (see the type's docs).
        unsafe { *self.q.add(i) }
    }

    #[inline(always)]
    fn set_x(&self, i: usize, v: Vec3) {
        debug_assert!(i < self.len);
        // SAFETY: in bounds; exclusive per batch (see the type's docs).
        unsafe { *self.x.add(i) = v }
    }

    #[inline(always)]
    fn set_q(&self, i: usize, v: Quat) {
        debug_assert!(i < self.len);
        // SAFETY: in bounds; exclusive per batch (see the type's docs).
        unsafe { *self.q.add(i) = v }
    }
}

/// Receives the corrections a projection applies (for diagnostics). Each
/// thread has its own recorder; its per-particle writes follow the same
/// colour discipline as [`Particles`].
pub(crate) trait Recorder: Send + Sync {
    /// Whether anything is recorded; lets the compiler drop the calls.
    const ON: bool;
    fn moved(&mut self, i: usize, dx: Vec3);
    fn turned(&mut self, i: usize, axis_angle: Vec3);
    /// A recorder for another thread, writing to the same place.
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
    fn moved(&mut self, _: usize, _: Vec3) {}
    #[inline(always)]
    fn turned(&mut self, _: usize, _: Vec3) {}
    fn fork(&self) -> Self {
        NoRecord
    }
    fn join(&mut self, _: Self) {}
}

/// Constraints per colour batch below which one thread beats several.
const PARALLEL_MIN: usize = 4096;
/// Constraints per parallel task.
const CHUNK: usize = 1024;

/// The XPBD step of one constraint: the change of its multiplier `μ` for a
/// violation `c`, a generalised inverse mass `w` and a compliance
/// `alpha_t = α / Δt²`.
#[inline(always)]
pub(crate) fn delta_mu(c: f32, w: f32, alpha_t: f32, mu: f32) -> f32 {
    (-c - alpha_t * mu) / (w + alpha_t)
}

/// Projects `items` colour batch by colour batch with `project`, each with
/// its own multiplier in `mu` (same index); large batches are split across
/// rayon's threads. Within a batch the order does not matter (no shared
/// particles), so the result is bit-identical for any number of threads.
pub(crate) fn project_batches<T, M, R>(
    items: &[T],
    mu: &mut [M],
    batches: &[std::ops::Range<usize>],
    rec: &mut R,
    project: impl Fn(T, &mut M, &mut R) + Sync,
) where
    T: Copy + Sync,
    M: Send,
    R: Recorder,
{
    use rayon::prelude::*;
    debug_assert_eq!(items.len(), mu.len());
    for range in batches {
        let batch = &items[range.clone()];
        let mu = &mut mu[range.clone()];
        if batch.len() < PARALLEL_MIN || rayon::current_num_threads() == 1 {
            for (&c, m) in batch.iter().zip(mu) {
                project(c, m, rec);
            }
        } else {
            let base: &R = rec;
            let gathered = batch
                .par_chunks(CHUNK)
                .zip(mu.par_chunks_mut(CHUNK))
                .map(|(chunk, mu)| {
                    let mut r = base.fork();
                    for (&c, m) in chunk.iter().zip(mu) {
                        project(c, m, &mut r);
                    }
                    r
                })
                .reduce(
                    || base.fork(),
                    |mut a, b| {
                        a.join(b);
                        a
                    },
                );
            rec.join(gathered);
        }
    }
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
        rec.turned(i, omega);
    }
}

/// Moves particle `i` by `dx`.
#[inline]
pub(crate) fn shift<R: Recorder>(p: &Particles, i: usize, dx: Vec3, rec: &mut R) {
    p.set_x(i, p.x(i) + dx);
    if R::ON {
        rec.moved(i, dx);
    }
}

/// `atan2(y, x)`, without a libm call: the series `t − t³/3 + t⁵/5 − t⁷/7`
/// (`t = y/x`) for the small angles that dominate (error below 1e-10), and
/// elsewhere a polynomial in `t²` on `|t| ≤ 1` (least-squares fit, error
/// below 2e-7 rad in `f32`) with the usual octant reduction. Pure arithmetic,
/// so the same on every machine. NaN in, NaN out.
#[inline]
pub(crate) fn atan2(y: f32, x: f32) -> f32 {
    if x > 0.0 && y.abs() < 0.05 * x {
        let t = y / x;
        let t2 = t * t;
        return t * (1.0 - t2 * (1.0 / 3.0 - t2 * (0.2 - t2 / 7.0)));
    }
    if x.is_nan() || y.is_nan() {
        return f32::NAN;
    }
    let (ay, ax) = (y.abs(), x.abs());
    if ay == 0.0 && ax == 0.0 {
        return 0.0;
    }
    let (t, steep) = if ay <= ax {
        (ay / ax, false)
    } else {
        (ax / ay, true)
    };
    let t2 = t * t;
    let p = ATAN_POLY.iter().rev().fold(0.0f32, |acc, &c| acc * t2 + c);
    let mut a = t * p;
    if steep {
        a = std::f32::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f32::consts::PI - a;
    }
    if y < 0.0 { -a } else { a }
}

/// `atan(t) / t` as a polynomial in `t²` on `[0, 1]`, lowest power first.
const ATAN_POLY: [f32; 8] = [
    0.999_999_34,
    -0.333_298_6,
    0.199_465_66,
    -0.139_086_28,
    0.096_421_905,
    -0.055_912_21,
    0.021_862_866,
    -0.004_054_539_4,
];
