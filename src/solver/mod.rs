//! The oriented-particle cloth solver of Bae, Baek, Lee and Ryu.
//!
//! A cloth is a grid of small surface elements: particles with mass, inertia
//! and an orientation whose local +Z is the element's normal ([`cloth`]).
//! A step of length `Δt` runs `substeps` substeps of `Δt / substeps`, each in
//! two phases:
//!
//! 1. **update** ([`update`]): every particle moves on its own by Störmer
//!    integration with damping `k`, under gravity and wind on its face;
//!    driven particles follow their attachment exactly.
//! 2. **adjust** ([`constraints`]): `iterations` sweeps over five families of
//!    geometric constraints between neighbours, each weighted by its `λ`:
//!    planarity, normality (with shear), curvature, facing (weft's own: each
//!    element turns to face the way the surface its neighbours make does,
//!    [`constraints::facing`]), then stretch (the length limit has the last
//!    word). Families are projected one after another
//!    (Gauss–Seidel), so a particle's correction combines what each asks.
//!    Each weight is a compliance (XPBD), so its effect does not depend on
//!    iterations, substeps or resolution ([`params::Weights`]); rotations
//!    are shaped by Eq. 3 ([`forced_rotation`]). A fifth family,
//!    self-collision (off by default), keeps the cloth's layers apart
//!    ([`constraints::self_collision`]). Colliders are projected after each
//!    sweep, friction once at the end ([`collision`]).
//!
//! Constraints are solved in graph-colour batches ([`topology`]): the
//! constraints of one colour share no particle, so large batches are split
//! across rayon's threads and the result is bit-identical for any number of
//! threads. The solver knows nothing of telemetry or
//! UI; [`diagnostics`] exposes what they need.
//!
//! ```
//! use weft::solver::{ClothSpec, Environment, Params, Pose, Solver};
//!
//! let spec = ClothSpec { weft: 8, warp: 8, ..ClothSpec::default() };
//! let mut solver = Solver::new(spec, Params::default(), &[Pose::IDENTITY]).unwrap();
//! solver.attach(spec.index(0, 7), 0);
//! solver.attach(spec.index(7, 7), 0);
//! for _ in 0..60 {
//!     solver.step(&Environment::default(), &[Pose::IDENTITY]).unwrap();
//! }
//! assert!(solver.state().position[0].z < -0.1); // the free corner fell
//! ```

mod adjust;
mod broad_phase;
pub mod cloth;
pub mod collision;
pub mod constraints;
pub mod diagnostics;
pub mod family;
pub mod forced_rotation;
pub mod frame;
pub mod params;
pub mod portable;
pub mod pull;
mod team;
pub mod topology;
pub mod update;

use std::time::Instant;

pub use cloth::{ClothSpec, ClothState};
pub use collision::{Collider, Pose, Shape};
pub use diagnostics::{Diagnostics, Orientation, Violation};
pub use family::{Family, PerFamily, STRETCH_PASSES};
pub use forced_rotation::ForcedRotation;
pub use frame::Frame;
pub use params::{
    ParamError, Params, REFERENCE_COMPLIANCE, Range, RangeError, Weights, Width, compliance_factor,
};
pub use pull::Pull;
pub use topology::Topology;
pub use update::Environment;

use glam::{DVec3, Vec3};

use adjust::{Adjust, Colliders};
use collision::Contact;
use constraints::self_collision::{self, Layers, SelfContacts};
use constraints::{Particles, Shared, stretch};
use diagnostics::CorrectionTrack;
use family::{Compliance, Multipliers, Sweep};
use frame::FrameStep;
use update::{FREE, FrameMotion, Reference};

/// A particle that follows a body exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attachment {
    /// The driven particle.
    pub particle: usize,
    /// The body it follows.
    pub body: usize,
    /// Its pose in the body's frame.
    pub local: Pose,
    /// Whether the body also drives its orientation (a clamp, as a sewn
    /// seam); otherwise it turns freely about the point (a pin, as a flag's
    /// grommets on a pole).
    pub clamp: bool,
}

/// A step that could not be completed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The state turned non-finite; the last good state was kept.
    #[error(
        "step {step} ({phase} phase): particle {particle} has a non-finite {quantity} {value}; the last good state was kept"
    )]
    NonFinite {
        /// Number of the failed step (the first step is 1).
        step: u64,
        /// `update` or `adjust`: where it was first seen.
        phase: &'static str,
        /// The first particle found non-finite.
        particle: usize,
        /// `position` or `orientation`.
        quantity: &'static str,
        /// The offending value, as text.
        value: String,
    },
    /// The step was given the wrong number of body poses.
    #[error("step {step}: {given} body poses given, the scene has {expected}")]
    Bodies {
        /// Number of the failed step.
        step: u64,
        /// Poses given.
        given: usize,
        /// Poses expected.
        expected: usize,
    },
}

/// Errors building a solver.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SetupError {
    /// A parameter or cloth property is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// An attachment or collider names a body that does not exist.
    #[error("{what} refers to body {body}, but there are {bodies} bodies")]
    NoSuchBody {
        /// What refers to it.
        what: String,
        /// The body index.
        body: usize,
        /// The number of bodies.
        bodies: usize,
    },
    /// An attachment names a particle outside the cloth.
    #[error("attachment refers to particle {particle}, but the cloth has {particles}")]
    NoSuchParticle {
        /// The particle index.
        particle: usize,
        /// The number of particles.
        particles: usize,
    },
}

/// A cloth and everything needed to step it.
#[derive(Clone, Debug)]
pub struct Solver {
    spec: ClothSpec,
    params: Params,
    topology: Topology,
    state: ClothState,
    last_good: ClothState,
    mass: Vec<f32>,
    inv_mass: Vec<f32>,
    inv_inertia: Vec<f32>,
    attachments: Vec<Attachment>,
    colliders: Vec<Collider>,
    bodies: Vec<Pose>,
    tethers: stretch::Tethers,
    /// Whether the attachments changed since the tethers were built.
    tethers_stale: bool,
    /// Per particle, the body damping measures its motion against.
    reference_body: Vec<u32>,
    multipliers: Multipliers,
    self_contacts: SelfContacts,
    rest_position: Vec<Vec3>,
    // Scratch, kept to avoid allocating per step.
    sub_from: Vec<Pose>,
    sub_to: Vec<Pose>,
    /// The bodies' poses at the start of the last substep (its end is `sub_from`).
    last_from: Vec<Pose>,
    /// The bodies' poses a step before `bodies` (to tell a jerk).
    bodies_before: Vec<Pose>,
    collider_from: Vec<Pose>,
    collider_to: Vec<Pose>,
    contacts: Vec<Contact>,
    /// The floating origin every position is measured from ([`frame`]).
    frame: Frame,
    /// The origin a step before `frame` (to tell a jerk).
    origin_before: DVec3,
    /// A particle pulled towards a point ([`pull`]), if any.
    pull: Option<Pull>,
    time: f64,
    steps: u64,
    diagnostics: Option<Box<Diagnostics>>,
    /// Scratch for reading the corrections off the state (diagnostics).
    track: CorrectionTrack,
}

impl Solver {
    /// A cloth at rest in the layout of `spec`, with bodies at `bodies`.
    pub fn new(spec: ClothSpec, params: Params, bodies: &[Pose]) -> Result<Self, SetupError> {
        spec.validate()?;
        params.validate()?;
        let n = spec.len();
        let state = ClothState::at_rest(&spec);
        let m = spec.particle_mass();
        Ok(Self {
            topology: Topology::grid(&spec),
            mass: vec![m; n],
            inv_mass: vec![1.0 / m; n],
            inv_inertia: vec![1.0 / spec.particle_inertia(); n],
            attachments: Vec::new(),
            colliders: Vec::new(),
            bodies: bodies.to_vec(),
            tethers: stretch::Tethers::default(),
            tethers_stale: false,
            reference_body: vec![FREE; n],
            multipliers: Multipliers::default(),
            self_contacts: SelfContacts::default(),
            rest_position: (0..spec.warp)
                .flat_map(|j| (0..spec.weft).map(move |i| spec.rest_position(i, j)))
                .collect(),
            last_good: state.clone(),
            sub_from: Vec::with_capacity(bodies.len()),
            sub_to: Vec::with_capacity(bodies.len()),
            last_from: bodies.to_vec(),
            bodies_before: bodies.to_vec(),
            collider_from: Vec::new(),
            collider_to: Vec::new(),
            contacts: vec![Contact::default(); n],
            state,
            frame: Frame::default(),
            origin_before: DVec3::ZERO,
            pull: None,
            time: 0.0,
            steps: 0,
            diagnostics: None,
            track: CorrectionTrack::default(),
            spec,
            params,
        })
    }

    /// Clamps `particle` to `body` from now on (position and orientation),
    /// keeping its current offset.
    ///
    /// # Panics
    /// If the particle or body does not exist; use [`Solver::try_attach`] for input.
    pub fn attach(&mut self, particle: usize, body: usize) {
        self.try_attach(particle, body, true)
            .expect("valid attachment");
    }

    /// Drives `particle` by `body` from now on, keeping its current offset;
    /// with `clamp`, its orientation too, else it turns freely (a pin).
    pub fn try_attach(
        &mut self,
        particle: usize,
        body: usize,
        clamp: bool,
    ) -> Result<(), SetupError> {
        if particle >= self.state.len() {
            return Err(SetupError::NoSuchParticle {
                particle,
                particles: self.state.len(),
            });
        }
        let pose = *self
            .bodies
            .get(body)
            .ok_or_else(|| SetupError::NoSuchBody {
                what: format!("attachment of particle {particle}"),
                body,
                bodies: self.bodies.len(),
            })?;
        let world = Pose::new(
            self.state.position[particle],
            self.state.orientation[particle],
        );
        let local = Pose::new(
            pose.inverse_transform_point(world.translation),
            (pose.rotation.conjugate() * world.rotation).normalize(),
        );
        self.attachments.retain(|a| a.particle != particle);
        self.attachments.push(Attachment {
            particle,
            body,
            local,
            clamp,
        });
        self.mass[particle] = 0.0;
        self.inv_mass[particle] = 0.0;
        self.inv_inertia[particle] = if clamp {
            0.0
        } else {
            1.0 / self.spec.particle_inertia()
        };
        self.tethers_stale = true;
        Ok(())
    }

    /// Adds a collider.
    pub fn add_collider(&mut self, collider: Collider) -> Result<(), SetupError> {
        if let Some(b) = collider.body
            && b >= self.bodies.len()
        {
            return Err(SetupError::NoSuchBody {
                what: format!("collider {}", self.colliders.len()),
                body: b,
                bodies: self.bodies.len(),
            });
        }
        params::Range::new(0.0, 10.0)
            .of("μ")
            .check("collider.friction", collider.friction)?;
        self.colliders.push(collider);
        Ok(())
    }

    /// Turns diagnostics on or off. Off, the solver computes none of them.
    pub fn set_diagnostics(&mut self, on: bool) {
        match (on, self.diagnostics.is_some()) {
            (true, false) => self.diagnostics = Some(Box::new(Diagnostics::new(self.state.len()))),
            (false, true) => self.diagnostics = None,
            _ => {}
        }
    }

    /// Whether diagnostics record every particle's corrections (on by
    /// default). Off, they keep only the figures and timings, which is all
    /// scalar telemetry needs. No effect while diagnostics are off.
    pub fn record_corrections(&mut self, on: bool) {
        if let Some(d) = self.diagnostics.as_deref_mut() {
            d.corrections = on;
        }
    }

    /// The last step's diagnostics, when on.
    pub fn diagnostics(&self) -> Option<&Diagnostics> {
        self.diagnostics.as_deref()
    }

    /// Replaces the parameters, after validating them; they apply from the next step.
    pub fn set_params(&mut self, params: Params) -> Result<(), ParamError> {
        params.validate()?;
        self.params = params;
        Ok(())
    }

    /// Pulls a particle towards a point from the next step on, or lets go
    /// (`None`), after checking it against the cloth ([`pull`]).
    pub fn set_pull(&mut self, pull: Option<Pull>) -> Result<(), ParamError> {
        if let Some(p) = &pull {
            p.validate(self.state.len())?;
        }
        self.pull = pull;
        Ok(())
    }

    /// The pull in force, if any.
    pub fn pull(&self) -> Option<Pull> {
        self.pull
    }

    /// The parameters in force.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The cloth's layout and material.
    pub fn spec(&self) -> &ClothSpec {
        &self.spec
    }

    /// The constraint topology.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The current state.
    pub fn state(&self) -> &ClothState {
        &self.state
    }

    /// Mutable state, to set up experiments (perturbations, initial velocity).
    pub fn state_mut(&mut self) -> &mut ClothState {
        &mut self.state
    }

    /// Mass of each particle (0 for driven particles).
    pub fn masses(&self) -> &[f32] {
        &self.mass
    }

    /// The attachments.
    pub fn attachments(&self) -> &[Attachment] {
        &self.attachments
    }

    /// The colliders.
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// The body poses at the current time.
    pub fn bodies(&self) -> &[Pose] {
        &self.bodies
    }

    /// The floating origin every position is measured from, and how it
    /// moved in the last step ([`frame`]).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Measures every position from `frame.origin` (world coordinates)
    /// from now on, the origin taken as moving by `frame.shift` a substep:
    /// the cloth, its previous positions and the bodies' poses are taken
    /// as measured from it already; colliders without a body stay where
    /// they are in the world. For setting a scene up (before the first
    /// step, the shift is the next step's: a cloth starts moving with its
    /// origin), or an experiment.
    pub fn set_frame(&mut self, frame: Frame) {
        self.frame = frame;
        self.origin_before = frame.origin - frame.shift * self.params.substeps as f64;
    }

    /// Simulated time, in seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The forced-rotation function (Eq. 3) in force.
    pub fn forced_rotation(&self) -> ForcedRotation {
        ForcedRotation {
            phi: self.params.phi,
            h: self.params.width(),
        }
    }

    /// Builds the tethers and each particle's reference body from the
    /// attachments, once after they change (not on every attach).
    fn refresh_tethers(&mut self) {
        if !self.tethers_stale {
            return;
        }
        self.tethers_stale = false;
        let driven: Vec<usize> = self.attachments.iter().map(|a| a.particle).collect();
        let (dx, dy) = self.spec.spacing();
        self.tethers = stretch::tethers(&self.rest_position, &driven, dx.min(dy));
        self.reference_body.fill(FREE);
        for a in &self.attachments {
            self.reference_body[a.particle] = a.body as u32;
        }
        // The first batch holds each particle's nearest anchor.
        for t in &self.tethers.items[self.tethers.batches[0].clone()] {
            self.reference_body[t.particle as usize] = self.reference_body[t.anchor as usize];
        }
    }

    /// The current violation of one family.
    pub fn violation(&self, family: Family) -> Violation {
        family::violation(family, &self.state, &self.topology, &self.spec)
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
    fn violations_from(&self, offsets: Option<&[f32]>) -> PerFamily<Violation> {
        family::violations(
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
        family::particle_violation(family, &self.state, &self.topology, &self.spec)
    }

    /// Particle `i`'s entry of [`Solver::particle_violation`], measured on
    /// the constraints that involve it alone: what inspecting one particle
    /// needs, at a fraction of the cost.
    pub fn particle_violation_at(&self, family: Family, i: usize) -> f32 {
        if !self.measured(family) {
            return 0.0;
        }
        family::particle_violation_at(family, &self.state, &self.topology, &self.spec, i)
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
    /// there ([`frame`]). A scene moves the origin with what carries the
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
        let start = self.diagnostics.is_some().then(Instant::now);
        if let Some(d) = self.diagnostics.as_deref_mut() {
            d.clear_step();
        }
        self.last_good.copy_from(&self.state);
        self.refresh_tethers();
        let substeps = self.params.substeps;
        let dt = self.params.substep_dt();
        let rot = self.forced_rotation();
        let frame = self.frame.step_to(origin, substeps, self.steps == 0);
        if self.self_collision_on() {
            self.watch_for_jerks(bodies, origin);
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
                self.find_tangles()
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
    fn substep(
        &mut self,
        env: &Environment,
        dt: f32,
        rot: &ForcedRotation,
        frame: &FrameStep,
        sub: u32,
        last: bool,
    ) -> Result<(), NonFinite> {
        if self.self_collision_on() && self.self_contacts.leave_tangles_this_substep() {
            self.find_tangles();
        }
        let t = self.diagnostics.is_some().then(Instant::now);
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
        if let (Some(d), Some(t)) = (self.diagnostics.as_deref_mut(), t) {
            d.timings.update += t.elapsed();
        }

        self.collider_from.clear();
        self.collider_to.clear();
        let (o0, o1) = (frame.origin_after(sub), frame.origin_after(sub + 1));
        for c in &self.colliders {
            self.collider_from.push(c.pose_from(&self.sub_from, o0));
            self.collider_to.push(c.pose_from(&self.sub_to, o1));
        }
        self.contacts.fill(Contact::default());
        if self.self_collision_on() {
            self.find_self_contacts();
        } else {
            self.self_contacts.clear();
        }
        self.multipliers.reset(
            &self.topology,
            self.tethers.items.len(),
            self.self_contacts.set.len(),
        );
        let compliance = Compliance::new(&self.params.weights, dt);
        let p = Particles::new(
            &mut self.state.position,
            &mut self.state.orientation,
            &self.inv_mass,
            &self.inv_inertia,
        );
        let adjust = Adjust {
            sweep: Sweep {
                topology: &self.topology,
                tethers: &self.tethers,
                contacts: &self.self_contacts.set,
                thickness: self.spec.thickness,
                p: &p,
                k: &compliance,
                rot,
            },
            mu: self.multipliers.shared(),
            weights: &self.params.weights,
            iterations: self.params.iterations,
            colliders: (!self.colliders.is_empty()).then(|| Colliders {
                shapes: &self.colliders,
                poses: &self.collider_to,
                margin: 0.5 * self.spec.thickness,
                contacts: Shared::new(&mut self.contacts),
            }),
        };
        adjust.run(
            threads,
            self.diagnostics.as_deref_mut(),
            last.then_some(&mut self.track),
        );
        if !self.self_contacts.set.is_empty() {
            self_collision::apply_friction(
                &mut self.state.position,
                &self.state.prev_position,
                &self.inv_mass,
                &self.self_contacts.set.items,
                &self.multipliers.self_contact,
                self.spec.friction,
            );
        }
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
        // Turns leave quaternions unit to rounding only; renormalise once.
        for q in &mut self.state.orientation {
            *q = q.normalize();
        }
        self.check_finite("adjust")
    }

    /// Finds which particles are tangled now (self-collision leaves them to
    /// the other families until they come apart), and returns where the
    /// (edge, triangle) pairs cross. Timed with the self-collision family.
    fn find_tangles(&mut self) -> Vec<Vec3> {
        let t = self.diagnostics.is_some().then(Instant::now);
        let crossings = self.self_contacts.find_tangles(
            &self.state.position,
            &self.topology.triangles,
            &self.spec,
        );
        if let (Some(d), Some(t)) = (self.diagnostics.as_deref_mut(), t) {
            d.families[Family::SelfCollision].time += t.elapsed();
        }
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
    fn watch_for_jerks(&mut self, bodies: &[Pose], origin: DVec3) {
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
    fn self_collision_on(&self) -> bool {
        self.params.weights[Family::SelfCollision] > 0.0
    }

    /// Whether `family`'s violation is measured: always, or for the
    /// families measured only while on, while its weight is above 0.
    fn measured(&self, family: Family) -> bool {
        !family.measured_only_while_on() || self.params.weights[family] > 0.0
    }

    /// Finds this substep's self-contacts over the predicted positions (timed
    /// with the self-collision family in diagnostics).
    fn find_self_contacts(&mut self) {
        let t = self.diagnostics.is_some().then(Instant::now);
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
        if let (Some(d), Some(t)) = (self.diagnostics.as_deref_mut(), t) {
            d.families[Family::SelfCollision].time += t.elapsed();
        }
    }

    /// How many threads the adjust phase may use: one for a cloth too small
    /// to share (a barrier costs more than its batches), else as many as
    /// rayon allows here ([`team`]).
    fn threads(&self) -> usize {
        if self.state.len() < PARALLEL_MIN_PARTICLES {
            1
        } else {
            team::available()
        }
    }

    /// Pushes every free particle out of every collider (timed in diagnostics).
    fn project_colliders(&mut self, margin: f32) {
        if self.colliders.is_empty() {
            return;
        }
        let t = self.diagnostics.is_some().then(Instant::now);
        collision::project(
            &mut self.state.position,
            &self.inv_mass,
            &self.colliders,
            &self.collider_to,
            margin,
            &mut self.contacts,
        );
        if let (Some(d), Some(t)) = (self.diagnostics.as_deref_mut(), t) {
            d.timings.collisions += t.elapsed();
        }
    }

    /// Before the first step: every free particle, and the reference motion
    /// damping measures it against, starts with the motion of the body it
    /// follows (its turn; the origin carries the translation, [`frame`]),
    /// so a cloth on a body that is already moving starts in steady motion.
    /// The motion is the body's over the first substep, taken as under way.
    fn start_with_carriers(&mut self, bodies: &[Pose]) {
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
    fn drive_attachments(&mut self) {
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

    fn check_finite(&self, phase: &'static str) -> Result<(), NonFinite> {
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

/// Particles below which the adjust phase runs on one thread. On the
/// shipped presets (256 to 1024 particles, one or two sweeps a substep) two
/// threads measured from 8 % faster to several times slower from run to run
/// on a 2-core virtual machine: with a barrier every few microseconds, a
/// thread the host pauses stalls its partner. From 64 × 64 up the gain held
/// in every run (BENCHMARKS.md, "Measured design choices").
const PARALLEL_MIN_PARTICLES: usize = 2048;

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

/// Where a state turned non-finite: phase, particle, quantity, value.
type NonFinite = (&'static str, usize, &'static str, String);
