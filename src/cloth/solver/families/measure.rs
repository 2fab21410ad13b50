//! Measuring the families' violations: over the whole cloth for the
//! figures and plots, and per particle for colouring and inspecting.

use super::violation::{Tally, Violation};
use super::{Family, PerFamily};
use crate::solver::cloth::{ClothSpec, ClothState};
use crate::solver::team;
use crate::solver::topology::{Batched, Pair, Topology, Triple};

/// The cloth a measurement reads, and how.
pub(crate) struct Measure<'a> {
    pub state: &'a ClothState,
    pub topology: &'a Topology,
    pub spec: &'a ClothSpec,
    /// Threads the tallies may use.
    pub threads: usize,
    /// Each element's angle to its surface, when already measured
    /// ([`normal_offsets`](crate::solver::diagnostics::normal_offsets)).
    pub offsets: Option<&'a [f32]>,
}

impl<'a> Measure<'a> {
    /// `state`'s violations over `topology`'s constraints, on up to
    /// `threads` threads.
    pub(crate) fn new(
        state: &'a ClothState,
        topology: &'a Topology,
        spec: &'a ClothSpec,
        threads: usize,
    ) -> Self {
        Self {
            state,
            topology,
            spec,
            threads,
            offsets: None,
        }
    }
}

/// The violation of one family over the constraints it projects (for
/// self-collision: the penetration of the pairs closer than the thickness).
pub fn violation(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
) -> Violation {
    family.violation_in(&Measure::new(state, topology, spec, 1))
}

/// Every family's violation, as [`violation`] measures each, on up to
/// `threads` threads, for the families `measured` names (0 for the others);
/// facing's is tallied from `offsets` when given (each element's angle to
/// its surface, its measure). Every set is tallied in blocks merged in
/// block order, so the figures do not depend on the threads.
pub fn violations(
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
    threads: usize,
    measured: impl Fn(Family) -> bool,
    offsets: Option<&[f32]>,
) -> PerFamily<Violation> {
    let m = Measure {
        offsets,
        ..Measure::new(state, topology, spec, threads)
    };
    PerFamily::from_fn(|family| {
        if measured(family) {
            family.violation_in(&m)
        } else {
            Violation::default()
        }
    })
}

/// Per particle, the largest violation of `family` over the constraints
/// that involve it (pairs: both ends; bend triples: all three), as in
/// [`violation`]. For colouring or labelling every particle.
pub fn particle_violation(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
) -> Vec<f32> {
    let mut out = vec![0.0f32; state.len()];
    let m = Measure::new(state, topology, spec, 1);
    family.each_violation(&m, None, &mut |i, v| {
        let slot = &mut out[i as usize];
        *slot = slot.max(v);
    });
    out
}

/// Particle `i`'s entry of [`particle_violation`], the same bit for bit,
/// from the constraints that involve `i` alone (for inspecting one
/// particle: the others are not measured).
pub fn particle_violation_at(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
    i: usize,
) -> f32 {
    let mut largest = 0.0f32;
    let m = Measure::new(state, topology, spec, 1);
    family.each_violation(&m, Some(i as u32), &mut |j, v| {
        if j as usize == i {
            largest = largest.max(v);
        }
    });
    largest
}

/// The violation `f` of every one of `items`, tallied in blocks on up to
/// `threads` threads and merged in block order.
pub(crate) fn tally<T: Copy + Sync>(
    threads: usize,
    items: &[T],
    f: impl Fn(T) -> f32 + Sync,
) -> Violation {
    const BLOCK: usize = 1024;
    let mut all = Tally::default();
    for block in team::run_blocks(threads, items.len(), BLOCK, |r| {
        let mut t = Tally::default();
        for &item in &items[r] {
            t.add(f(item));
        }
        t
    }) {
        all.merge(block);
    }
    all.violation()
}

/// Calls `put` for both ends of every pair of `set` (given `only`, of the
/// pairs that involve it) with the pair's violation `f`.
pub(crate) fn each_pair(
    set: &Batched<Pair>,
    only: Option<u32>,
    f: impl Fn(Pair) -> f32,
    put: &mut dyn FnMut(u32, f32),
) {
    for &p in set.items.iter().filter(|p| wanted(only, &[p.a, p.b])) {
        let v = f(p);
        put(p.a, v);
        put(p.b, v);
    }
}

/// [`each_pair`] for the bend triples of `set`: all three particles.
pub(crate) fn each_triple(
    set: &Batched<Triple>,
    only: Option<u32>,
    f: impl Fn(Triple) -> f32,
    put: &mut dyn FnMut(u32, f32),
) {
    for &t in set
        .items
        .iter()
        .filter(|t| wanted(only, &[t.a, t.mid, t.b]))
    {
        let v = f(t);
        put(t.a, v);
        put(t.mid, v);
        put(t.b, v);
    }
}

/// Whether a constraint of `members` is measured when only `only`'s are.
pub(crate) fn wanted(only: Option<u32>, members: &[u32]) -> bool {
    only.is_none_or(|i| members.contains(&i))
}
