//! What the solver reports about a step, on request.
//!
//! With diagnostics on, a step records, per family, the corrections `δx` and
//! `δθ` (axis × angle) it applied to each particle in its last adjust phase,
//! the largest single forced rotation, the residual violation (max and RMS),
//! and wall times. With diagnostics off none of this is computed: the
//! projections are compiled with a recorder that does nothing.
//!
//! The measurement functions here ([`violation`], [`max_strain`],
//! [`kinetic_energy`]) are plain functions of a state, used by diagnostics and
//! by tests alike.

use std::time::Duration;

use glam::Vec3;

use super::{
    cloth::ClothState,
    constraints::Recorder,
    family::{Family, PerFamily},
    topology::Topology,
};

/// Max and RMS of a family's violation over its pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Violation {
    /// Largest violation.
    pub max: f32,
    /// Root mean square of the violations.
    pub rms: f32,
}

impl Violation {
    /// Max and RMS of some violations (0 for none).
    pub fn of(values: impl Iterator<Item = f32>) -> Self {
        let (mut max, mut sum, mut n) = (0.0f32, 0.0f64, 0usize);
        for v in values {
            max = max.max(v);
            sum += (v as f64) * (v as f64);
            n += 1;
        }
        Violation {
            max,
            rms: if n == 0 {
                0.0
            } else {
                (sum / n as f64).sqrt() as f32
            },
        }
    }
}

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
    /// Edges of the cloth's mesh that cross a triangle (see
    /// [`Solver::self_crossings`](super::Solver::self_crossings)), while
    /// self-collision is on.
    pub self_crossings: Option<usize>,
    /// Wall times.
    pub timings: Timings,
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

    /// Clears per-particle corrections before an adjust phase.
    pub(crate) fn clear_corrections(&mut self) {
        if !self.corrections {
            return;
        }
        for f in self.families.iter_mut() {
            f.dx.fill(Vec3::ZERO);
            f.dtheta.fill(Vec3::ZERO);
        }
    }

    /// Clears the per-step figures before a step.
    pub(crate) fn clear_step(&mut self) {
        for f in self.families.iter_mut() {
            f.max_rotation = 0.0;
            f.time = Duration::ZERO;
        }
        self.timings = Timings::default();
    }
}

/// Records one family's corrections into its diagnostics. Forks write to
/// the same per-particle arrays (distinct particles per colour batch, see
/// `Particles`) and keep their own largest rotation until joined.
pub(crate) struct FamilyRecorder {
    dx: *mut Vec3,
    dtheta: *mut Vec3,
    len: usize,
    /// Largest single rotation seen by this recorder.
    pub max_rotation: f32,
}

// SAFETY: forks on other threads write distinct elements only (colouring);
// sharing a recorder only lets other threads fork it (copy its pointers).
unsafe impl Send for FamilyRecorder {}
unsafe impl Sync for FamilyRecorder {}

impl FamilyRecorder {
    /// A recorder writing into `fd`'s arrays (which must outlive it).
    pub(crate) fn new(fd: &mut FamilyDiagnostics) -> Self {
        Self {
            dx: fd.dx.as_mut_ptr(),
            dtheta: fd.dtheta.as_mut_ptr(),
            len: fd.dx.len().min(fd.dtheta.len()),
            max_rotation: 0.0,
        }
    }
}

impl Recorder for FamilyRecorder {
    const ON: bool = true;
    #[inline]
    fn moved(&mut self, i: usize, dx: Vec3) {
        assert!(i < self.len);
        // SAFETY: in bounds; this particle is this thread's in the batch.
        unsafe { *self.dx.add(i) += dx }
    }
    #[inline]
    fn turned(&mut self, i: usize, axis_angle: Vec3) {
        assert!(i < self.len);
        // SAFETY: in bounds; this particle is this thread's in the batch.
        unsafe { *self.dtheta.add(i) += axis_angle }
        self.max_rotation = self.max_rotation.max(axis_angle.length());
    }
    fn fork(&self) -> Self {
        Self {
            max_rotation: 0.0,
            ..*self
        }
    }
    fn join(&mut self, other: Self) {
        self.max_rotation = self.max_rotation.max(other.max_rotation);
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

/// Kinetic energy `Σ ½ m |Δx / Δt|²` of the particles with mass, for substep `dt`.
pub fn kinetic_energy(state: &ClothState, mass: &[f32], dt: f32) -> f32 {
    let mut e = 0.0f64;
    for (i, &m) in mass.iter().enumerate() {
        let v = (state.position[i] - state.prev_position[i]) / dt;
        e += 0.5 * m as f64 * v.length_squared() as f64;
    }
    e as f32
}

/// Per particle, the largest strain of its weft and warp edges, as in
/// [`max_strain`] (0 when all are compressed).
pub fn particle_strain(state: &ClothState, topology: &Topology) -> Vec<f32> {
    let x = &state.position;
    let mut out = vec![0.0f32; state.len()];
    for p in &topology.structural.items {
        let len = x[p.b as usize].distance(x[p.a as usize]);
        let s = ((len - p.rest) / p.rest).max(0.0);
        for i in [p.a as usize, p.b as usize] {
            out[i] = out[i].max(s);
        }
    }
    out
}
