//! Headless recording: run a scene, stream its telemetry, keep the figures a
//! CI job needs, and judge them against the preset's `[expect]` table.
//!
//! [`Run`] drives one scene frame by frame. It is shared by `weft record`,
//! `weft replay` and the desktop app, so a parameter change reaches the
//! recording at the frame it takes effect, whoever made it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::scene::{Scene, Tuning, preset::Expect};
use crate::solver::{Family, Params, StepError};
use crate::telemetry::{Collect, Telemetry, paths};

/// What a run measured.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Figures {
    /// The preset's name or path.
    pub preset: String,
    /// Frames stepped.
    pub frames: u64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Wall-clock seconds spent stepping and logging.
    pub wall_seconds: f64,
    /// Frames per wall-clock second.
    pub steps_per_second: f64,
    /// Largest edge strain seen at any frame.
    pub max_strain: f32,
    /// Largest violation seen at any frame, per family.
    pub max_violation: std::collections::BTreeMap<String, f32>,
    /// Kinetic energy at the last frame, in joules.
    pub final_kinetic_energy: f32,
    /// Whether the state stayed finite.
    pub finite: bool,
    /// Whether the run was interrupted (Ctrl-C) before its last frame.
    pub interrupted: bool,
    /// The solver failure that ended the run, if any.
    pub failure: Option<String>,
    /// Digest of the final state (see `ClothState::digest`), in hex.
    pub final_state: String,
    /// The most edges of the cloth crossing one of its triangles at any
    /// measured frame (the cloth passing through itself; measured at every
    /// frame with diagnostics, whatever self-collision's weight).
    pub max_crossings: u64,
    /// How many measured frames had a crossing edge.
    pub crossing_frames: u64,
    /// The solver's floating origin at the last frame, in world
    /// coordinates (none in a recording made before weft had one).
    pub final_origin: Option<[f64; 3]>,
}

impl Figures {
    /// Counts a measured frame with `n` crossing edges.
    fn count_crossings(&mut self, n: usize) {
        self.max_crossings = self.max_crossings.max(n as u64);
        self.crossing_frames += u64::from(n > 0);
    }
}

/// One `[expect]` bound checked against the figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// The bound, as written in the preset (`expect.max_strain`).
    pub bound: String,
    /// The limit.
    pub limit: f64,
    /// What the run measured.
    pub value: f64,
    /// Whether the run stayed within it.
    pub ok: bool,
}

/// Checks `figures` against a preset's `[expect]` bounds (none without them).
pub fn verdict(expect: Option<&Expect>, figures: &Figures) -> Vec<Check> {
    let Some(expect) = expect else {
        return Vec::new();
    };
    let mut checks = Vec::new();
    let mut check = |bound: String, limit: f32, value: f32| {
        checks.push(Check {
            bound,
            limit: limit as f64,
            value: value as f64,
            ok: value <= limit,
        })
    };
    if let Some(limit) = expect.max_strain {
        check("expect.max_strain".into(), limit, figures.max_strain);
    }
    for f in Family::ALL {
        if let Some(limit) = expect.max_violation[f] {
            let value = figures.max_violation.get(f.name()).copied().unwrap_or(0.0);
            check(format!("expect.max_violation.{}", f.name()), limit, value);
        }
    }
    if let Some(limit) = expect.settle_energy {
        check(
            "expect.settle_energy".into(),
            limit,
            figures.final_kinetic_energy,
        );
    }
    if let Some(limit) = expect.max_crossings {
        checks.push(Check {
            bound: "expect.max_crossings".into(),
            limit,
            value: figures.max_crossings as f64,
            ok: figures.max_crossings as f64 <= limit,
        });
    }
    if expect.finite {
        checks.push(Check {
            bound: "expect.finite".into(),
            limit: 1.0,
            value: if figures.finite { 1.0 } else { 0.0 },
            ok: figures.finite,
        });
    }
    checks
}

/// How a run ended early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The solver failed; the failure was logged and the recording closed.
    #[error("solver failure at frame {frame}: {error}")]
    Solver {
        /// The frame that failed.
        frame: u64,
        /// What failed.
        error: StepError,
    },
    /// Writing telemetry failed.
    #[error("telemetry: {0}")]
    Telemetry(#[from] rerun::RecordingStreamError),
    /// The recording could not be written out in full.
    #[error("telemetry: {0}")]
    Flush(#[from] rerun::sink::SinkFlushError),
}

/// A scene being stepped and recorded.
pub struct Run {
    /// The scene.
    pub scene: Scene,
    /// Where its telemetry goes.
    pub telemetry: Telemetry,
    figures: Figures,
    wall: std::time::Duration,
    /// What the solver collects at every step, whatever the telemetry logs
    /// ([`Run::diagnose_every_step`]).
    every_step: Collect,
}

impl Run {
    /// Starts a run: logs static data, the initial parameters and the
    /// scene's current frame (frame 0 for a new scene).
    pub fn start(
        mut scene: Scene,
        telemetry: Telemetry,
        name: &str,
        resolved: &str,
    ) -> Result<Self, RunError> {
        telemetry.configure(scene.solver_mut());
        let mut run = Self {
            figures: Figures {
                preset: name.to_string(),
                finite: true,
                max_violation: Family::ALL
                    .iter()
                    .map(|f| (f.name().to_string(), 0.0))
                    .collect(),
                ..Figures::default()
            },
            scene,
            telemetry,
            wall: std::time::Duration::ZERO,
            every_step: Collect::default(),
        };
        run.telemetry.log_static(&run.scene, resolved)?;
        let tuning = run.scene.tuning();
        let (frame, time) = (run.scene.frame(), run.scene.time());
        run.telemetry.log_tuning(frame, time, &tuning)?;
        run.telemetry.log_frame(&run.scene)?;
        Ok(run)
    }

    /// Applies new parameters from the next step on; they are logged at the
    /// frame that step produces.
    pub fn set_params(&mut self, params: Params) -> Result<(), crate::solver::ParamError> {
        self.scene.set_params(params)
    }

    /// Applies new live settings (parameters and wind) from the next step on.
    pub fn set_tuning(&mut self, tuning: &Tuning) -> Result<(), crate::solver::ParamError> {
        self.scene.set_tuning(tuning)
    }

    /// Has the solver collect `what` at every step, whatever the telemetry
    /// logs (the desktop debugger's readouts, and its particle inspector).
    /// A step collects at least what the frame it produces logs
    /// ([`Telemetry::collects_for_step`]).
    pub fn diagnose_every_step(&mut self, what: Collect) {
        self.every_step = what;
    }

    /// Steps one frame and logs it.
    pub fn step(&mut self) -> Result<(), RunError> {
        let start = Instant::now();
        let frame = self.scene.frame() + 1;
        let time = self.scene.time() + self.scene.solver().params().dt as f64;
        let tuning = self.scene.tuning();
        self.telemetry.log_tuning(frame, time, &tuning)?;
        self.telemetry
            .collects_for_step(frame)
            .or(self.every_step)
            .apply(self.scene.solver_mut());
        if let Err(error) = self.scene.step() {
            self.figures.finite = false;
            self.figures.failure = Some(error.to_string());
            self.telemetry.log_failure(frame, time, &error)?;
            return Err(RunError::Solver { frame, error });
        }
        self.measure();
        self.telemetry.log_frame(&self.scene)?;
        self.wall += start.elapsed();
        Ok(())
    }

    fn measure(&mut self) {
        measure(&mut self.figures, &self.scene);
    }

    /// A copy of the run's state (scene and figures), to resume from later.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            scene: self.scene.clone(),
            figures: self.figures.clone(),
        }
    }

    /// Continues a run from `snapshot` into new telemetry: logs the static
    /// data, the tuning and the snapshot's frame, as [`Run::start`] does at
    /// frame 0. Its figures go on from the snapshot's.
    pub fn resume(
        snapshot: Snapshot,
        telemetry: Telemetry,
        name: &str,
        resolved: &str,
    ) -> Result<Self, RunError> {
        let Snapshot { scene, figures } = snapshot;
        let mut run = Self::start(scene, telemetry, name, resolved)?;
        run.figures = Figures {
            preset: name.to_string(),
            ..figures
        };
        Ok(run)
    }

    /// Steps `frames` frames, or until `stop` is set; `tick` is called after each.
    pub fn run(
        &mut self,
        frames: u64,
        stop: &AtomicBool,
        mut tick: impl FnMut(u64),
    ) -> Result<(), RunError> {
        for _ in 0..frames {
            if stop.load(Ordering::Relaxed) {
                self.figures.interrupted = true;
                break;
            }
            self.step()?;
            tick(self.scene.frame());
        }
        Ok(())
    }

    /// The figures so far.
    pub fn figures(&self) -> Figures {
        let mut f = self.figures.clone();
        let solver = self.scene.solver();
        f.frames = self.scene.frame();
        f.sim_seconds = self.scene.time();
        f.wall_seconds = self.wall.as_secs_f64();
        f.steps_per_second = if f.wall_seconds > 0.0 {
            f.frames as f64 / f.wall_seconds
        } else {
            0.0
        };
        f.final_kinetic_energy = solver.kinetic_energy();
        f.final_state = format!("{:016x}", solver.state().digest());
        f.final_origin = Some(solver.frame().origin.to_array());
        f
    }

    /// Logs the summary of the run so far (what `weft replay` checks against).
    pub fn log_summary(&self) -> Result<Figures, RunError> {
        let figures = self.figures();
        self.log_figures(&figures)?;
        Ok(figures)
    }

    fn log_figures(&self, figures: &Figures) -> Result<(), RunError> {
        let text = toml::to_string(figures).expect("figures serialize");
        self.telemetry.stream().log_static(
            paths::SUMMARY,
            &rerun::TextDocument::new(text).with_media_type(rerun::MediaType::plain_text()),
        )?;
        Ok(())
    }

    /// Logs the end-of-run summary, flushes, and returns the figures.
    pub fn finish(self) -> Result<Figures, RunError> {
        let (figures, written) = self.close();
        written.map(|()| figures)
    }

    /// [`Run::finish`], the figures kept whether or not the recording took
    /// them (a recording that failed is still reported).
    pub fn close(self) -> (Figures, Result<(), RunError>) {
        let figures = self.figures();
        let written = self
            .log_figures(&figures)
            .and_then(|()| Ok(self.telemetry.flush()?));
        (figures, written)
    }
}

/// A run's state at one frame: the scene and the figures so far.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// The scene.
    pub scene: Scene,
    figures: Figures,
}

impl Snapshot {
    /// Steps one frame without logging, keeping the figures exactly as
    /// [`Run::step`] would.
    pub fn advance(&mut self) -> Result<(), StepError> {
        self.scene.step()?;
        measure(&mut self.figures, &self.scene);
        Ok(())
    }
}

/// Folds the solver's state after a step into the running figures. The
/// crossings come from the diagnostics; without them they are counted only
/// for a bound that asks for them.
fn measure(f: &mut Figures, scene: &Scene) {
    let solver = scene.solver();
    let (strain, violations) = match solver.diagnostics() {
        Some(d) => (d.max_strain, d.families.map(|_, fd| fd.violation.max)),
        None => (
            solver.max_strain(),
            solver.measured_violations().map(|_, v| v.max),
        ),
    };
    f.max_strain = f.max_strain.max(strain);
    let bounded = (scene.preset().expect.as_ref()).is_some_and(|e| e.max_crossings.is_some());
    match solver.diagnostics() {
        Some(d) => {
            if let Some(n) = d.self_crossings {
                f.count_crossings(n);
            }
        }
        None if bounded => f.count_crossings(solver.self_crossings()),
        None => {}
    }
    for (fam, &v) in violations.iter() {
        let slot = f.max_violation.entry(fam.name().to_string()).or_insert(0.0);
        *slot = slot.max(v);
    }
}

/// A plain-text table of the figures and checks, for the terminal.
pub fn table(figures: &Figures, checks: &[Check]) -> String {
    let mut s = String::new();
    let status = if figures.failure.is_some() {
        "FAILED"
    } else if figures.interrupted {
        "interrupted"
    } else {
        "done"
    };
    s += &format!(
        "{status}: {} frames ({:.2} s simulated) in {:.2} s, {:.1} steps/s\n",
        figures.frames, figures.sim_seconds, figures.wall_seconds, figures.steps_per_second
    );
    s += &format!(
        "  {:<28} {:>12}\n",
        "max strain",
        format!("{:.4}", figures.max_strain)
    );
    for (family, v) in &figures.max_violation {
        s += &format!(
            "  {:<28} {:>12}\n",
            format!("max violation {family}"),
            format!("{v:.4}")
        );
    }
    s += &format!(
        "  {:<28} {:>12}\n",
        "max crossing edges", figures.max_crossings
    );
    s += &format!(
        "  {:<28} {:>12}\n",
        "frames with crossings", figures.crossing_frames
    );
    s += &format!(
        "  {:<28} {:>12}\n",
        "final kinetic energy (J)",
        format!("{:.3e}", figures.final_kinetic_energy)
    );
    if let Some(f) = &figures.failure {
        s += &format!("  failure: {f}\n");
    }
    if !checks.is_empty() {
        s += &format!(
            "  {:<32} {:>12} {:>12}  verdict\n",
            "expect", "limit", "measured"
        );
        for c in checks {
            s += &format!(
                "  {:<32} {:>12} {:>12}  {}\n",
                c.bound,
                format!("{:.4e}", c.limit),
                format!("{:.4e}", c.value),
                if c.ok { "ok" } else { "FAIL" }
            );
        }
    }
    s
}
