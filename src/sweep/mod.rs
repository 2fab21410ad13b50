//! Sweeps: one preset run headless at every point of a grid of settings.
//!
//! A [`Plan`] is the preset, the [`grid`] of `--set` axes, the number of
//! frames and the telemetry level. Every point is validated (loaded with its
//! overrides) before anything runs. Each point is an independent,
//! deterministic run ([`run_point`]) whose files live under the output
//! directory, named after the point:
//!
//! | file | what |
//! |---|---|
//! | `sweep.json` | the manifest: preset, axes, frames, level, every point's index, name and settings |
//! | `NAME.rrd` | the point's recording (level `summary` unless `--level`) |
//! | `NAME.json` | the point's settings, figures and `[expect]` checks |
//! | `NAME.rrd.part`, `NAME.json.part` | a point being written (or cut off): renamed when complete |
//!
//! A point is complete when `NAME.json` exists and reads back, and
//! `NAME.rrd` exists; the JSON is renamed into place last. Re-running the
//! same sweep skips complete points, so an interrupted sweep resumes. The
//! manifest must match: a directory holding another sweep is refused.
//!
//! Points run on `--jobs` threads; since each point is a run of its own and
//! the solver is bit-identical for any thread count, the results do not
//! depend on `--jobs`, on the order the points finish, or on the [`shard`]
//! that ran them. [`collect`] reads a finished (or partial) sweep back.
//!
//! A plan need not be a grid: [`Plan::of_points`] takes any list of points
//! (`weft fit` runs each generation of its search as one), and a plan's
//! [`Measurement`] may watch every frame of every point and store what it
//! measured in the point's `NAME.json` (`measured`).

pub mod collect;
pub mod grid;
mod manifest;
pub mod shard;
pub mod storage;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::record::{Check, Figures, Run, verdict};
use crate::scene::{Loaded, Override, Scene, load};
use crate::telemetry::{self, Telemetry, blueprint};
use grid::{Axis, Point};
pub use manifest::{Manifest, ManifestAxis, ManifestPoint, prepare};
use shard::Shard;
pub use storage::part_path;
use storage::{FileError, file, write_atomically};

/// Above this many points (in this shard), a sweep asks for `--yes`.
pub const MAX_POINTS: usize = 256;
/// Above this estimated duration (of this shard), a sweep asks for `--yes`.
pub const MAX_SECONDS: f64 = 3600.0;

/// The manifest's file name.
pub const MANIFEST: &str = "sweep.json";

/// What a sweep runs.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Preset file or shipped name.
    pub preset: String,
    /// The axes, in command-line order.
    pub axes: Vec<Axis>,
    /// Frames per point (`None`: each point's preset `duration`).
    pub frames: Option<u64>,
    /// Seconds per point, if given instead of frames.
    pub seconds: Option<f32>,
    /// Telemetry level of each point's recording.
    pub level: String,
    /// Every point, in order, loaded.
    pub points: Vec<(Point, Loaded)>,
    /// What each point measures besides its figures, if anything.
    pub measurement: Option<Measurement>,
}

/// Watches a point's run frame by frame and says what it measured.
pub trait Measure {
    /// Called after every frame (and once before the first, at frame 0).
    fn frame(&mut self, scene: &Scene);
    /// What was measured, stored as the point's `measured`.
    fn finish(self: Box<Self>, scene: &Scene) -> serde_json::Value;
}

/// Makes a [`Measure`] for a point's scene.
pub type MakeMeasure = dyn Fn(&Scene) -> Box<dyn Measure> + Send + Sync;

/// Makes a fresh [`Measure`] for each point's scene.
#[derive(Clone)]
pub struct Measurement(pub Arc<MakeMeasure>);

impl std::fmt::Debug for Measurement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Measurement")
    }
}

/// What a finished point wrote to `NAME.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// Index in grid order.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Key → value, as written.
    pub settings: Vec<(String, String)>,
    /// The run's figures.
    pub figures: Figures,
    /// The preset's `[expect]` bounds, checked.
    pub checks: Vec<Check>,
    /// What the plan's [`Measurement`] measured, if it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured: Option<serde_json::Value>,
}

impl PointResult {
    /// `FAILED`, `ok`, `FAIL (n)` or `no bounds`.
    pub fn verdict(&self) -> String {
        if self.figures.failure.is_some() || !self.figures.finite {
            return "FAILED".into();
        }
        let failed = self.checks.iter().filter(|c| !c.ok).count();
        match (self.checks.is_empty(), failed) {
            (true, _) => "no bounds".into(),
            (false, 0) => "ok".into(),
            (false, n) => format!("FAIL ({n})"),
        }
    }
}

impl Plan {
    /// Builds and validates the plan: every point must load.
    pub fn new(
        preset: &str,
        axes: Vec<Axis>,
        frames: Option<u64>,
        seconds: Option<f32>,
        level: &str,
    ) -> Result<Self, SweepError> {
        grid::check(&axes)?;
        if let Some(s) = seconds
            && !(s.is_finite() && s > 0.0)
        {
            return Err(SweepError::Seconds(s));
        }
        let mut plan = Self::of_points(preset, grid::points(&axes), frames, seconds, level)?;
        plan.axes = axes;
        Ok(plan)
    }

    /// A plan of the given points (not necessarily a grid), each validated.
    pub fn of_points(
        preset: &str,
        list: Vec<Point>,
        frames: Option<u64>,
        seconds: Option<f32>,
        level: &str,
    ) -> Result<Self, SweepError> {
        if let Some(s) = seconds
            && !(s.is_finite() && s > 0.0)
        {
            return Err(SweepError::Seconds(s));
        }
        let level_set = Override {
            key: "telemetry.level".into(),
            value: toml::Value::String(level.into()),
        };
        let mut points = Vec::new();
        for p in list {
            let mut sets = p.overrides.clone();
            sets.push(level_set.clone());
            let loaded = load::load(preset, &sets).map_err(|source| {
                let at = p
                    .settings
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                SweepError::Point {
                    index: p.index,
                    at,
                    source: Box::new(source),
                }
            })?;
            points.push((p, loaded));
        }
        Ok(Self {
            preset: preset.into(),
            axes: Vec::new(),
            frames,
            seconds,
            level: level.into(),
            points,
            measurement: None,
        })
    }

    /// The manifest of this plan.
    pub fn manifest(&self) -> Manifest {
        Manifest {
            weft: crate::solver::version(),
            preset: self.preset.clone(),
            frames: self.frames,
            seconds: self.seconds,
            level: self.level.clone(),
            axes: self
                .axes
                .iter()
                .map(|a| ManifestAxis {
                    key: a.key.clone(),
                    values: a.texts.clone(),
                })
                .collect(),
            points: self
                .points
                .iter()
                .map(|(p, _)| ManifestPoint {
                    index: p.index,
                    name: p.name.clone(),
                    settings: p.settings.clone(),
                })
                .collect(),
        }
    }

    /// The frames a point runs.
    pub fn frames_of(&self, loaded: &Loaded, scene: &Scene) -> u64 {
        match (self.frames, self.seconds) {
            (Some(n), _) => n,
            (None, Some(s)) => scene.frames_in(s),
            (None, None) => scene.frames_in(loaded.preset.duration),
        }
    }

    /// Estimated wall seconds for the points of `shard` on `jobs` threads:
    /// a few frames of up to [`SAMPLES`] points spread over the grid are
    /// timed here (without telemetry), since points differ in cost.
    pub fn estimate(&self, shard: Option<Shard>, jobs: usize) -> f64 {
        let mine: Vec<&(Point, Loaded)> = self
            .points
            .iter()
            .filter(|(p, _)| shard.is_none_or(|s| s.contains(p.index)))
            .collect();
        if mine.is_empty() {
            return 0.0;
        }
        let frames_of = |l: &Loaded| -> u64 {
            match (self.frames, self.seconds) {
                (Some(n), _) => n,
                (None, Some(s)) => (s / l.preset.solver.dt).round().max(1.0) as u64,
                (None, None) => (l.preset.duration / l.preset.solver.dt).round().max(1.0) as u64,
            }
        };
        let picks = SAMPLES.min(mine.len());
        let mut seconds = 0.0;
        for k in 0..picks {
            let (_, loaded) = mine[k * (mine.len() - 1) / (picks - 1).max(1)];
            let start = Instant::now();
            let Ok(mut scene) = Scene::new(&loaded.preset) else {
                continue;
            };
            let setup = start.elapsed().as_secs_f64();
            let sample = 3.min(frames_of(loaded));
            let start = Instant::now();
            for _ in 0..sample {
                if scene.step().is_err() {
                    break;
                }
            }
            let per_frame = start.elapsed().as_secs_f64() / sample.max(1) as f64;
            seconds += setup + per_frame * frames_of(loaded) as f64;
        }
        seconds / picks as f64 * mine.len() as f64 / jobs.clamp(1, mine.len()) as f64
    }
}

/// How many points [`Plan::estimate`] times.
pub const SAMPLES: usize = 6;

/// Why a sweep could not be planned, run or written.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A `--set` axis that does not parse.
    #[error(transparent)]
    Axis(#[from] grid::AxisError),
    /// `--seconds` not a positive number.
    #[error("--seconds {0}: expected a positive number of seconds")]
    Seconds(f32),
    /// A point of the grid whose preset does not load.
    #[error("{source}\n  (at point {index} of the sweep: {at})")]
    Point {
        /// The point's index.
        index: usize,
        /// Its settings, `key=value, …`.
        at: String,
        /// Why its preset does not load.
        source: Box<crate::scene::PresetError>,
    },
    /// A file or directory that could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// A manifest that is not a sweep's.
    #[error("{}: not a weft sweep manifest ({source}); use another --out", path.display())]
    Manifest {
        /// The manifest.
        path: PathBuf,
        /// What the parser said.
        source: serde_json::Error,
    },
    /// The output directory holds another sweep.
    #[error("{} holds another sweep ({what}); its points are kept: use another --out, or delete it to start over", dir.display())]
    Another {
        /// The directory.
        dir: PathBuf,
        /// How the sweeps differ.
        what: String,
    },
    /// A point's scene could not be built.
    #[error("{point}: {source}")]
    Setup {
        /// The point's name.
        point: String,
        /// Why.
        source: Box<crate::solver::SetupError>,
    },
    /// A point's run could not be logged or finished.
    #[error("{point}: {source}")]
    Run {
        /// The point's name.
        point: String,
        /// Why.
        source: Box<crate::record::RunError>,
    },
    /// A point's recording could not be started.
    #[error("cannot write {}: {source}", path.display())]
    Recording {
        /// The file.
        path: PathBuf,
        /// What Rerun said.
        source: rerun::RecordingStreamError,
    },
    /// Rerun's batching could not be set up.
    #[error(transparent)]
    Batching(#[from] rerun::log::ChunkBatcherError),
}

/// Whether the point's files are complete.
pub fn is_complete(dir: &Path, name: &str) -> bool {
    let json = dir.join(format!("{name}.json"));
    dir.join(format!("{name}.rrd")).is_file()
        && std::fs::read_to_string(json)
            .ok()
            .and_then(|t| serde_json::from_str::<PointResult>(&t).ok())
            .is_some()
}

/// Runs one point and writes its files. A solver failure is a result (in the
/// figures), not an error; errors are about files.
pub fn run_point(
    plan: &Plan,
    point: &Point,
    loaded: &Loaded,
    dir: &Path,
) -> Result<PointResult, SweepError> {
    let rrd = dir.join(format!("{}.rrd", point.name));
    let part = part_path(&rrd);
    let scene = Scene::new(&loaded.preset).map_err(|source| SweepError::Setup {
        point: point.name.clone(),
        source: Box::new(source),
    })?;
    let frames = plan.frames_of(loaded, &scene);
    let batching = telemetry::file_batching()?;
    let stream = rerun::RecordingStreamBuilder::new("weft")
        .batcher_config(batching)
        .save(&part)
        .and_then(|s| blueprint::send_default(&s).map(|()| s))
        .map_err(|source| SweepError::Recording {
            path: part.clone(),
            source,
        })?;
    let telemetry = Telemetry::new(stream.clone(), loaded.preset.telemetry);
    let run_error = |source| SweepError::Run {
        point: point.name.clone(),
        source: Box::new(source),
    };
    let mut run =
        Run::start(scene, telemetry, &plan.preset, &loaded.resolved).map_err(run_error)?;
    let mut measure = plan.measurement.as_ref().map(|m| (m.0)(&run.scene));
    if let Some(m) = &mut measure {
        m.frame(&run.scene);
    }
    let mut outcome = Ok(());
    for _ in 0..frames {
        outcome = run.step();
        if outcome.is_err() {
            break;
        }
        if let Some(m) = &mut measure {
            m.frame(&run.scene);
        }
    }
    if let Err(e @ crate::record::RunError::Telemetry(_)) = outcome {
        return Err(run_error(e));
    }
    let measured = measure.map(|m| m.finish(&run.scene));
    // `finish` flushes the file; only a complete one is renamed into place.
    let figures = run.finish().map_err(run_error)?;
    drop(stream);
    std::fs::rename(&part, &rrd).map_err(file("renaming into place", &part))?;
    let checks = verdict(loaded.preset.expect.as_ref(), &figures);
    let result = PointResult {
        index: point.index,
        name: point.name.clone(),
        settings: point.settings.clone(),
        figures,
        checks,
        measured,
    };
    let json = serde_json::to_string_pretty(&result).expect("result serializes");
    write_atomically(&dir.join(format!("{}.json", point.name)), json.as_bytes())?;
    Ok(result)
}

/// What the sweep reports while it runs.
#[derive(Clone, Debug)]
pub enum Progress {
    /// How many points this shard has, and how many were already complete.
    Start {
        /// Points in this shard.
        total: usize,
        /// Already complete (skipped).
        skipped: usize,
    },
    /// A point finished.
    Done(Box<PointResult>, Duration),
    /// A point could not be written.
    Error(String),
}

/// How a sweep ended.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    /// Points run now.
    pub ran: usize,
    /// Points skipped as already complete.
    pub skipped: usize,
    /// Points not run because of `stop`.
    pub left: usize,
    /// Points that could not be written.
    pub errors: Vec<String>,
}

/// Runs the points of `shard` (all without one) that are not complete in
/// `dir`, on `jobs` threads; no new point starts once `stop` is set.
pub fn run(
    plan: &Plan,
    dir: &Path,
    shard: Option<Shard>,
    jobs: usize,
    stop: &AtomicBool,
    mut progress: impl FnMut(Progress),
) -> Result<Outcome, SweepError> {
    prepare(dir, &plan.manifest())?;
    let mine: Vec<&(Point, Loaded)> = plan
        .points
        .iter()
        .filter(|(p, _)| shard.is_none_or(|s| s.contains(p.index)))
        .collect();
    let todo: Vec<&(Point, Loaded)> = mine
        .iter()
        .copied()
        .filter(|(p, _)| !is_complete(dir, &p.name))
        .collect();
    let mut outcome = Outcome {
        skipped: mine.len() - todo.len(),
        ..Outcome::default()
    };
    progress(Progress::Start {
        total: mine.len(),
        skipped: outcome.skipped,
    });
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel();
    std::thread::scope(|s| {
        for _ in 0..jobs.clamp(1, todo.len().max(1)) {
            let tx = tx.clone();
            let (todo, next) = (&todo, &next);
            s.spawn(move || {
                loop {
                    if stop.load(Ordering::Relaxed) {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some((point, loaded)) = todo.get(k) else {
                        break;
                    };
                    let start = Instant::now();
                    let r = run_point(plan, point, loaded, dir);
                    if tx.send(r.map(|r| (r, start.elapsed()))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for r in rx {
            match r {
                Ok((r, t)) => {
                    outcome.ran += 1;
                    progress(Progress::Done(Box::new(r), t));
                }
                Err(e) => {
                    let e = e.to_string();
                    outcome.errors.push(e.clone());
                    progress(Progress::Error(e));
                }
            }
        }
    });
    outcome.left = todo.len() - outcome.ran - outcome.errors.len();
    Ok(outcome)
}
