//! Self-collision's part of a step: this substep's contacts, and the
//! tangles left alone after a body jerks the cloth through itself.

use glam::{DVec3, Vec3};

use super::untangle::{STEP, untangle};
use super::{EDGE_GAP, Layers};
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

    /// Moves the particles of the crossings [`Solver::find_tangles`] found
    /// last so that the cloth comes apart (`untangle.rs`).
    pub(in crate::solver) fn untangle(&mut self) {
        let t = self.stopwatch();
        let (dx, dy) = self.spec.spacing();
        untangle(
            &mut self.state.position,
            &self.inv_mass,
            &self.topology.triangles,
            &self.self_contacts.crossed,
            STEP * dx.min(dy),
        );
        self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
    }

    /// Leaves tangles alone (self-collision's contacts skip the particles
    /// of edges that cross a triangle, looked for at every substep) for this
    /// step and the next [`JERK_WATCH`] if a body jerks its particles: if
    /// the distance an attachment moves in this step differs from the last
    /// step's by more than [`JERK`] rest spacings (a teleport: a bar that
    /// jumps and stops; not a car that brakes, whose motion changes by
    /// millimetres a step). The cloth it drags through itself then comes
    /// apart instead of being held tangled by contacts that keep each
    /// particle's side, helped by [`Solver::untangle`].
    pub(in crate::solver) fn watch_for_jerks(&mut self, bodies: &[Pose], origin: DVec3) {
        let (dx, dy) = self.spec.spacing();
        let limit = JERK as f64 * dx.min(dy) as f64;
        // In world coordinates: the origin may carry the attachments.
        let at = |poses: &[Pose], origin: DVec3, a: &Attachment| {
            origin + poses[a.body].compose(&a.local).translation.as_dvec3()
        };
        // At the first step the cloth starts with its carriers' motion
        // (`start_with_carriers`): there is no earlier step to jerk from.
        let jerk = self.steps > 0
            && self.attachments.iter().any(|a| {
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
            // Nor are the particles bounded for the first steps: held to
            // their bounds, the free particles could not follow the jerked
            // ones.
            self.unbounded = JERK_UNBOUNDED * self.params.substeps;
        }
    }

    /// Looks for crossings at the step's start unless the cloth is known to
    /// be free of them (the path check keeps it so, but for a driven
    /// particle that went beyond its bound, or a jerk): if any, the tangled
    /// particles are left alone, exempt from their bounds and from the
    /// contacts, until they come apart.
    pub(in crate::solver) fn watch_for_crossings(&mut self) {
        if self.self_contacts.watching() {
            // Tangled particles move freely: look again once they are apart.
            self.offsets.checked = false;
            return;
        }
        if self.offsets.checked {
            return;
        }
        let tangled = !self.find_tangles().is_empty();
        self.offsets.checked = !tangled;
        if tangled {
            self.self_contacts.watch_for_tangles(self.params.substeps);
        }
    }

    /// Starts the substep's path check (`Offsets::begin`), unless a jerk
    /// leaves this substep unchecked.
    pub(in crate::solver) fn begin_offsets(&mut self) {
        if self.unbounded > 0 {
            self.unbounded -= 1;
            self.offsets.clear();
            return;
        }
        let t = self.stopwatch();
        self.offsets.begin(
            &self.state.position,
            &self.topology.triangles,
            &self.spec,
            self.self_contacts.tangled(),
        );
        self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
    }

    /// Pushes apart the edge pairs found nearer than a fraction of the
    /// thickness at the substep's start.
    pub(in crate::solver) fn keep_edges_apart(&mut self) {
        self.offsets.keep_edges_apart(
            &mut self.state.position,
            &self.inv_mass,
            EDGE_GAP * self.spec.thickness,
            self.self_contacts.tangled(),
        );
    }

    /// Leaves the particles where the update (or the sweeps, at the
    /// substep's end: `rounds`) took them if the path there from the
    /// substep's start forms no crossing, parting the pairs that approach
    /// too fast (`Offsets::path_clear`); else bounds every particle at the
    /// substep's start and brings each within its bound. At the end, where
    /// that moved a particle, the bounds are found again at the clamped
    /// state (free of crossings like the substep's start) and the particles
    /// go on from there towards where the sweeps took them, up to
    /// [`OFFSET_ROUNDS`] times: a particle held back by a near layer catches
    /// up with the rest instead of stretching its edges.
    pub(in crate::solver) fn clamp_to_offsets(&mut self, rounds: bool) {
        let rounds = if rounds { OFFSET_ROUNDS } else { 1 };
        let t = self.stopwatch();
        let exempt = self.self_contacts.tangled();
        // A pulled particle is one of the cloth's, pushed and parted by
        // its mass like any other, but the clamp leaves it where its pull
        // took it: held back to its bound a grab would barely follow.
        let pulled = self.pull.map(|p| p.particle);
        let (x, triangles) = (&mut self.state.position, &self.topology.triangles);
        if !self
            .offsets
            .path_clear(x, &self.inv_mass, triangles, &self.spec, exempt)
        {
            self.offsets.find_at_start(triangles, &self.spec, exempt);
            // Where the sweeps took the particles, to go on towards after
            // each round but the last.
            let mut target = std::mem::take(&mut self.offset_target);
            if rounds > 1 {
                target.clone_from(&self.state.position);
            }
            for round in 1..=rounds {
                let moved = self
                    .offsets
                    .clamp(&mut self.state.position, &self.inv_mass, pulled);
                if moved == 0 || round == rounds {
                    break;
                }
                self.offsets.find(
                    &self.state.position,
                    &self.topology.triangles,
                    &self.spec,
                    self.self_contacts.tangled(),
                );
                self.state.position.copy_from_slice(&target);
            }
            self.offset_target = target;
        }
        self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
    }

    /// The colliders have the last word at a substep's end: parting the
    /// layers may have moved a particle into one. A push out of a collider
    /// is a move the path check has not seen, so the path is checked again
    /// for the pairs of the particles it moved (`Offsets::path_clear_after`,
    /// parting what comes too near), and while parting moves particles the
    /// colliders push again, up to [`COLLIDER_ROUNDS`] times. A path still
    /// not clear after them (a layer squeezed between a collider and
    /// another layer) leaves the cloth no longer known to be free of
    /// crossings: they are looked for at the next step's start.
    pub(in crate::solver) fn colliders_last(&mut self, margin: f32) {
        // The state the path was cleared to, in the clamp's scratch.
        let mut cleared = std::mem::take(&mut self.offset_target);
        cleared.clone_from(&self.state.position);
        if self.project_colliders(margin) && !self.check_colliders_push(&cleared, margin) {
            self.offsets.checked = false;
        }
        self.offset_target = cleared;
    }

    /// [`Solver::colliders_last`]'s rounds after the colliders pushed a
    /// particle away from `cleared`: whether the path ends clear.
    fn check_colliders_push(&mut self, cleared: &[Vec3], margin: f32) -> bool {
        for _ in 0..COLLIDER_ROUNDS {
            let t = self.stopwatch();
            let clear = self.offsets.path_clear_after(
                &mut self.state.position,
                cleared,
                &self.inv_mass,
                &self.topology.triangles,
                &self.spec,
                self.self_contacts.tangled(),
            );
            self.charge(t, |d| &mut d.families[Family::SelfCollision].time);
            // Nothing parted: the colliders' push is where it was left.
            if clear && !self.offsets.parted {
                return true;
            }
            if !self.project_colliders(margin) {
                return clear;
            }
        }
        false
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

/// How many times a substep's end may be clamped to the offset bounds,
/// finding them again in between ([`Solver::clamp_to_offsets`]).
const OFFSET_ROUNDS: u32 = 6;

/// How many times a substep's end checks the path again after the
/// colliders pushed a particle ([`Solver::colliders_last`]).
const COLLIDER_ROUNDS: u32 = 3;

/// How many steps after a jerk self-collision leaves tangles alone.
const JERK_WATCH: u32 = 60;

/// How many steps, the jerk's included, the path check and its bounds are
/// lifted for: the free particles follow the jerked ones, and are checked
/// again (but for the tangled ones) while the tangles are undone.
const JERK_UNBOUNDED: u32 = 5;
