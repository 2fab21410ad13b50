//! Scenes: a preset brought to life: cloth, moving bodies, wind, colliders.
//!
//! [`Scene`] owns a [`Solver`] and the motion of every body. Each
//! [`Scene::step`] evaluates the bodies' poses and the wind at the end of the
//! frame and advances the solver by one `Δt`. Everything is deterministic:
//! the same preset gives the same frames.
//!
//! Presets, bodies and colliders are in world coordinates; the solver
//! measures every position from a floating origin kept in double precision
//! ([`crate::solver::frame`]). The scene puts the origin on the **carrier**,
//! the body most of the cloth's attachments follow, and moves it with the
//! carrier's position at every step (a cloth that hangs from nothing keeps
//! it where the cloth was placed). So the cloth moves the same wherever it
//! is and however fast it is carried, and it starts moving with its
//! carrier. [`Scene::world_positions`] gives the particles in world
//! coordinates.
//!
//! ```
//! use weft_cloth::scene::{Scene, load};
//!
//! let loaded = load::load("hanging_sheet", &[]).unwrap();
//! let mut scene = Scene::new(&loaded.preset).unwrap();
//! for _ in 0..10 {
//!     scene.step().unwrap();
//! }
//! assert!(scene.solver().max_strain() < 0.1);
//! ```

pub mod load;
pub mod motion;
pub mod preset;
pub mod shipped;
pub mod tuning;

use std::borrow::Cow;

use glam::{DVec3, Vec3};

pub use load::{Loaded, Override, PresetError};
pub use preset::{FORMAT, Preset};
pub use tuning::Tuning;

use crate::solver::{
    Collider, Environment, Frame, ParamError, Params, Pose, SetupError, Shape, Solver, StepError,
};
use motion::Motion;
pub use motion::Placement;
use preset::{ShapeKind, WindSection, euler};

/// A running scene.
#[derive(Clone, Debug)]
pub struct Scene {
    preset: Preset,
    solver: Solver,
    motions: Vec<Motion>,
    /// The bodies where they are, in world coordinates.
    placements: Vec<Placement>,
    /// The same, in single precision (for drawing).
    world_poses: Vec<Pose>,
    /// The same, measured from the solver's origin.
    poses: Vec<Pose>,
    /// The body the origin moves with, if any.
    carrier: Option<usize>,
    /// Where the host puts each body it drives ([`Scene::drive`]), in world
    /// coordinates; `None` for a body its motion script moves.
    driven: Vec<Option<Placement>>,
    frame: u64,
}

/// A body the scene does not have.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("no body {body}: the scene has {count} (indices 0 to {last}, in the preset's order)", last = .count.saturating_sub(1))]
pub struct NoBody {
    /// The index asked for.
    pub body: usize,
    /// How many bodies the scene has.
    pub count: usize,
}

impl Scene {
    /// Builds the scene a (validated) preset describes, at time 0.
    pub fn new(preset: &Preset) -> Result<Self, SetupError> {
        let mut motions: Vec<Motion> = preset.bodies.iter().map(Motion::new).collect();
        let placements: Vec<Placement> = motions.iter_mut().map(|m| m.pose(0.0)).collect();
        let body = |name: &str| preset.bodies.iter().position(|b| b.name == name);
        let carrier = carrier(preset, &body);
        let origin = carrier.map_or(preset.cloth.position, |b| placements[b].translation);
        let poses: Vec<Pose> = placements.iter().map(|p| p.from(origin)).collect();
        let spec = preset.cloth.spec_from(origin);
        let mut solver = Solver::new(spec, preset.solver, &poses)?;
        solver.set_frame(Frame {
            origin,
            shift: DVec3::ZERO,
        });
        for (a, att) in preset.attachments.iter().enumerate() {
            let b = body(&att.body).ok_or_else(|| SetupError::NoSuchBody {
                what: format!("attachment {a} (`{}`)", att.body),
                body: usize::MAX,
                bodies: poses.len(),
            })?;
            let cells = att
                .select
                .iter()
                .flat_map(|r| r.cells(spec.weft, spec.warp))
                .chain(att.particles.iter().copied());
            for [i, j] in cells {
                if i >= spec.weft || j >= spec.warp {
                    return Err(SetupError::NoSuchParticle {
                        particle: spec.index(i.min(spec.weft), j.min(spec.warp)),
                        particles: spec.len(),
                    });
                }
                solver.try_attach(spec.index(i, j), b, att.clamp)?;
            }
        }
        for c in &preset.colliders {
            let shape = match c.shape {
                ShapeKind::Plane => Shape::Plane,
                ShapeKind::Sphere => Shape::Sphere {
                    radius: c.radius.unwrap_or(0.5),
                },
                ShapeKind::Capsule => Shape::Capsule {
                    radius: c.radius.unwrap_or(0.1),
                    half_length: c.half_length.unwrap_or(0.5),
                },
                ShapeKind::Cylinder => Shape::Cylinder {
                    radius: c.radius.unwrap_or(0.5),
                    half_length: c.half_length.unwrap_or(0.5),
                },
                ShapeKind::Box => Shape::Box {
                    half_extents: c.half_extents.unwrap_or(Vec3::splat(0.5)),
                },
            };
            solver.add_collider(Collider {
                shape,
                body: match &c.body {
                    Some(name) => Some(body(name).ok_or_else(|| SetupError::NoSuchBody {
                        what: format!("collider on `{name}`"),
                        body: usize::MAX,
                        bodies: poses.len(),
                    })?),
                    None => None,
                },
                pose: Pose::new(c.position, euler(c.rotation)),
                friction: c.friction,
            })?;
        }
        Ok(Self {
            preset: preset.clone(),
            solver,
            motions,
            world_poses: placements.iter().map(Placement::world).collect(),
            placements,
            poses,
            carrier,
            driven: vec![None; preset.bodies.len()],
            frame: 0,
        })
    }

    /// Advances one frame (`Δt`).
    pub fn step(&mut self) -> Result<(), StepError> {
        self.step_with(&mut |_| {})
    }

    /// [`Scene::step`], calling `after_substep` with the cloth at the end of
    /// every substep.
    pub fn step_with(
        &mut self,
        after_substep: &mut dyn FnMut(&crate::solver::ClothState),
    ) -> Result<(), StepError> {
        let t0 = self.solver.time();
        let t1 = t0 + self.solver.params().dt as f64;
        let bodies = self.placements.iter_mut().zip(&mut self.motions);
        for ((placement, m), host) in bodies.zip(&self.driven) {
            *placement = match host {
                Some(p) => *p,
                None => m.pose(t1),
            };
        }
        let origin = self.carrier.map_or(self.solver.frame().origin, |b| {
            self.placements[b].translation
        });
        for (pose, placement) in self.poses.iter_mut().zip(&self.placements) {
            *pose = placement.from(origin);
        }
        let env = self.environment_at(t0 as f32);
        self.solver
            .step_in_frame(&env, &self.poses, origin, after_substep)?;
        for (world, placement) in self.world_poses.iter_mut().zip(&self.placements) {
            *world = placement.world();
        }
        self.frame += 1;
        Ok(())
    }

    /// The particles' positions in world coordinates (the solver measures
    /// them from its floating origin).
    pub fn world_positions(&self) -> Cow<'_, [Vec3]> {
        let x = &self.solver.state().position;
        if self.solver.frame().origin == DVec3::ZERO {
            return Cow::Borrowed(x);
        }
        Cow::Owned(self.to_world(x))
    }

    /// Points measured from the solver's origin, in world coordinates.
    pub fn to_world(&self, local: &[Vec3]) -> Vec<Vec3> {
        let frame = self.solver.frame();
        local.iter().map(|&p| frame.world(p).as_vec3()).collect()
    }

    /// Drives `body` from the host: at the end of the next step (and of
    /// every step after, until [`Scene::release`]) it is at `placement`, in
    /// world coordinates, instead of where its motion in the preset takes
    /// it; the particles attached to it and its colliders follow. A host
    /// calls it before each step with its own transform for that step's end
    /// (a character's shoulders, a car). The body's velocity is what its
    /// placements imply, step to step.
    ///
    /// ```
    /// use weft_cloth::scene::{Placement, Scene, load};
    /// use glam::{DVec3, Quat};
    ///
    /// let mut scene = Scene::new(&load::load("cape_runner", &[]).unwrap().preset).unwrap();
    /// let runner = scene.body("runner").unwrap();
    /// for frame in 0..30 {
    ///     // The host's character walks along +x at 1.5 m/s.
    ///     let x = 1.5 * (frame + 1) as f64 / 60.0;
    ///     let at = Placement { translation: DVec3::new(x, 0.0, 0.0), rotation: Quat::IDENTITY };
    ///     scene.drive(runner, at).unwrap();
    ///     scene.step().unwrap();
    /// }
    /// assert!((scene.body_placements()[runner].translation.x - 0.75).abs() < 1e-9);
    /// ```
    pub fn drive(&mut self, body: usize, placement: Placement) -> Result<(), NoBody> {
        let count = self.driven.len();
        let slot = self.driven.get_mut(body).ok_or(NoBody { body, count })?;
        *slot = Some(placement);
        Ok(())
    }

    /// Hands `body` back to its motion in the preset (evaluated at each
    /// step's end time, as if it had never been driven).
    pub fn release(&mut self, body: usize) -> Result<(), NoBody> {
        let count = self.driven.len();
        let slot = self.driven.get_mut(body).ok_or(NoBody { body, count })?;
        *slot = None;
        Ok(())
    }

    /// The index of the body named `name` in the preset, if there is one.
    pub fn body(&self, name: &str) -> Option<usize> {
        self.preset.bodies.iter().position(|b| b.name == name)
    }

    /// Adds a collider of the host's, in world coordinates or moving with a
    /// body (drive that body to move it). It acts from the next step on.
    pub fn add_collider(&mut self, collider: Collider) -> Result<(), SetupError> {
        self.solver.add_collider(collider)
    }

    /// Each particle's normal (its element's local +Z), unit length; the
    /// same in world coordinates as in the solver's (the floating origin
    /// only moves).
    pub fn normals(&self) -> Vec<Vec3> {
        let s = self.solver.state();
        (0..s.len()).map(|i| s.normal(i)).collect()
    }

    /// The cloth's triangles, as indices into the positions: two a cell of
    /// the woven grid.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.solver.topology().triangles
    }

    /// The body the origin moves with, if any (the one most of the cloth's
    /// attachments follow).
    pub fn carrier(&self) -> Option<usize> {
        self.carrier
    }

    /// Gravity, air and the gusting wind at time `t`.
    pub fn environment_at(&self, t: f32) -> Environment {
        let e = &self.preset.environment;
        Environment {
            gravity: e.gravity,
            wind: wind_at(&e.wind, t),
            air_density: e.air_density,
            drag_normal: e.drag_normal,
            drag_tangent: e.drag_tangent,
        }
    }

    /// Replaces the solver parameters from the next step on.
    pub fn set_params(&mut self, params: Params) -> Result<(), ParamError> {
        self.set_tuning(&Tuning {
            solver: params,
            ..self.tuning()
        })
    }

    /// The live-tunable settings: solver parameters, wind, and the pull on
    /// a particle if there is one.
    pub fn tuning(&self) -> Tuning {
        Tuning {
            pull: self.solver.pull(),
            ..Tuning::of(&self.preset)
        }
    }

    /// Applies live-tunable settings from the next step on, if they validate
    /// (else nothing changes). A pull's particle must be one of the cloth's.
    pub fn set_tuning(&mut self, tuning: &Tuning) -> Result<(), ParamError> {
        tuning.validate()?;
        if let Some(pull) = &tuning.pull {
            pull.validate(self.solver.state().len())?;
        }
        self.solver.set_params(tuning.solver)?;
        self.solver.set_pull(tuning.pull)?;
        tuning.apply_to(&mut self.preset);
        Ok(())
    }

    /// The preset, with any parameter changes applied.
    pub fn preset(&self) -> &Preset {
        &self.preset
    }

    /// The solver.
    pub fn solver(&self) -> &Solver {
        &self.solver
    }

    /// The solver, mutably (e.g. to turn diagnostics on).
    pub fn solver_mut(&mut self) -> &mut Solver {
        &mut self.solver
    }

    /// Frames stepped so far.
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Simulated time, in seconds.
    pub fn time(&self) -> f64 {
        self.solver.time()
    }

    /// Body names, in body-index order.
    pub fn body_names(&self) -> impl Iterator<Item = &str> {
        self.preset.bodies.iter().map(|b| b.name.as_str())
    }

    /// Body poses at the current time, in world coordinates.
    pub fn body_poses(&self) -> &[Pose] {
        &self.world_poses
    }

    /// Body poses at the current time, in world coordinates, positions in
    /// double precision.
    pub fn body_placements(&self) -> &[Placement] {
        &self.placements
    }

    /// Frames in `seconds` of simulated time (at least one).
    pub fn frames_in(&self, seconds: f32) -> u64 {
        ((seconds / self.solver.params().dt).round() as u64).max(1)
    }
}

/// The body most of the preset's attached particles follow (the first of
/// those with most), if any particle is attached.
fn carrier(preset: &Preset, body: &impl Fn(&str) -> Option<usize>) -> Option<usize> {
    let spec = preset.cloth.spec();
    let mut count = vec![0usize; preset.bodies.len()];
    for att in &preset.attachments {
        if let Some(b) = body(&att.body) {
            let cells = att
                .select
                .iter()
                .map(|r| r.cells(spec.weft, spec.warp).len());
            count[b] += cells.sum::<usize>() + att.particles.len();
        }
    }
    let most = count.iter().copied().max().filter(|&m| m > 0)?;
    count.iter().position(|&c| c == most)
}

/// The wind at time `t`: the mean velocity, plus gusts along it and a sway of
/// its direction, from a fixed sum of sines (deterministic, never negative
/// gusts).
pub fn wind_at(w: &WindSection, t: f32) -> Vec3 {
    use crate::solver::portable::{rotation_z, sin};
    use std::f32::consts::TAU;
    if w.gust_period <= 0.0 || (w.gust == 0.0 && w.sway == 0.0) {
        return w.velocity;
    }
    let p = t / w.gust_period;
    let gust = w.gust * (0.6 * sin(TAU * p) + 0.4 * sin(TAU * 2.3 * p + 1.3)).max(0.0);
    let sway = w.sway.to_radians() * sin(TAU * 0.43 * p + 0.7);
    let dir = w.velocity.try_normalize().unwrap_or(Vec3::X);
    rotation_z(sway) * (w.velocity + dir * gust)
}
