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
//! 2. **adjust** (`adjust`, [`families`]): `iterations` sweeps over the
//!    families of geometric constraints between neighbours, each weighted
//!    by its `λ`, in the order [`Family::ALL`] lists them: the surface
//!    families (the paper's, and facing, weft's own: each element turns to
//!    face the way the surface its neighbours make does), then stretch (the
//!    length limit has the last word). Families are projected one after
//!    another (Gauss–Seidel), so a particle's correction combines what each
//!    asks.
//!    Each weight is a compliance (XPBD), so its effect does not depend on
//!    iterations, substeps or resolution ([`params::Weights`]); rotations
//!    are shaped by Eq. 3 ([`forced_rotation`]). The last family,
//!    self-collision (on by default), keeps the cloth's layers apart
//!    ([`self_collision`]). Colliders are projected after each
//!    sweep, friction once at the end ([`collision`]).
//!
//! Constraints are solved in graph-colour batches ([`topology`]): the
//! constraints of one colour share no particle, so large batches are split
//! across rayon's threads and the result is bit-identical for any number of
//! threads. The solver knows nothing of telemetry or
//! UI; [`diagnostics`] exposes what they need.
//!
//! ```
//! use weft_cloth::solver::{ClothSpec, Environment, Params, Pose, Solver};
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
pub mod cloth;
pub mod collision;
pub mod diagnostics;
pub mod families;
pub mod forced_rotation;
pub mod frame;
pub(crate) mod kernels;
mod measure;
pub mod params;
pub mod portable;
pub mod pull;
pub mod range;
pub mod rotation;
pub mod self_collision;
mod step;
mod team;
pub mod topology;
pub mod update;

pub use cloth::{ClothSpec, ClothState};
pub use collision::{Collider, Pose, Shape};
pub use diagnostics::{Diagnostics, Orientation};
pub use families::compliance_factor;
pub use families::{Family, PerFamily, Violation};
pub use forced_rotation::ForcedRotation;
pub use frame::Frame;
pub use params::{Params, Weights, Width};
pub use pull::Pull;
pub use range::{ParamError, Range, RangeError};
pub use topology::Topology;
pub use update::Environment;

/// Which results this solver gives: raised whenever a change makes the
/// same preset and parameters step to a different state. A recording names
/// the revision that made it, so that a replay by another revision can say
/// why it does not reproduce (`weft replay`). The test
/// `the_solver_revision_names_its_results` (`tests/record.rs`) pins the
/// results of this one, so a change of results cannot land without it.
pub const REVISION: u32 = 2;

/// This weft and its solver's results, `0.1.0 (solver revision 2)`:
/// recordings, sweeps and fits are stamped with it.
pub fn version() -> String {
    format!("{} {SOLVER_REVISION}{REVISION})", env!("CARGO_PKG_VERSION"))
}

/// How [`version`] names the revision.
const SOLVER_REVISION: &str = "(solver revision ";

/// The solver revision a [`version`] names (within any text around it,
/// `weft 0.1.0 (solver revision 1)`); `None` for one from before
/// revisions were named.
pub fn revision_of(version: &str) -> Option<u32> {
    let (_, rest) = version.split_once(SOLVER_REVISION)?;
    rest.strip_suffix(')')?.parse().ok()
}

use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};

use collision::Contact;
use diagnostics::CorrectionTrack;
use families::{Multipliers, stretch};
use self_collision::SelfCollision;
use update::FREE;

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
    /// Self-collision's state and stages ([`self_collision`]).
    self_collision: SelfCollision,
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
            self_collision: SelfCollision::default(),
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
        range::Range::new(0.0, 10.0)
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

    /// The time now, while diagnostics are on: for [`Solver::charge`].
    pub(in crate::solver) fn stopwatch(&self) -> Option<Instant> {
        self.diagnostics.is_some().then(Instant::now)
    }

    /// Adds the time since `start` (a [`Solver::stopwatch`]) to the timing
    /// of the diagnostics that `part` picks.
    pub(in crate::solver) fn charge(
        &mut self,
        start: Option<Instant>,
        part: impl FnOnce(&mut Diagnostics) -> &mut Duration,
    ) {
        if let (Some(d), Some(t)) = (self.diagnostics.as_deref_mut(), start) {
            *part(d) += t.elapsed();
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
}

/// Particles below which the adjust phase runs on one thread. On the
/// shipped presets (256 to 1024 particles, one or two sweeps a substep) two
/// threads measured from 8 % faster to several times slower from run to run
/// on a 2-core virtual machine: with a barrier every few microseconds, a
/// thread the host pauses stalls its partner. From 64 × 64 up the gain held
/// in every run (BENCHMARKS.md, "Measured design choices").
const PARALLEL_MIN_PARTICLES: usize = 2048;

/// Where a state turned non-finite: phase, particle, quantity, value.
type NonFinite = (&'static str, usize, &'static str, String);
