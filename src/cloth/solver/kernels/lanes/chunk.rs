//! A chunk's particles: their indices in lanes, gathered into lane values
//! and scattered back ([`Chunk`]), and positions held in lanes while a
//! kernel moves them more than once ([`Held`]).

use super::vectors::turn_by;
use super::{Lane, Q4, V3};
use crate::solver::kernels::{NoRecord, Particles, Recorder, shift, turn};

/// The particle indices of one role (say, every constraint's first end)
/// across a chunk of `F::N` constraints.
#[derive(Clone, Copy)]
pub(crate) struct Chunk<F: Lane> {
    idx: F::Array<usize>,
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
    /// [`turn`]).
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
