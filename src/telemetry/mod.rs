//! Telemetry: what a running scene streams to Rerun.
//!
//! The solver knows nothing of Rerun; this module reads the scene and the
//! solver's [`Diagnostics`](crate::solver::Diagnostics) and logs them, in a
//! few batched entities per frame (never one entity per particle). Entity
//! paths ([`paths`]):
//!
//! | path | what | level |
//! |---|---|---|
//! | `world` | Z-up view coordinates | static |
//! | `world/cloth/particles` | points, coloured by `color_by` | summary |
//! | `world/cloth/particles` | per particle: `i`, `j` (static); `strain`, `normal_offset`, `violation_{family}`, `dx_{family}`, `dtheta_{family}` (families that turn), as `f32` | full, with `set_particle_values` (the debugger) |
//! | `world/cloth/framing` | two points the debugger's camera tracks, drawn with no radius (`framing.rs`) | summary, with `set_framing` (the debugger) |
//! | `world/cloth/mesh` | the cloth surface (`full.rs`, with the normals, the corrections and the hover values) | full |
//! | `world/cloth/normals` | element normals (arrows) | full |
//! | `world/ghost/mesh` | another run's cloth, faint (`ghost.rs`: a branch's parent, in the debugger) | triangles static; positions and normals at the frames logged |
//! | `world/corrections/{family}/dx` | δx of the last adjust (arrows, each at most the cloth's longer side long) | full |
//! | `world/corrections/{family}/dtheta` | δθ as axis × angle (arrows, as δx's), families that turn | full |
//! | `world/pull` | the debugger's pull: a line from the pulled particle to its target, while there is one (`pull.rs`) | summary |
//! | `world/bodies/{name}` | body transform; its colliders below it | summary, when it moved |
//! | `world/colliders/{k}` | fixed colliders; a plane's patch under the cloth (`colliders.rs`) | static; a plane's corners at summary |
//! | `metrics/violation/{family}/{max,rms}` | per-family violation | summary |
//! | `metrics/violation/self/crossings` | mesh edges through a triangle (0 when the cloth does not pass through itself), while self-collision is on | summary |
//! | `metrics/strain/max`, `metrics/energy/kinetic` | strain, energy | summary |
//! | `metrics/normals/{flipped,offset_rms}` | the normals against the surface | summary |
//! | `metrics/time/…` | update, adjust per family, collisions, telemetry, total (ms) | summary |
//! | `params` | solver parameters (TOML), at every change | always |
//! | `events` | parameter changes, a drag's start and end (`drag.rs`), solver failures | always |
//! | `preset`, `weft`, `cloth/topology` | resolved preset, version, topology | static |
//!
//! Timelines: `frame` (sequence) and `sim_time` (seconds).

/// Where `--connect` goes without a URL: a viewer started with `rerun`.
pub const DEFAULT_VIEWER: &str = "rerun+http://127.0.0.1:9876/proxy";

mod batch;
mod batching;
pub mod blueprint;
mod changes;
mod colliders;
pub mod color;
mod drag;
pub mod framing;
mod full;
pub mod ghost;
pub mod paths;
mod pull;
pub mod read;

pub use batching::{file_batching, whole_frames};

pub use changes::describe_changes;

use std::time::{Duration, Instant};

use rerun::{RecordingStream, RecordingStreamResult};

use crate::scene::{
    Scene, Tuning,
    preset::{Level, TelemetrySettings},
};
use crate::solver::{Family, Pose, Solver, StepError};

/// What the solver collects in a step, beyond the step itself (each costs
/// step time).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Collect {
    /// The figures and timings ([`Solver::set_diagnostics`]).
    pub figures: bool,
    /// Every particle's corrections as well ([`Solver::record_corrections`]).
    pub corrections: bool,
}

impl Collect {
    /// What this or `other` collects.
    pub fn or(self, other: Collect) -> Collect {
        Collect {
            figures: self.figures || other.figures,
            corrections: self.corrections || other.corrections,
        }
    }

    /// Sets `solver`'s switches to collect this.
    pub fn apply(self, solver: &mut Solver) {
        solver.set_diagnostics(self.figures || self.corrections);
        solver.record_corrections(self.corrections);
    }
}

/// Streams a scene to a Rerun recording.
pub struct Telemetry {
    rec: RecordingStream,
    settings: TelemetrySettings,
    last_tuning: Option<Tuning>,
    /// The body poses last logged (a pose that does not change is logged once).
    last_poses: Vec<Option<Pose>>,
    /// Time spent logging the previous frame (reported with the next).
    last_cost: Duration,
    particle_values: bool,
    /// Whether each frame logs the points the debugger's camera frames.
    framing: bool,
    /// Whether level full draws the correction arrows (of the families on
    /// in the settings).
    arrows: bool,
    /// What the frames logged so far left on screen of what only level
    /// full draws.
    drawn: full::Drawn,
    /// Whether the last logged frame marked crossings.
    crossings_drawn: bool,
    /// Whether the next frames log what the 3D view draws, or their
    /// scalars only ([`Self::set_visuals`]).
    visuals: bool,
    /// Whether the last logged frame drew a pull.
    pull_drawn: bool,
    /// The drag under way, for its events ([`drag`]).
    drag: drag::Drag,
}

impl Telemetry {
    /// Telemetry into `rec`, with `settings`.
    pub fn new(rec: RecordingStream, settings: TelemetrySettings) -> Self {
        Self {
            rec,
            settings,
            last_tuning: None,
            last_poses: Vec::new(),
            last_cost: Duration::ZERO,
            particle_values: false,
            framing: false,
            arrows: true,
            drawn: full::Drawn::default(),
            crossings_drawn: false,
            visuals: true,
            pull_drawn: false,
            drag: drag::Drag::default(),
        }
    }

    /// Whether the frames logged from now on carry what the 3D view draws
    /// (particles, mesh, normals, arrows, crossings, colliders, bodies), or
    /// only their scalars. On unless turned off: the desktop debugger logs
    /// a frame's drawing only when the window has drawn the one before, so
    /// the viewer is never sent more than it can show, and sends each
    /// drawing whole ([`Self::send`]), so the view never mixes two frames.
    /// Turned back on, the next frame draws everything afresh.
    pub fn set_visuals(&mut self, on: bool) {
        self.visuals = on;
    }

    /// Whether frame `frame` is logged with its drawing
    /// ([`Self::set_visuals`]).
    pub fn draws_frame(&self, frame: u64) -> bool {
        self.visuals && self.logs_frame(frame)
    }

    /// Whether each frame at level full also logs every particle's values
    /// (strain, violation, δx and δθ per family) on the particles entity,
    /// for hovering in the viewer. The desktop debugger turns this on;
    /// `weft record` leaves it off (it adds about a third to a full file).
    pub fn set_particle_values(&mut self, on: bool) {
        self.particle_values = on;
    }

    /// Whether each logged frame also logs [`framing::points`] at
    /// [`paths::FRAMING`], which the desktop debugger's camera tracks; off
    /// for `weft record`.
    pub fn set_framing(&mut self, on: bool) {
        self.framing = on;
    }

    /// Whether level full draws the correction arrows at all (of the
    /// families on in the settings' `corrections`). On unless turned off:
    /// the desktop debugger starts with them off, and its panel turns them
    /// on. Off, the arrows drawn so far are cleared at the next frame.
    pub fn set_arrows(&mut self, on: bool) {
        self.arrows = on;
    }

    /// Whether level full draws the correction arrows ([`Self::set_arrows`]).
    pub fn arrows(&self) -> bool {
        self.arrows
    }

    /// The settings in force.
    pub fn settings(&self) -> &TelemetrySettings {
        &self.settings
    }

    /// Changes the settings (e.g. from the tuning panel).
    pub fn set_settings(&mut self, settings: TelemetrySettings) {
        self.settings = settings;
    }

    /// The recording stream.
    pub fn stream(&self) -> &RecordingStream {
        &self.rec
    }

    /// Whether the solver must collect diagnostics for this level.
    pub fn needs_diagnostics(&self) -> bool {
        self.settings.level != Level::Off
    }

    /// Whether the solver's diagnostics must record every particle's
    /// corrections: for the arrows (level full) and for colouring by them.
    pub fn needs_corrections(&self) -> bool {
        self.settings.level == Level::Full || self.settings.color_by.uses_corrections()
    }

    /// Has `solver` collect the diagnostics this telemetry logs, and no
    /// more (they cost the step time): what the first frame needs, which
    /// every level but `off` logs.
    pub fn configure(&self, solver: &mut Solver) {
        self.collects_for_step(0).apply(solver);
    }

    /// What the step that produces `frame` must collect for this telemetry:
    /// the figures at every level but `off`, every particle's corrections
    /// (level full, or colouring by them) only if that frame is logged. They describe one step's adjust phase,
    /// so with `log_every = N` the steps in between need not track them;
    /// what a logged frame shows is the same bit for bit.
    pub fn collects_for_step(&self, frame: u64) -> Collect {
        Collect {
            figures: self.needs_diagnostics(),
            corrections: self.needs_corrections() && self.logs_frame(frame) && self.visuals,
        }
    }

    /// Whether frame `frame` is logged: never into a disabled stream
    /// (`weft record` without an output), where nothing is kept.
    pub fn logs_frame(&self, frame: u64) -> bool {
        self.settings.level != Level::Off
            && frame.is_multiple_of(self.settings.log_every as u64)
            && self.rec.is_enabled()
    }

    fn set_time(&self, frame: u64, time: f64) {
        if !self.rec.is_enabled() {
            return; // Rerun would warn that it ignores the time.
        }
        self.rec.set_time_sequence(paths::FRAME, frame as i64);
        self.rec.set_duration_secs(paths::SIM_TIME, time);
    }

    /// Logs what never changes: version, resolved preset, topology, colliders
    /// and series styles. Call once, before the first frame.
    pub fn log_static(&self, scene: &Scene, resolved_preset: &str) -> RecordingStreamResult<()> {
        if !self.rec.is_enabled() {
            return Ok(());
        }
        let rec = &self.rec;
        rec.log_static(paths::WORLD, &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
        rec.log_static(
            paths::VERSION,
            &rerun::TextDocument::new(format!("weft {}", crate::solver::version())),
        )?;
        rec.log_static(
            paths::PRESET,
            &rerun::TextDocument::new(resolved_preset)
                .with_media_type(rerun::MediaType::plain_text()),
        )?;
        let topo = scene.solver().topology();
        let pairs = |set: &crate::solver::topology::PairSet| -> Vec<u32> {
            set.items.iter().flat_map(|p| [p.a, p.b]).collect()
        };
        let bends: Vec<u32> = topo
            .bend
            .items
            .iter()
            .flat_map(|t| [t.a, t.mid, t.b])
            .collect();
        let spec = scene.solver().spec();
        rec.log_static(
            paths::TOPOLOGY,
            &rerun::AnyValues::default()
                .with_component::<rerun::components::Count>("weft", [spec.weft as u64])
                .with_component::<rerun::components::Count>("warp", [spec.warp as u64])
                .with_component::<rerun::components::Count>(
                    "structural",
                    pairs(&topo.structural).into_iter().map(u64::from),
                )
                .with_component::<rerun::components::Count>(
                    "shear",
                    pairs(&topo.shear).into_iter().map(u64::from),
                )
                .with_component::<rerun::components::Count>(
                    "bend",
                    bends.into_iter().map(u64::from),
                ),
        )?;
        // Each particle's grid cell (i along the weft, j along the warp),
        // shown when a particle is hovered in the viewer.
        let cells = || (0..spec.len()).map(|k| spec.cell(k));
        rec.log_static(
            paths::PARTICLES,
            &rerun::AnyValues::default()
                .with_component::<rerun::components::Count>("i", cells().map(|(i, _)| i as u64))
                .with_component::<rerun::components::Count>("j", cells().map(|(_, j)| j as u64)),
        )?;
        let triangles: Vec<[u32; 3]> = topo.triangles.clone();
        rec.log_static(
            paths::MESH,
            &rerun::Mesh3D::update_fields()
                .with_triangle_indices(triangles)
                .with_albedo_factor(rerun::Rgba32::from_rgb(200, 170, 120)),
        )?;
        colliders::log_static(&self.rec, scene)?;
        self.log_series_styles()?;
        Ok(())
    }

    fn log_series_styles(&self) -> RecordingStreamResult<()> {
        for f in Family::ALL {
            let c = color::family(f);
            self.rec.log_static(
                paths::violation(f, "max"),
                &rerun::SeriesLines::new()
                    .with_colors([c])
                    .with_names([format!("{} max", f.name())]),
            )?;
            self.rec.log_static(
                paths::violation(f, "rms"),
                &rerun::SeriesLines::new()
                    .with_colors([c])
                    .with_names([format!("{} rms", f.name())])
                    .with_widths([0.5]),
            )?;
            self.rec.log_static(
                paths::adjust_time(f),
                &rerun::SeriesLines::new()
                    .with_colors([c])
                    .with_names([format!("adjust {}", f.name())]),
            )?;
        }
        Ok(())
    }

    /// Logs the live settings (solver parameters and wind) if they differ
    /// from the last logged ones, at `frame`, with an event naming what
    /// changed. `frame` is the frame whose step first uses them.
    pub fn log_tuning(
        &mut self,
        frame: u64,
        time: f64,
        tuning: &Tuning,
    ) -> RecordingStreamResult<()> {
        if self.last_tuning.as_ref() == Some(tuning) {
            return Ok(());
        }
        self.set_time(frame, time);
        let text = crate::scene::load::to_toml(tuning);
        self.rec.log(
            paths::PARAMS,
            &rerun::TextDocument::new(text).with_media_type(rerun::MediaType::plain_text()),
        )?;
        let message = match &self.last_tuning {
            None => Some("initial parameters".to_string()),
            Some(old) => match self.drag.said(old, tuning, frame) {
                drag::Said::NotADrag => Some(format!(
                    "parameters changed: {}",
                    describe_changes(old, tuning)
                )),
                drag::Said::Nothing => None,
                drag::Said::Event(text) => Some(text),
            },
        };
        if let Some(message) = message {
            self.rec.log(
                paths::EVENTS,
                &rerun::TextLog::new(message).with_level(rerun::TextLogLevel::INFO),
            )?;
        }
        self.last_tuning = Some(*tuning);
        Ok(())
    }

    /// Forgets what was logged, so everything is logged again (for a new sink).
    pub fn forget(&mut self) {
        self.last_tuning = None;
        self.last_poses.clear();
        self.drawn = full::Drawn::default();
    }

    /// Logs an informational event at `frame`.
    pub fn log_event(&self, frame: u64, time: f64, text: &str) -> RecordingStreamResult<()> {
        self.set_time(frame, time);
        self.rec.log(
            paths::EVENTS,
            &rerun::TextLog::new(text).with_level(rerun::TextLogLevel::INFO),
        )
    }

    /// Logs a solver failure at the frame it happened.
    pub fn log_failure(
        &self,
        frame: u64,
        time: f64,
        error: &StepError,
    ) -> RecordingStreamResult<()> {
        self.set_time(frame, time);
        self.rec.log(
            paths::EVENTS,
            &rerun::TextLog::new(error.to_string()).with_level(rerun::TextLogLevel::ERROR),
        )
    }

    /// Logs one frame of the scene, as the settings ask.
    pub fn log_frame(&mut self, scene: &Scene) -> RecordingStreamResult<()> {
        let frame = scene.frame();
        if !self.logs_frame(frame) {
            return Ok(());
        }
        let start = Instant::now();
        self.set_time(frame, scene.time());
        let solver = scene.solver();
        let diag = solver.diagnostics();
        let rec = &self.rec;

        // Scalars (none before the first step: there is nothing to measure).
        if let Some(d) = diag.filter(|_| frame > 0) {
            for f in Family::ALL {
                let v = d.family(f).violation;
                rec.log(
                    paths::violation(f, "max"),
                    &rerun::Scalars::single(v.max as f64),
                )?;
                rec.log(
                    paths::violation(f, "rms"),
                    &rerun::Scalars::single(v.rms as f64),
                )?;
                rec.log(
                    paths::adjust_time(f),
                    &rerun::Scalars::single(ms(d.family(f).time)),
                )?;
            }
            if let Some(n) = d.self_crossings {
                rec.log(paths::SELF_CROSSINGS, &rerun::Scalars::single(n as f64))?;
            }
            rec.log(paths::STRAIN, &rerun::Scalars::single(d.max_strain as f64))?;
            let o = d.orientation;
            rec.log(
                paths::NORMALS_FLIPPED,
                &rerun::Scalars::single(o.flipped as f64),
            )?;
            rec.log(
                paths::NORMALS_OFFSET,
                &rerun::Scalars::single(o.offset_rms as f64),
            )?;
            rec.log(
                paths::ENERGY,
                &rerun::Scalars::single(d.kinetic_energy as f64),
            )?;
            rec.log(
                paths::TIME_UPDATE,
                &rerun::Scalars::single(ms(d.timings.update)),
            )?;
            rec.log(
                paths::TIME_COLLISIONS,
                &rerun::Scalars::single(ms(d.timings.collisions)),
            )?;
            rec.log(
                paths::TIME_TOTAL,
                &rerun::Scalars::single(ms(d.timings.total)),
            )?;
            rec.log(
                paths::TIME_TELEMETRY,
                &rerun::Scalars::single(ms(self.last_cost)),
            )?;
        }

        if self.visuals {
            self.log_visuals(scene)?;
        }
        self.last_cost = start.elapsed();
        Ok(())
    }

    /// Logs the drawing of the scene's current frame, if that frame is
    /// logged: for a frame logged with its scalars only
    /// ([`Self::set_visuals`]) that the user stopped on.
    pub fn redraw(&mut self, scene: &Scene) -> RecordingStreamResult<()> {
        if !self.logs_frame(scene.frame()) {
            return Ok(());
        }
        self.set_time(scene.frame(), scene.time());
        self.log_visuals(scene)
    }

    /// Sends what is logged so far to the sink at once: for a stream whose
    /// batcher does not flush on its own ([`whole_frames`], the window's),
    /// after a frame's whole drawing, so the view never shows part of one.
    /// (A flush of a stream to the window does not fail; if one did, the
    /// batcher's tick would send the drawing a second later.)
    pub fn send(&self) {
        if let Err(e) = self.rec.flush_async() {
            re_log::warn_once!("sending a frame to the window: {e}");
        }
    }

    /// Logs what the 3D view draws of the scene's current frame (at the
    /// time [`Self::log_frame`] set): the particles, and at level full the
    /// mesh, normals and arrows; the crossings, colliders and bodies.
    pub fn log_visuals(&mut self, scene: &Scene) -> RecordingStreamResult<()> {
        let solver = scene.solver();
        let x = &*scene.world_positions();
        let rec = &self.rec;
        // Particles.
        let colours = color::particles(self.settings.color_by, scene);
        let radius = 0.25 * solver.spec().spacing().0.min(solver.spec().spacing().1);
        rec.log(
            paths::PARTICLES,
            &batch::points(x)
                .with_colors(colours.iter().copied())
                .with_radii([radius]),
        )?;
        if self.framing
            && let Some(points) = framing::points(x)
        {
            rec.log(
                paths::FRAMING,
                &rerun::Points3D::new(points).with_radii([0.0]),
            )?;
        }
        colliders::log_planes(rec, scene, x)?;
        self.log_crossings(scene, radius)?;
        pull::log(&self.rec, scene, x, radius, &mut self.pull_drawn)?;

        if self.settings.level == Level::Full {
            self.log_full(scene, radius)?;
        } else {
            self.blank_full()?;
        }
        self.log_bodies(scene)
    }

    /// Marks where the cloth passes through itself, whatever
    /// self-collision's weight: a red point where each crossing edge meets
    /// its triangle (the crossings measured at the step's end, so at level
    /// summary and full); blanked once there are none.
    fn log_crossings(&mut self, scene: &Scene, radius: f32) -> RecordingStreamResult<()> {
        let local = scene
            .solver()
            .diagnostics()
            .map_or(&[][..], |d| &d.crossing_points[..]);
        if local.is_empty() {
            if std::mem::take(&mut self.crossings_drawn) {
                self.rec.log(paths::CROSSINGS, &batch::points(&[]))?;
            }
            return Ok(());
        }
        let points = scene.to_world(local);
        self.rec.log(
            paths::CROSSINGS,
            &batch::points(&points)
                .with_colors([rerun::Color::from_rgb(255, 40, 40)])
                .with_radii([2.0 * radius]),
        )?;
        self.crossings_drawn = true;
        Ok(())
    }

    /// Logs each body's pose, if it moved since it was last logged (a
    /// static body's once: the viewer holds the latest pose).
    fn log_bodies(&mut self, scene: &Scene) -> RecordingStreamResult<()> {
        let poses = scene.body_poses();
        self.last_poses.resize(poses.len(), None);
        for ((name, pose), last) in scene.body_names().zip(poses).zip(&mut self.last_poses) {
            if *last != Some(*pose) {
                self.rec.log(
                    paths::body(name),
                    &rerun::Transform3D::from_translation_rotation(pose.translation, pose.rotation),
                )?;
                *last = Some(*pose);
            }
        }
        Ok(())
    }

    /// Flushes everything logged so far (to the file or viewer).
    pub fn flush(&self) -> Result<(), rerun::sink::SinkFlushError> {
        if !self.rec.is_enabled() {
            return Ok(()); // Nothing to flush; Rerun would warn.
        }
        self.rec.flush_blocking()
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
