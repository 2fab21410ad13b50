//! A step: the frame and the bodies move, then each substep updates and
//! adjusts the cloth (docs/method.md §3), with the colliders and
//! self-collision's contacts; and the checks that keep a failed step from
//! leaving a broken state.

use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};

use super::adjust::{Adjust, Colliders, LayerFriction};
use super::collision::{self, Collider, Contact, Pose};
use super::diagnostics;
use super::families::{Family, Sets, Sweep};
use super::forced_rotation::ForcedRotation;
use super::frame::{Frame, FrameStep};
use super::kernels::{Particles, Shared};
use super::self_collision::Grid;
use super::update::{self, Environment, FrameMotion, Reference};
use super::{Attachment, ClothState, NonFinite, PARALLEL_MIN_PARTICLES, Solver, StepError, team};

/// The cloth as self-collision's stages read it ([`Grid`]), borrowing the
/// solver's fields alone so that its positions can be lent beside it.
macro_rules! grid {
    ($solver:expr) => {
        Grid {
            topology: &$solver.topology,
            spec: &$solver.spec,
            inv_mass: &$solver.inv_mass,
        }
    };
}

/// The colliders' push of free particles, timed when `spent` is: the
/// solver's fields it needs, borrowed apart from the positions it moves.
struct PushOut<'a> {
    colliders: &'a [Collider],
    poses: &'a [Pose],
    inv_mass: &'a [f32],
    contacts: &'a mut [Contact],
    margin: f32,
    spent: Option<Duration>,
}

impl PushOut<'_> {
    /// Pushes every free particle of `x` out of every collider; whether it
    /// moved one.
    fn push(&mut self, x: &mut [Vec3]) -> bool {
        if self.colliders.is_empty() {
            return false;
        }
        let start = self.spent.is_some().then(Instant::now);
        let (colliders, poses, margin) = (self.colliders, self.poses, self.margin);
        let moved = collision::project(x, self.inv_mass, colliders, poses, margin, self.contacts);
        if let (Some(spent), Some(start)) = (self.spent.as_mut(), start) {
            *spent += start.elapsed();
        }
        moved
    }
}

/// A [`PushOut`] of the solver's colliders at the substep's end.
macro_rules! push_out {
    ($solver:expr, $margin:expr) => {
        PushOut {
            colliders: &$solver.colliders,
            poses: &$solver.collider_to,
            inv_mass: &$solver.inv_mass,
            contacts: &mut $solver.contacts,
            margin: $margin,
            spent: $solver.diagnostics.is_some().then_some(Duration::ZERO),
        }
    };
}

impl Solver {
    /// Advances by `Δt`: the bodies move from their current poses to `bodies`.
    ///
    /// On error the state is left as it was before the step.
    pub fn step(&mut self, env: &Environment, bodies: &[Pose]) -> Result<(), StepError> {
        self.step_with(env, bodies, &mut |_| {})
    }

    /// [`Solver::step`], calling `after_substep` with the state at the end of
    /// every substep (for checks that must hold at each, as in the tests).
    pub fn step_with(
        &mut self,
        env: &Environment,
        bodies: &[Pose],
        after_substep: &mut dyn FnMut(&ClothState),
    ) -> Result<(), StepError> {
        let origin = self.frame.origin;
        self.step_in_frame(env, bodies, origin, after_substep)
    }

    /// [`Solver::step_with`], the origin moving to `origin` (world
    /// coordinates) over the step, steadily, and `bodies` measured from it
    /// there ([`super::frame`]). A scene moves the origin with what carries the
    /// cloth, so that neither where the cloth is nor how fast it is carried
    /// changes a bit of how it moves.
    pub fn step_in_frame(
        &mut self,
        env: &Environment,
        bodies: &[Pose],
        origin: DVec3,
        after_substep: &mut dyn FnMut(&ClothState),
    ) -> Result<(), StepError> {
        let step = self.steps + 1;
        if bodies.len() != self.bodies.len() {
            return Err(StepError::Bodies {
                step,
                given: bodies.len(),
                expected: self.bodies.len(),
            });
        }
        let start = self.stopwatch();
        if let Some(d) = self.diagnostics.as_deref_mut() {
            d.clear_step();
        }
        self.last_good.copy_from(&self.state);
        self.refresh_tethers();
        let substeps = self.params.substeps;
        let dt = self.params.substep_dt();
        let rot = self.forced_rotation();
        let frame = self.frame.step_to(origin, substeps, self.steps == 0);
        self.self_collision.time_stages(self.diagnostics.is_some());
        if self.self_collision_on() {
            let changes = self.attachment_motion_changes(bodies, origin);
            let (grid, x) = (grid!(self), &self.state.position);
            self.self_collision
                .start_step(grid, x, changes, self.params.substeps);
        } else {
            self.self_collision.off();
        }
        if self.steps == 0 {
            self.start_with_carriers(bodies);
        }
        for sub in 0..substeps {
            let (f0, f1) = (
                sub as f32 / substeps as f32,
                (sub + 1) as f32 / substeps as f32,
            );
            self.sub_from.clear();
            self.sub_to.clear();
            for (from, to) in self.bodies.iter().zip(bodies) {
                self.sub_from.push(from.lerp(to, f0));
                self.sub_to.push(from.lerp(to, f1));
            }
            let result = self.substep(env, dt, &rot, &frame, sub, sub + 1 == substeps);
            std::mem::swap(&mut self.last_from, &mut self.sub_from);
            if let Err((phase, particle, quantity, value)) = result {
                self.state.copy_from(&self.last_good);
                return Err(StepError::NonFinite {
                    step,
                    phase,
                    particle,
                    quantity,
                    value,
                });
            }
            after_substep(&self.state);
        }
        self.bodies_before.copy_from_slice(&self.bodies);
        self.bodies.copy_from_slice(bodies);
        self.origin_before = self.frame.origin;
        self.frame = Frame::after(&frame, origin);
        // The crossings at the step's end, for the diagnostics, whatever
        // self-collision's weight (a cloth that passes through itself is
        // shown, on or off); on, they are also its tangles.
        let crossings = self.diagnostics.is_some().then(|| {
            if self.self_collision_on() {
                let grid = grid!(self);
                self.self_collision.tangles(grid, &self.state.position)
            } else {
                self.self_crossing_points()
            }
        });
        self.time += self.params.dt as f64;
        self.steps = step;
        if self.diagnostics.is_some() {
            // The normals against the surface, for facing's violation and
            // the orientation: measured once.
            let offsets = self.normal_offsets();
            let facing = self.measured(Family::Facing).then_some(&offsets[..]);
            let violations = self.violations_from(facing);
            let d = self.diagnostics.as_deref_mut().expect("diagnostics are on");
            d.orientation = diagnostics::orientation(&offsets);
            let stages = self.self_collision.take_time();
            d.families[Family::SelfCollision].time += stages.total();
            d.self_collision = stages;
            d.self_crossings = crossings.as_ref().map(Vec::len);
            d.crossing_points = crossings.unwrap_or_default();
            for (fd, v) in d.families.iter_mut().zip(violations) {
                fd.violation = v;
            }
            d.max_strain = diagnostics::max_strain(&self.state, &self.topology);
            d.kinetic_energy = diagnostics::kinetic_energy(
                &self.state,
                &self.mass,
                dt,
                self.frame.shift.as_vec3(),
            );
            d.timings.total = start.map(|s| s.elapsed()).unwrap_or_default();
        }
        Ok(())
    }

    /// One substep. A non-finite state is checked for after the update
    /// (where a bad input shows at its own particle, before the constraints
    /// spread it) and after the adjust.
    pub(in crate::solver) fn substep(
        &mut self,
        env: &Environment,
        dt: f32,
        rot: &ForcedRotation,
        frame: &FrameStep,
        sub: u32,
        last: bool,
    ) -> Result<(), NonFinite> {
        let bounded = self.self_collision_on();
        if bounded {
            let grid = grid!(self);
            self.self_collision
                .start_substep(grid, &mut self.state.position);
        }
        let t = self.stopwatch();
        let threads = self.threads();
        update::integrate(
            &mut self.state,
            &self.inv_mass,
            &self.inv_inertia,
            &Reference {
                body_of: &self.reference_body,
                from: &self.last_from,
                to: &self.sub_from,
            },
            FrameMotion {
                before: frame.before(sub),
                kick: frame.kick(sub),
            },
            env,
            self.spec.density,
            self.params.substep_damping(),
            dt,
            threads,
        );
        self.drive_attachments();
        if let Some(pull) = &self.pull {
            let origin = frame.origin_after(sub + 1);
            pull.apply(
                &mut self.state.position,
                &self.mass,
                &self.inv_mass,
                origin,
                dt,
            );
        }
        self.check_finite("update")?;
        self.charge(t, |d| &mut d.timings.update);
        let pulled = self.pull.map(|p| p.particle);
        if bounded {
            let grid = grid!(self);
            self.self_collision
                .after_update(grid, &mut self.state.position, pulled);
        }

        self.collider_from.clear();
        self.collider_to.clear();
        let (o0, o1) = (frame.origin_after(sub), frame.origin_after(sub + 1));
        for c in &self.colliders {
            self.collider_from.push(c.pose_from(&self.sub_from, o0));
            self.collider_to.push(c.pose_from(&self.sub_to, o1));
        }
        self.contacts.fill(Contact::default());
        if bounded {
            let grid = grid!(self);
            let (x, start) = (&self.state.position, &self.state.prev_position);
            self.self_collision.find_contacts(grid, x, start, threads);
        } else {
            self.self_collision.off();
        }
        let sets = Sets {
            topology: &self.topology,
            tethers: &self.tethers,
            contacts: self.self_collision.contacts(),
        };
        self.multipliers.reset(&sets);
        let p = Particles::new(
            &mut self.state.position,
            &mut self.state.orientation,
            &self.inv_mass,
            &self.inv_inertia,
        );
        let adjust = Adjust {
            sweep: Sweep {
                sets,
                thickness: self.spec.thickness,
                p: &p,
                dt,
                rot,
                weights: &self.params.weights,
            },
            mu: self.multipliers.shared(),
            iterations: self.params.iterations,
            colliders: (!self.colliders.is_empty()).then(|| Colliders {
                shapes: &self.colliders,
                poses: &self.collider_to,
                margin: 0.5 * self.spec.thickness,
                contacts: Shared::new(&mut self.contacts),
            }),
            friction: (!self.self_collision.contacts().is_empty() && self.spec.friction > 0.0)
                .then(|| LayerFriction {
                    contacts: &self.self_collision.contacts().items,
                    start: &self.state.prev_position,
                    friction: self.spec.friction,
                }),
        };
        adjust.run(
            threads,
            self.diagnostics.as_deref_mut(),
            last.then_some(&mut self.track),
        );
        let margin = 0.5 * self.spec.thickness;
        if !self.colliders.is_empty() {
            collision::apply_friction(
                &mut self.state.position,
                &self.state.prev_position,
                &self.colliders,
                &self.collider_from,
                &self.collider_to,
                &self.contacts,
            );
            // Friction slides along the surface, which on a curved one can
            // dip a particle back in: one more push keeps every particle out.
            self.project_colliders(margin);
        }
        if bounded {
            self.end_self_collision_substep(pulled, margin);
        }
        // Turns leave quaternions unit to rounding only; renormalise once.
        for q in &mut self.state.orientation {
            *q = q.normalize();
        }
        self.check_finite("adjust")
    }

    /// How many threads the adjust phase may use: one for a cloth too small
    /// to share (a barrier costs more than its batches), else as many as
    /// rayon allows here ([`team`]).
    pub(in crate::solver) fn threads(&self) -> usize {
        if self.state.len() < PARALLEL_MIN_PARTICLES {
            1
        } else {
            team::available()
        }
    }

    /// Whether the self-collision family is on (its weight above 0).
    pub(in crate::solver) fn self_collision_on(&self) -> bool {
        self.params.weights[Family::SelfCollision] > 0.0
    }

    /// How much each attachment's motion over the step to `bodies` (and
    /// `origin`: it may carry the attachments) differs from its motion
    /// over the last step, in metres, in world coordinates; none at the
    /// first step, whose cloth starts with its carriers' motion
    /// (`start_with_carriers`): there is no earlier step to jerk from.
    fn attachment_motion_changes(&self, bodies: &[Pose], origin: DVec3) -> Vec<f64> {
        if self.steps == 0 {
            return Vec::new();
        }
        let at = |poses: &[Pose], origin: DVec3, a: &Attachment| {
            origin + poses[a.body].compose(&a.local).translation.as_dvec3()
        };
        self.attachments
            .iter()
            .map(|a| {
                let before = at(&self.bodies_before, self.origin_before, a);
                let from = at(&self.bodies, self.frame.origin, a);
                let to = at(bodies, origin, a);
                ((to - from) - (from - before)).length()
            })
            .collect()
    }

    /// Self-collision's substep end ([`SelfCollision::end_substep`]), with
    /// the colliders' push (timed with the colliders) as its last word.
    fn end_self_collision_substep(&mut self, pulled: Option<usize>, margin: f32) {
        let grid = grid!(self);
        let mut colliders = push_out!(self, margin);
        self.self_collision
            .end_substep(grid, &mut self.state.position, pulled, |x| {
                colliders.push(x)
            });
        let spent = colliders.spent;
        self.charge_spent(spent);
    }

    /// Pushes every free particle out of every collider (timed in
    /// diagnostics). Returns whether it moved a particle.
    pub(in crate::solver) fn project_colliders(&mut self, margin: f32) -> bool {
        let mut colliders = push_out!(self, margin);
        let moved = colliders.push(&mut self.state.position);
        let spent = colliders.spent;
        self.charge_spent(spent);
        moved
    }

    /// Adds a collider push's time to the diagnostics' timings.
    fn charge_spent(&mut self, spent: Option<Duration>) {
        if let (Some(d), Some(spent)) = (self.diagnostics.as_deref_mut(), spent) {
            d.timings.collisions += spent;
        }
    }

    /// Before the first step: every free particle, and the reference motion
    /// damping measures it against, starts with the motion of the body it
    /// follows (its turn; the origin carries the translation, [`frame`]),
    /// so a cloth on a body that is already moving starts in steady motion.
    /// The motion is the body's over the first substep, taken as under way.
    pub(in crate::solver) fn start_with_carriers(&mut self, bodies: &[Pose]) {
        let substeps = self.params.substeps as f32;
        // Each body's motion over a substep, `M = P(Δt/s) ∘ P(0)⁻¹`, and
        // the pose it came from, `M⁻¹ ∘ P(0)`.
        let motions: Vec<Option<Pose>> = self
            .bodies
            .iter()
            .zip(bodies)
            .map(|(from, to)| {
                (from != to).then(|| {
                    let next = from.lerp(to, 1.0 / substeps);
                    next.compose(&from.inverse())
                })
            })
            .collect();
        for (b, m) in motions.iter().enumerate() {
            if let Some(m) = m {
                self.last_from[b] = m.inverse().compose(&self.bodies[b]);
            }
        }
        for i in 0..self.state.len() {
            let Some(Some(m)) = motions.get(self.reference_body[i] as usize) else {
                continue;
            };
            let back = m.inverse();
            if self.inv_mass[i] > 0.0 {
                self.state.prev_position[i] = back.transform_point(self.state.position[i]);
            }
            if self.inv_inertia[i] > 0.0 {
                self.state.prev_orientation[i] =
                    (back.rotation * self.state.orientation[i]).normalize();
            }
        }
    }

    /// Puts every driven particle where its body holds it at the substep's end.
    pub(in crate::solver) fn drive_attachments(&mut self) {
        for a in &self.attachments {
            let target = self.sub_to[a.body].compose(&a.local);
            let i = a.particle;
            self.state.prev_position[i] = self.state.position[i];
            self.state.position[i] = target.translation;
            if a.clamp {
                self.state.prev_orientation[i] = self.state.orientation[i];
                self.state.orientation[i] = target.rotation;
            }
        }
    }

    pub(in crate::solver) fn check_finite(&self, phase: &'static str) -> Result<(), NonFinite> {
        let s = &self.state;
        for i in 0..s.len() {
            if !s.position[i].is_finite() {
                return Err((phase, i, "position", format!("{}", s.position[i])));
            }
            if !s.orientation[i].is_finite() {
                return Err((phase, i, "orientation", format!("{}", s.orientation[i])));
            }
        }
        Ok(())
    }
}
