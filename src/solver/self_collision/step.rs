//! Self-collision's part of a step: this substep's contacts, and the
//! tangles left alone after a body jerks the cloth through itself.

use glam::{DVec3, Vec3};

use super::Layers;
use crate::solver::collision::Pose;
use crate::solver::{Attachment, Family, Solver};

impl Solver {
    /// Finds which particles are tangled now (self-collision leaves them to
    /// the other families until they come apart), and returns where the
    /// (edge, triangle) pairs cross. Timed with the self-collision family.
    pub(in crate::solver) fn find_tangles(&mut self) -> Vec<Vec3> {
        let t = self.stopwatch();
        let crossings = self.self_contacts.find_tangles(
            &self.state.position,
            &self.topology.triangles,
            &self.spec,
        );
        self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
        crossings
    }

    /// Leaves tangles alone (self-collision's contacts skip the particles
    /// of edges that cross a triangle, looked for at every substep) for this
    /// step and the next [`JERK_WATCH`] if a body jerks its particles: if
    /// the distance an attachment moves in this step differs from the last
    /// step's by more than [`JERK`] rest spacings (a teleport: a bar that
    /// jumps and stops; not a car that brakes, whose motion changes by
    /// millimetres a step). The cloth it drags through itself then comes
    /// apart instead of being held tangled by contacts that keep each
    /// particle's side.
    pub(in crate::solver) fn watch_for_jerks(&mut self, bodies: &[Pose], origin: DVec3) {
        let (dx, dy) = self.spec.spacing();
        let limit = JERK as f64 * dx.min(dy) as f64;
        // In world coordinates: the origin may carry the attachments.
        let at = |poses: &[Pose], origin: DVec3, a: &Attachment| {
            origin + poses[a.body].compose(&a.local).translation.as_dvec3()
        };
        let jerk = self.attachments.iter().any(|a| {
            let (before, from, to) = (
                at(&self.bodies_before, self.origin_before, a),
                at(&self.bodies, self.frame.origin, a),
                at(bodies, origin, a),
            );
            !((to - from) - (from - before)).length().le(&limit)
        });
        if jerk {
            self.self_contacts
                .watch_for_tangles((JERK_WATCH + 1) * self.params.substeps);
        }
    }

    /// Whether the self-collision family is on (its weight above 0).
    pub(in crate::solver) fn self_collision_on(&self) -> bool {
        self.params.weights[Family::SelfCollision] > 0.0
    }

    /// Finds this substep's self-contacts over the predicted positions (timed
    /// with the self-collision family in diagnostics).
    pub(in crate::solver) fn find_self_contacts(&mut self) {
        let t = self.stopwatch();
        let (dx, dy) = self.spec.spacing();
        let threads = self.threads();
        self.self_contacts.build(
            &Layers {
                now: &self.state.position,
                start: &self.state.prev_position,
                inv_mass: &self.inv_mass,
            },
            &self.topology,
            &self.spec,
            self.spec.thickness + SELF_CONTACT_SLACK * dx.min(dy),
            threads,
        );
        self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
    }
}

/// How much farther than the thickness, in rest spacings, a particle and a
/// triangle may be at the predicted positions to be a self-contact of the
/// substep: room for the adjust phase's own corrections to bring them
/// together.
const SELF_CONTACT_SLACK: f32 = 0.25;

/// How much, in rest spacings, an attachment's motion may change from one
/// step to the next before self-collision leaves tangles alone
/// ([`Solver::watch_for_jerks`]).
const JERK: f32 = 2.0;

/// How many steps after a jerk self-collision leaves tangles alone.
const JERK_WATCH: u32 = 60;
