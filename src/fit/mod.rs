//! Fits: the values of some live keys that bring a preset closest to a
//! reference run or to target figures (`weft fit`).
//!
//! A [`Fit`] is the preset (with its `--set` overrides), the varied keys
//! ([`space`]), the reference recording and the target figures
//! ([`distance`]), the budget of runs, the seed and the optimiser
//! ([`search`]). Everything is checked before anything runs.
//!
//! The search asks for points one generation at a time; each generation is
//! a sweep of those points ([`crate::sweep::Plan::of_points`]) in its own
//! directory, so it runs on `--jobs` threads or as the shards of a Slurm
//! array job, and every point keeps its files (`NAME.json` holds its
//! figures and what the fit's [`measure::Probe`] measured). The search
//! reads every answer back from those files, so a fit that is interrupted,
//! resumed, or run shard by shard sees the same numbers, bit for bit, as
//! one that ran straight through:
//!
//! | file | what |
//! |---|---|
//! | `fit.json` | the manifest: preset, overrides, varied keys, reference, targets, budget, seed, optimiser, frames |
//! | `reference.json` | the reference's features (measured once, by re-running its stored preset) |
//! | `gen-NNN/` | generation `NNN`: a sweep directory, one point per candidate (`INDEX_KEY=VALUE…`) |
//! | `fitted.toml` | the fitted preset (`weft show`, `weft gui` load it) |
//! | `start.rrd`, `fitted.rrd`, `comparison.rrd` | the start and the fit recorded, and `weft compare`'s recording of them beside the reference |
//!
//! Here: what a fit is ([`Fit`], checked from a [`Request`]) and its
//! errors; `manifest.rs` writes and checks `fit.json`, `reference.rs` measures
//! and caches the reference, `evaluate.rs` runs the generations and reads
//! their points back ([`run`]); [`report`] makes the table and the files at
//! the end.

pub mod distance;
mod evaluate;
mod manifest;
pub mod measure;
mod reference;
pub mod report;
pub mod search;
pub mod space;

pub use evaluate::{Evaluated, Halt, Outcome, Progress, run};
pub use manifest::{Manifest, ManifestReference, prepare, read_manifest};
pub use reference::reference_features;

use std::path::{Path, PathBuf};

use crate::compare::{RunData, flatten};
use crate::record::Figures;
use crate::scene::load::{self, Loaded, Override};
use crate::scene::{Scene, Tuning};
use crate::sweep::SweepError;
use crate::sweep::storage::{FileError, file};
use distance::{Target, Terms};
use measure::{Features, Lattice};
use search::Method;
use space::Vary;

/// The manifest's file name.
pub const MANIFEST: &str = "fit.json";
/// The cached reference features' file name.
pub const REFERENCE: &str = "reference.json";
/// The distance of a run that failed or went non-finite.
pub const FAILED: f64 = 1e9;

/// Why a fit cannot start, run or finish.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// A `--vary` that is wrong.
    #[error(transparent)]
    Vary(#[from] space::VaryError),
    /// The preset (with `--set`) does not load.
    #[error(transparent)]
    Preset(#[from] Box<load::PresetError>),
    /// No `--vary`.
    #[error("nothing to fit: give at least one --vary KEY=LO..HI")]
    NoVary,
    /// Neither `--to` nor `--target`.
    #[error("nothing to fit to: give --to REFERENCE.rrd or at least one --target FIGURE=VALUE")]
    NoTarget,
    /// `--budget 0`.
    #[error("--budget 0: a fit needs at least 1 run (the start); e.g. --budget 64")]
    Budget,
    /// `--seconds` not positive.
    #[error("--seconds {0}: expected a positive number of seconds")]
    Seconds(f32),
    /// The preset's scene cannot be built.
    #[error("{preset}: {why}")]
    Setup {
        /// The preset.
        preset: String,
        /// Why.
        why: String,
    },
    /// `--to-weight` not positive.
    #[error("--to-weight {0}: expected a positive weight")]
    Weight(f64),
    /// The reference recording cannot be read.
    #[error("--to {}: {source}", path.display())]
    Reference {
        /// The file.
        path: PathBuf,
        /// Why.
        source: Box<crate::compare::CompareError>,
    },
    /// The reference's stored preset does not load with this weft.
    #[error("--to {}: its stored preset does not load with this weft; record the reference again", .0.display())]
    ReferencePreset(PathBuf),
    /// The reference is a run of another scene.
    #[error("--to {}: a run of another scene than {preset} ({}); a fit compares runs of one scene, which may differ only in resolution (cloth.weft, cloth.warp), the solver's settings and the wind", path.display(), keys.join(", "))]
    Family {
        /// The file.
        path: PathBuf,
        /// The fitted preset.
        preset: String,
        /// The keys that differ.
        keys: Vec<String>,
    },
    /// The reference was tuned while it ran.
    #[error("--to {}: its settings changed while it ran ({} changes, e.g. at frame {frame}); fit to a run of fixed settings (weft record)", path.display(), count)]
    ReferenceTuned {
        /// The file.
        path: PathBuf,
        /// How many changes.
        count: usize,
        /// The first change's frame.
        frame: i64,
    },
    /// The reference's scene failed to build or step.
    #[error("--to {}: re-running its stored preset failed: {why}", path.display())]
    ReferenceRun {
        /// The file.
        path: PathBuf,
        /// Why.
        why: String,
    },
    /// The output directory holds another fit.
    #[error("{} holds another fit ({what}); its points are kept: use another --out, or delete it to start over", dir.display())]
    Another {
        /// The directory.
        dir: PathBuf,
        /// How the fits differ.
        what: String,
    },
    /// A file that could not be read or written.
    #[error(transparent)]
    File(#[from] FileError),
    /// A generation's sweep could not be planned or run.
    #[error(transparent)]
    Sweep(#[from] SweepError),
    /// Points that could not be run or written.
    #[error("{} point(s) could not be run or written: {}", .0.len(), .0.join("; "))]
    Points(Vec<String>),
    /// argmin failed.
    #[error(transparent)]
    Search(#[from] search::SearchError),
    /// The comparison recording could not be written.
    #[error("writing the comparison {}: {source}", path.display())]
    Comparison {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: anyhow::Error,
    },
}

/// The reference run a fit compares with.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The recording, read back.
    pub run: RunData,
    /// Its weight in the distance.
    pub weight: f64,
}

/// What the user asked for, checked.
#[derive(Clone, Debug)]
pub struct Fit {
    /// Preset file or shipped name.
    pub preset: String,
    /// The `--set` overrides every run gets.
    pub base: Vec<Override>,
    /// The varied keys.
    pub vary: Vec<Vary>,
    /// The reference, if any.
    pub reference: Option<Reference>,
    /// The target figures.
    pub targets: Vec<Target>,
    /// At most this many runs.
    pub budget: usize,
    /// The optimiser's seed.
    pub seed: u64,
    /// The optimiser.
    pub method: Method,
    /// Simulated seconds per run.
    pub seconds: f32,
    /// Frames per run (of the fitted preset).
    pub frames: u64,
    /// The material points every run is measured at.
    pub lattice: Lattice,
    /// The preset with its overrides, at the start values.
    pub start: Loaded,
}

/// What the user asked for, unchecked (the command line's options).
#[derive(Clone, Debug)]
pub struct Request {
    /// Preset file or shipped name.
    pub preset: String,
    /// `--set` overrides.
    pub base: Vec<Override>,
    /// `--vary`.
    pub vary: Vec<Vary>,
    /// `--to`.
    pub reference: Option<PathBuf>,
    /// `--to-weight`.
    pub reference_weight: f64,
    /// `--target`.
    pub targets: Vec<Target>,
    /// `--budget`.
    pub budget: usize,
    /// `--seed`.
    pub seed: u64,
    /// `--method`.
    pub method: Method,
    /// `--seconds` (default: the preset's duration).
    pub seconds: Option<f32>,
}

impl Fit {
    /// Checks a request: the keys and ranges, the reference and targets, the
    /// budget. Runs nothing.
    pub fn new(req: Request) -> Result<Self, FitError> {
        if req.vary.is_empty() {
            return Err(FitError::NoVary);
        }
        if req.reference.is_none() && req.targets.is_empty() {
            return Err(FitError::NoTarget);
        }
        if req.budget == 0 {
            return Err(FitError::Budget);
        }
        if !(req.reference_weight.is_finite() && req.reference_weight > 0.0) {
            return Err(FitError::Weight(req.reference_weight));
        }
        let start = load::load(&req.preset, &req.base).map_err(Box::new)?;
        let mut vary = req.vary;
        space::check(&req.preset, &req.base, &mut vary)?;
        let seconds = req.seconds.unwrap_or(start.preset.duration);
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(FitError::Seconds(seconds));
        }
        let scene = Scene::new(&start.preset).map_err(|e| FitError::Setup {
            preset: req.preset.clone(),
            why: e.to_string(),
        })?;
        let frames = scene.frames_in(seconds);
        let lattice = Lattice::of(&scene);
        let reference = match req.reference {
            None => None,
            Some(path) => Some(Reference {
                run: check_reference(&path, &req.preset, &start)?,
                weight: req.reference_weight,
            }),
        };
        Ok(Self {
            preset: req.preset,
            base: req.base,
            vary,
            reference,
            targets: req.targets,
            budget: req.budget,
            seed: req.seed,
            method: req.method,
            seconds,
            frames,
            lattice,
            start,
        })
    }

    /// The start's unit coordinates: each key's value in the preset, in its range.
    pub fn start_point(&self) -> Vec<f64> {
        let live = space::live_numbers(&self.start.preset);
        self.vary
            .iter()
            .map(|v| {
                let value = match live.get(&v.key) {
                    Some(toml::Value::Float(f)) => *f,
                    Some(toml::Value::Integer(n)) => *n as f64,
                    _ => v.lo,
                };
                v.unit(value)
            })
            .collect()
    }

    /// The manifest of this fit.
    pub fn manifest(&self) -> Manifest {
        Manifest {
            weft: crate::solver::version(),
            preset: self.preset.clone(),
            set: self
                .base
                .iter()
                .map(|o| format!("{}={}", o.key, o.value))
                .collect(),
            vary: self.vary.clone(),
            reference: self.reference.as_ref().map(|r| ManifestReference {
                path: r.run.path.display().to_string(),
                final_state: r.run.figures.final_state.clone(),
                weight: r.weight,
            }),
            targets: self.targets.clone(),
            budget: self.budget,
            seed: self.seed,
            method: self.method,
            frames: self.frames,
            seconds: Some(self.seconds),
        }
    }

    /// The overrides of a point: `--set`, then each varied key at its
    /// value (as run: the text the point's name and file give).
    pub fn overrides_of(&self, texts: &[String]) -> Vec<Override> {
        let mut sets = self.base.clone();
        for (v, t) in self.vary.iter().zip(texts) {
            let value = if v.integer {
                toml::Value::Integer(t.parse().expect("an integer's text"))
            } else {
                toml::Value::Float(t.parse::<f32>().expect("a float's text") as f64)
            };
            sets.push(Override {
                key: v.key.clone(),
                value,
            });
        }
        sets
    }

    /// The distance of a run with these features and figures, given the
    /// reference's features.
    pub fn distance(
        &self,
        features: &Features,
        figures: &Figures,
        reference: Option<&Features>,
    ) -> Distance {
        let terms = reference.map(|r| Terms {
            horizon: features.horizon.unwrap_or(0.0),
            ..distance::between(features, r, self.lattice.length)
        });
        let values: Vec<f64> = self
            .targets
            .iter()
            .map(|t| distance::figure_of(features, figures, &t.figure).unwrap_or(f64::NAN))
            .collect();
        let failed = !features.finite || !figures.finite || figures.failure.is_some();
        let mut total = terms.map_or(0.0, |t| {
            t.total() * self.reference.as_ref().map_or(1.0, |r| r.weight)
        });
        for (t, v) in self.targets.iter().zip(&values) {
            total += t.weight * t.miss(*v);
        }
        if failed || !total.is_finite() {
            total = FAILED;
        }
        Distance {
            total,
            terms,
            values,
            failed,
        }
    }
}

/// A reference that can be compared with `preset`: it reads, its stored
/// preset loads, it is a run of the same scene (only the resolution, the
/// tuning, telemetry and bounds may differ), and it was not retuned.
fn check_reference(path: &Path, preset: &str, start: &Loaded) -> Result<RunData, FitError> {
    let run = RunData::read(path).map_err(|source| FitError::Reference {
        path: path.into(),
        source: Box::new(source),
    })?;
    if run.preset.is_none() {
        return Err(FitError::ReferencePreset(path.into()));
    }
    let table = toml::Table::try_from(&start.preset).expect("a preset serializes");
    let mut ours = std::collections::BTreeMap::new();
    flatten("", &toml::Value::Table(table), &mut ours);
    let free = |k: &str| {
        Tuning::is_live(k)
            || ["cloth.weft", "cloth.warp", "description", "duration"].contains(&k)
            || ["telemetry", "expect"]
                .iter()
                .any(|s| k == *s || k.starts_with(&format!("{s}.")))
    };
    let mut keys: Vec<String> = ours
        .keys()
        .chain(run.settings.keys())
        .filter(|k| !free(k) && ours.get(*k) != run.settings.get(*k))
        .cloned()
        .collect();
    keys.sort();
    keys.dedup();
    if !keys.is_empty() {
        return Err(FitError::Family {
            path: path.into(),
            preset: preset.into(),
            keys,
        });
    }
    if let Some((frame, _)) = run.changes.first() {
        return Err(FitError::ReferenceTuned {
            path: path.into(),
            count: run.changes.len(),
            frame: *frame,
        });
    }
    Ok(run)
}

/// A run's distance, with its parts.
#[derive(Clone, Debug, PartialEq)]
pub struct Distance {
    /// The weighted total the search minimises.
    pub total: f64,
    /// The terms of the distance to the reference, if there is one.
    pub terms: Option<Terms>,
    /// Each target figure's value.
    pub values: Vec<f64>,
    /// Whether the run failed or went non-finite.
    pub failed: bool,
}
