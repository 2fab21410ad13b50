//! What a solver measures of its cloth, for the figures, plots, colours
//! and the particle inspector: the families' violations, strain, energy,
//! the normals against the surface and the crossings. Every measure reads
//! the state and changes nothing; the ones a family owns are measured only
//! while it is on when it says so ([`Solver::measured`]).

use glam::Vec3;

use super::diagnostics::{self, Orientation};
use super::families::Violation;
use super::families::{self, Family, PerFamily};
use super::{Solver, self_collision, team};

impl Solver {
    /// The current violation of one family.
    pub fn violation(&self, family: Family) -> Violation {
        families::violation(family, &self.state, &self.topology, &self.spec)
    }

    /// The violations a run's figures report: as [`Solver::violation`] for
    /// every family, but self-collision's and facing's only while the family
    /// is on ([`Family::measured_only_while_on`]; off, they report 0).
    /// Measured on the solver's threads.
    pub fn measured_violations(&self) -> PerFamily<Violation> {
        let offsets = self.measured(Family::Facing).then(|| self.normal_offsets());
        self.violations_from(offsets.as_deref())
    }

    /// [`Solver::measured_violations`], facing's from `offsets` (each
    /// element's [`Solver::normal_offsets`], given while facing is on).
    pub(in crate::solver) fn violations_from(
        &self,
        offsets: Option<&[f32]>,
    ) -> PerFamily<Violation> {
        families::violations(
            &self.state,
            &self.topology,
            &self.spec,
            self.threads(),
            |f| self.measured(f),
            offsets,
        )
    }

    /// Per particle, the largest violation of `family` among the
    /// constraints that involve it; self-collision's and facing's only while
    /// the family is on (0 otherwise), as in [`Solver::measured_violations`].
    pub fn particle_violation(&self, family: Family) -> Vec<f32> {
        if !self.measured(family) {
            return vec![0.0; self.state.len()];
        }
        families::particle_violation(family, &self.state, &self.topology, &self.spec)
    }

    /// Particle `i`'s entry of [`Solver::particle_violation`], measured on
    /// the constraints that involve it alone: what inspecting one particle
    /// needs, at a fraction of the cost.
    pub fn particle_violation_at(&self, family: Family, i: usize) -> f32 {
        if !self.measured(family) {
            return 0.0;
        }
        families::particle_violation_at(family, &self.state, &self.topology, &self.spec, i)
    }

    /// Per particle, the largest strain of its weft and warp edges.
    pub fn particle_strain(&self) -> Vec<f32> {
        diagnostics::particle_strain(&self.state, &self.topology)
    }

    /// Particle `i`'s entry of [`Solver::particle_strain`], from its own
    /// edges alone.
    pub fn particle_strain_at(&self, i: usize) -> f32 {
        diagnostics::particle_strain_at(&self.state, &self.topology, i)
    }

    /// Per element, the angle between its normal and the surface's
    /// ([`diagnostics::normal_offsets`]; above 90°: facing the other way).
    pub fn normal_offsets(&self) -> Vec<f32> {
        diagnostics::normal_offsets(&self.state, &self.topology, self.threads())
    }

    /// Particle `i`'s entry of [`Solver::normal_offsets`], on its own.
    pub fn normal_offset_at(&self, i: usize) -> f32 {
        diagnostics::normal_offset(&self.state, self.topology.patches.items[i])
    }

    /// How well the elements' normals follow the surface: the share facing
    /// the other way, and the RMS angle off the surface's normal line
    /// ([`diagnostics::orientation`]).
    pub fn orientation(&self) -> Orientation {
        diagnostics::orientation(&self.normal_offsets())
    }

    /// How many edges of the cloth's mesh cross a triangle they share no
    /// particle with: 0 while the cloth does not pass through itself.
    pub fn self_crossings(&self) -> usize {
        self.self_crossing_points().len()
    }

    /// Where the edges [`Solver::self_crossings`] counts pass through their
    /// triangles, one point each, found as it counts them.
    pub fn self_crossing_points(&self) -> Vec<Vec3> {
        // On every thread there is, whatever the cloth's size: the shares
        // are independent and joined in order.
        self_collision::crossing_points(
            &self.state.position,
            &self.topology.triangles,
            &self.spec,
            team::available(),
        )
    }

    /// The largest strain of a weft or warp edge.
    pub fn max_strain(&self) -> f32 {
        diagnostics::max_strain(&self.state, &self.topology)
    }

    /// The kinetic energy of the free particles, in joules.
    pub fn kinetic_energy(&self) -> f32 {
        diagnostics::kinetic_energy(
            &self.state,
            &self.mass,
            self.params.substep_dt(),
            self.frame.shift.as_vec3(),
        )
    }

    /// Whether `family`'s violation is measured: always, or for the
    /// families measured only while on, while its weight is above 0.
    pub(in crate::solver) fn measured(&self, family: Family) -> bool {
        !family.measured_only_while_on() || self.params.weights[family] > 0.0
    }
}
