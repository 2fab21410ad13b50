//! What the solver reports about a step, on request.
//!
//! With diagnostics on, a step records, per family, the corrections `δx` and
//! `δθ` (axis × angle) it applied to each particle in its last adjust phase,
//! the largest single forced rotation, the residual violation (max and RMS),
//! and wall times. With diagnostics off none of this is computed: the
//! projections are compiled with a recorder that does nothing.
//!
//! The corrections cost the kernels nothing: they are read off the
//! particles' state between sweeps (`CorrectionTrack`), in the last
//! substep only. The violations are measured by the families, on the
//! solver's threads (`families::violations`).
//!
//! The measurement functions here ([`max_strain`], [`kinetic_energy`],
//! [`particle_strain`], [`normal_offsets`]) are plain functions of a state,
//! used by diagnostics, telemetry and tests alike.

mod corrections;

use std::time::Duration;

use glam::Vec3;

pub(crate) use corrections::{CorrectionTrack, Tracking};

use super::{
    cloth::ClothState,
    families::{Family, PerFamily, Violation, facing},
    kernels::Recorder,
    kernels::lanes::{Lane, V3, WIDE_LANES},
    self_collision::StageTimes,
    team,
    topology::{Pair, Patch, Topology},
};

/// What one family did in the last adjust phase.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FamilyDiagnostics {
    /// Total translation applied to each particle.
    pub dx: Vec<Vec3>,
    /// Total rotation applied to each particle, as axis × angle (radians).
    pub dtheta: Vec<Vec3>,
    /// Largest single forced rotation, in radians (never above `Φ`).
    pub max_rotation: f32,
    /// Violation after the step.
    pub violation: Violation,
    /// Wall time spent projecting this family during the step.
    pub time: Duration,
}

/// Wall times of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// The update phase.
    pub update: Duration,
    /// Collider projection and friction.
    pub collisions: Duration,
    /// The whole step.
    pub total: Duration,
}

/// Everything a step reports when diagnostics are on.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// Per family.
    pub families: PerFamily<FamilyDiagnostics>,
    /// Whether the per-particle corrections (`dx`, `dtheta`, `max_rotation`)
    /// are recorded; without them the figures and timings still are, at
    /// less cost.
    pub corrections: bool,
    /// Largest strain of a weft or warp edge.
    pub max_strain: f32,
    /// Kinetic energy of the free particles, in joules.
    pub kinetic_energy: f32,
    /// How well the elements' normals follow the surface after the step.
    pub orientation: Orientation,
    /// Edges of the cloth's mesh that cross a triangle (see
    /// [`Solver::self_crossings`](super::Solver::self_crossings)) at the
    /// step's end, whatever self-collision's weight.
    pub self_crossings: Option<usize>,
    /// Where those edges pass through their triangles, one point each
    /// (measured from the solver's origin).
    pub crossing_points: Vec<Vec3>,
    /// Wall times.
    pub timings: Timings,
    /// Where self-collision's time went, stage by stage (part of its
    /// family's `time`).
    pub self_collision: StageTimes,
}

impl Diagnostics {
    /// Empty diagnostics for `n` particles.
    pub fn new(n: usize) -> Self {
        let mut d = Self {
            corrections: true,
            ..Self::default()
        };
        for f in d.families.iter_mut() {
            f.dx = vec![Vec3::ZERO; n];
            f.dtheta = vec![Vec3::ZERO; n];
        }
        d
    }

    /// One family's diagnostics.
    pub fn family(&self, family: Family) -> &FamilyDiagnostics {
        &self.families[family]
    }

    /// Clears the per-step figures before a step.
    pub(crate) fn clear_step(&mut self) {
        for f in self.families.iter_mut() {
            f.max_rotation = 0.0;
            f.time = Duration::ZERO;
        }
        self.timings = Timings::default();
        self.self_collision = StageTimes::default();
    }
}

/// Records the largest forced rotation a family applies, as its square
/// (lane by lane for the kernels that turn a chunk's particles at once); one
/// per thread, joined after the phase.
#[derive(Clone, Copy, Default)]
pub(crate) struct LargestTurn {
    squared: f32,
    lanes: [f32; WIDE_LANES],
}

impl LargestTurn {
    /// The largest rotation recorded, in radians.
    pub(crate) fn radians(&self) -> f32 {
        let lanes = self.lanes.into_iter().fold(0.0, f32::max);
        self.squared.max(lanes).sqrt()
    }
}

impl Recorder for LargestTurn {
    const ON: bool = true;
    #[inline]
    fn turned(&mut self, omega: Vec3) {
        self.squared = self.squared.max(omega.length_squared());
    }
    // Always inlined, so that in the AVX2 copy of a kernel its lanes are
    // AVX instructions, not calls (`kernels/avx.rs`).
    #[inline(always)]
    fn turned_lanes<F: Lane>(&mut self, omega: V3<F>, mask: F) {
        let squared = mask.select(omega.length_squared(), F::ZERO);
        let lanes = F::chunk_mut(&mut self.lanes[..F::N]);
        *lanes = F::new(*lanes).max(squared).to_array();
    }
    fn fork(&self) -> Self {
        Self::default()
    }
    fn join(&mut self, other: Self) {
        self.squared = self.squared.max(other.squared);
        self.lanes = std::array::from_fn(|k| self.lanes[k].max(other.lanes[k]));
    }
}

/// The largest strain (elongation `(|s| − L) / L`, 0 when compressed) of a
/// weft or warp edge. Compression is left out: cloth buckles rather than
/// compress, so a folded edge is not a stretched one.
pub fn max_strain(state: &ClothState, topology: &Topology) -> f32 {
    let x = &state.position;
    topology.structural.items.iter().fold(0.0, |m, p| {
        let len = x[p.b as usize].distance(x[p.a as usize]);
        m.max((len - p.rest) / p.rest)
    })
}

/// Kinetic energy `Σ ½ m |(Δx + D) / Δt|²` of the particles with mass, for
/// substep `dt`, in world terms: `D` (`frame`) is how far the floating
/// origin moved in the substep ([`super::frame`]).
pub fn kinetic_energy(state: &ClothState, mass: &[f32], dt: f32, frame: Vec3) -> f32 {
    let mut e = 0.0f64;
    for (i, &m) in mass.iter().enumerate() {
        let v = (state.position[i] - state.prev_position[i] + frame) / dt;
        e += 0.5 * m as f64 * v.length_squared() as f64;
    }
    e as f32
}

/// Per particle, the largest strain of its weft and warp edges, as in
/// [`max_strain`] (0 when all are compressed).
pub fn particle_strain(state: &ClothState, topology: &Topology) -> Vec<f32> {
    let mut out = vec![0.0f32; state.len()];
    for (p, s) in edge_strains(state, topology, None) {
        for i in [p.a as usize, p.b as usize] {
            out[i] = out[i].max(s);
        }
    }
    out
}

/// Particle `i`'s entry of [`particle_strain`], the same bit for bit, from
/// its own edges alone (for inspecting one particle).
pub fn particle_strain_at(state: &ClothState, topology: &Topology, i: usize) -> f32 {
    edge_strains(state, topology, Some(i as u32)).fold(0.0, |m, (_, s)| m.max(s))
}

/// Each weft and warp edge with its strain (0 when compressed); given
/// `only`, the edges of that particle alone.
fn edge_strains<'a>(
    state: &'a ClothState,
    topology: &'a Topology,
    only: Option<u32>,
) -> impl Iterator<Item = (&'a Pair, f32)> {
    let x = &state.position;
    let edges = topology.structural.items.iter();
    edges
        .filter(move |p| only.is_none_or(|i| p.a == i || p.b == i))
        .map(|p| {
            let len = x[p.b as usize].distance(x[p.a as usize]);
            (p, ((len - p.rest) / p.rest).max(0.0))
        })
}

/// Per element, the angle in `[0, π]` between its normal `n` and the normal
/// of the surface its neighbours make,
///
/// ```text
/// g = (x(i+1, j) − x(i−1, j)) × (x(i, j+1) − x(i, j−1))
/// ```
///
/// (one-sided at the border; [`Patch::surface_normal`]), which faces the way
/// every element faced at rest: facing's violation, measured whatever its
/// weight. Planarity cannot tell `n` from `−n`, so an angle above 90° is an
/// element facing the other way. 0 where `g` vanishes (a particle whose
/// neighbours coincide).
/// Measured on up to `threads` threads.
pub fn normal_offsets(state: &ClothState, topology: &Topology, threads: usize) -> Vec<f32> {
    const BLOCK: usize = 1024;
    let patches = &topology.patches.items;
    team::run_blocks(threads, patches.len(), BLOCK, |r| {
        let offsets = patches[r].iter().map(|&p| normal_offset(state, p));
        offsets.collect::<Vec<_>>()
    })
    .concat()
}

/// The entry of [`normal_offsets`] for `patch`'s particle (for inspecting
/// one particle).
pub fn normal_offset(state: &ClothState, patch: Patch) -> f32 {
    facing::violation(&state.position, |i| state.normal(i), patch)
}

/// How well the elements' normals follow the surface: see [`orientation`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Orientation {
    /// The share of elements facing against the surface (offset above 90°),
    /// in `[0, 1]`.
    pub flipped: f32,
    /// The root mean square of each normal's angle to the surface's normal
    /// line, whichever way it faces (`min(a, π − a)` of an offset `a`), in
    /// radians: how far the normals stray, apart from turning over.
    pub offset_rms: f32,
}

/// Sums up [`normal_offsets`].
pub fn orientation(offsets: &[f32]) -> Orientation {
    if offsets.is_empty() {
        return Orientation::default();
    }
    let flipped = offsets
        .iter()
        .filter(|&&a| a > std::f32::consts::FRAC_PI_2)
        .count();
    let squares: f64 = offsets
        .iter()
        .map(|&a| a.min(std::f32::consts::PI - a) as f64)
        .map(|a| a * a)
        .sum();
    Orientation {
        flipped: flipped as f32 / offsets.len() as f32,
        offset_rms: (squares / offsets.len() as f64).sqrt() as f32,
    }
}
