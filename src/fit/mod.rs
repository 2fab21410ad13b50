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
//! [`report`] makes the table and the files at the end.

pub mod distance;
pub mod measure;
pub mod report;
pub mod search;
pub mod space;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::compare::{RunData, flatten};
use crate::record::Figures;
use crate::scene::load::{self, Loaded, Override};
use crate::scene::{Scene, Tuning};
use crate::sweep::grid::{MAX_NAME, Point, safe, short};
use crate::sweep::shard::Shard;
use crate::sweep::{Measure, Measurement, Plan, PointResult, SweepError, is_complete};
use distance::{Target, Terms};
use measure::{Features, Horizon, Lattice, Probe};
use search::{Evaluate, Method};
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
    #[error("{action} {}: {source}", path.display())]
    File {
        /// What was being done.
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
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

fn file(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> FitError {
    let path = path.to_path_buf();
    move |source| FitError::File {
        action,
        path,
        source,
    }
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

/// `fit.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The weft that wrote it, with its solver revision
    /// ([`crate::solver::version`]): points of another solver are not mixed in.
    pub weft: String,
    /// The preset.
    pub preset: String,
    /// The `--set` overrides.
    pub set: Vec<String>,
    /// The varied keys.
    pub vary: Vec<Vary>,
    /// The reference.
    pub reference: Option<ManifestReference>,
    /// The targets.
    pub targets: Vec<Target>,
    /// The budget.
    pub budget: usize,
    /// The seed.
    pub seed: u64,
    /// The optimiser.
    pub method: Method,
    /// Frames per run.
    pub frames: u64,
    /// Simulated seconds per run (absent from a fit made before weft kept
    /// them: `frames` says the same).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f32>,
}

impl Request {
    /// The request a manifest records (to make the fit's report again).
    pub fn of_manifest(m: &Manifest) -> Result<Self, load::OverrideError> {
        Ok(Self {
            preset: m.preset.clone(),
            base: m.set.iter().map(|s| s.parse()).collect::<Result<_, _>>()?,
            vary: m.vary.clone(),
            reference: m.reference.as_ref().map(|r| PathBuf::from(&r.path)),
            reference_weight: m.reference.as_ref().map_or(1.0, |r| r.weight),
            targets: m.targets.clone(),
            budget: m.budget,
            seed: m.seed,
            method: m.method,
            seconds: m.seconds,
        })
    }
}

/// Reads the manifest of the fit in `dir`.
pub fn read_manifest(dir: &Path) -> Result<Manifest, FitError> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(file("reading", &path))?;
    serde_json::from_str(&text).map_err(|e| FitError::Another {
        dir: dir.into(),
        what: format!("{MANIFEST} does not read: {e}"),
    })
}

/// The reference in the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestReference {
    /// The file, as given.
    pub path: String,
    /// Its final state's digest (which run it is).
    pub final_state: String,
    /// Its weight.
    pub weight: f64,
}

/// Creates `dir` and writes the manifest, or checks the one there.
pub fn prepare(dir: &Path, manifest: &Manifest) -> Result<(), FitError> {
    std::fs::create_dir_all(dir).map_err(file("cannot create", dir))?;
    let path = dir.join(MANIFEST);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let mut old: Manifest = serde_json::from_str(&text).map_err(|e| FitError::Another {
                dir: dir.into(),
                what: format!("{MANIFEST} does not read: {e}"),
            })?;
            // A manifest from before weft kept the seconds: its frames decide.
            old.seconds = old.seconds.or(manifest.seconds);
            if old == *manifest {
                return Ok(());
            }
            let what = if old.weft != manifest.weft {
                format!(
                    "written by weft {}, this is weft {}",
                    old.weft, manifest.weft
                )
            } else if old.preset != manifest.preset || old.set != manifest.set {
                "another preset or --set".into()
            } else if old.vary != manifest.vary {
                "other --vary keys or ranges".into()
            } else if old.reference != manifest.reference || old.targets != manifest.targets {
                "another reference or other targets".into()
            } else {
                "another budget, seed, method or length".into()
            };
            Err(FitError::Another {
                dir: dir.into(),
                what,
            })
        }
        Err(_) => write_atomically(
            &path,
            serde_json::to_string_pretty(manifest)
                .expect("manifest serializes")
                .as_bytes(),
        ),
    }
}

fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FitError> {
    let tmp = path.with_extension(format!("part.{}", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(file("writing", &tmp))?;
    std::fs::rename(&tmp, path).map_err(file("renaming into place", &tmp))
}

/// The cache of the reference's features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct CachedReference {
    final_state: String,
    frames: u64,
    /// The lattice as JSON text: compared as text, since a float read back
    /// from JSON may differ from the one written in its last bit.
    lattice: String,
    features: Features,
}

/// The reference's features: re-runs its stored preset for the fit's
/// simulated time (measured like every candidate), or reads them from
/// `dir`'s cache. On the fitted preset's grid, also its shared states for
/// short horizons (a run of the reference, cached or not).
pub fn reference_features(
    fit: &Fit,
    dir: &Path,
) -> Result<(Option<Features>, Option<Arc<Horizon>>), FitError> {
    let Some(r) = &fit.reference else {
        return Ok((None, None));
    };
    let preset = r.run.preset.as_ref().expect("checked in Fit::new");
    let failed = |why: String| FitError::ReferenceRun {
        path: r.run.path.clone(),
        why,
    };
    let frames = Scene::new(preset)
        .map_err(|e| failed(e.to_string()))?
        .frames_in(fit.seconds);
    let same_grid = preset.cloth.weft == fit.start.preset.cloth.weft
        && preset.cloth.warp == fit.start.preset.cloth.warp;
    let path = dir.join(REFERENCE);
    let lattice = serde_json::to_string(&fit.lattice).expect("a lattice serializes");
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(c) = serde_json::from_str::<CachedReference>(&text)
        && c.final_state == r.run.figures.final_state
        && c.frames == frames
        && c.lattice == lattice
    {
        let horizon = if same_grid {
            measure::measure_with(preset, &fit.lattice, fit.seconds, true)
                .map_err(|e| failed(e.to_string()))?
                .1
        } else {
            None
        };
        return Ok((Some(c.features), horizon.map(Arc::new)));
    }
    let (features, horizon) = measure::measure_with(preset, &fit.lattice, fit.seconds, same_grid)
        .map_err(|e| failed(e.to_string()))?;
    let cached = CachedReference {
        final_state: r.run.figures.final_state.clone(),
        frames,
        lattice,
        features,
    };
    let json = serde_json::to_string_pretty(&cached).expect("features serialize");
    write_atomically(&path, json.as_bytes())?;
    // The search reads what is on disk, so that a fit that computed the
    // features and one that found them agree to the bit.
    let text = std::fs::read_to_string(&path).map_err(file("reading", &path))?;
    let back: CachedReference =
        serde_json::from_str(&text).map_err(|e| failed(format!("{REFERENCE}: {e}")))?;
    Ok((Some(back.features), horizon.map(Arc::new)))
}

/// One evaluated point.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// Its index in the fit (0: the start).
    pub index: usize,
    /// The generation that ran it.
    pub generation: usize,
    /// Its name (of its files, under `gen-NNN/`).
    pub name: String,
    /// Each varied key's value, as run.
    pub values: Vec<String>,
    /// Its unit coordinates.
    pub x: Vec<f64>,
    /// Its figures.
    pub figures: Figures,
    /// What it measured.
    pub features: Features,
    /// Its distance.
    pub distance: Distance,
}

/// Why the search stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum Halt {
    /// The budget is spent (or the optimiser converged).
    Done,
    /// Ctrl-C: the points run so far are kept.
    Interrupted,
    /// This shard ran its points of a generation; other shards still run theirs.
    Pending {
        /// The generation.
        generation: usize,
        /// Its points not yet complete.
        missing: usize,
    },
}

/// What the fit reports while it runs.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A generation starts: how many points it runs here, how many were already done.
    Generation {
        /// Its number.
        generation: usize,
        /// Points to run here.
        run: usize,
        /// Points already complete.
        done: usize,
    },
    /// A point finished running.
    Ran {
        /// Its name.
        name: String,
        /// Wall time.
        time: Duration,
    },
    /// A point's distance is known (in index order).
    Evaluated {
        /// Its index.
        index: usize,
        /// Its distance.
        distance: f64,
        /// The best distance so far.
        best: f64,
    },
}

/// How a fit ended.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Why it stopped.
    pub halt: Halt,
    /// Every evaluated point, by index.
    pub points: Vec<Evaluated>,
    /// The reference's features.
    pub reference: Option<Features>,
}

impl Outcome {
    /// The best point: the smallest distance, the first of equals.
    pub fn best(&self) -> Option<&Evaluated> {
        self.points
            .iter()
            .min_by(|a, b| a.distance.total.total_cmp(&b.distance.total))
    }

    /// The start (index 0).
    pub fn start(&self) -> Option<&Evaluated> {
        self.points.first()
    }
}

struct State {
    generation: usize,
    next: usize,
    cache: HashMap<Vec<String>, usize>,
    points: Vec<Evaluated>,
    halt: Option<Halt>,
    errors: Vec<String>,
    failure: Option<FitError>,
}

struct Evaluator<'a> {
    fit: &'a Fit,
    dir: &'a Path,
    shard: Option<Shard>,
    jobs: usize,
    stop: &'a AtomicBool,
    dry: bool,
    reference: Option<&'a Features>,
    horizon: Option<Arc<Horizon>>,
    progress: Mutex<&'a mut (dyn FnMut(Progress) + Send)>,
    state: Mutex<State>,
}

impl Evaluator<'_> {
    fn tell(&self, p: Progress) {
        (self.progress.lock().expect("progress lock"))(p)
    }

    /// Runs the new points of a generation and reads every point's result
    /// back; `None` when the search must stop (`state.halt` says why).
    fn generation(&self, points: &[Vec<f64>]) -> Option<Vec<f64>> {
        let mut st = self.state.lock().expect("state lock");
        if st.halt.is_some() {
            return None;
        }
        let texts: Vec<Vec<String>> = points
            .iter()
            .map(|x| {
                self.fit
                    .vary
                    .iter()
                    .zip(x)
                    .map(|(v, &x)| v.at(x).1)
                    .collect()
            })
            .collect();
        let mut new: Vec<usize> = Vec::new();
        for (k, t) in texts.iter().enumerate() {
            if !st.cache.contains_key(t) && !new.iter().any(|&n| texts[n] == *t) {
                new.push(k);
            }
        }
        let room = self.fit.budget.saturating_sub(st.next);
        let truncated = new.len() > room;
        new.truncate(room);
        if !new.is_empty() {
            let generation = st.generation;
            let first = st.next;
            let list: Vec<Point> = new
                .iter()
                .enumerate()
                .map(|(n, &k)| self.point(first + n, &texts[k], &points[k]))
                .collect();
            drop(st);
            let ran = self.run_generation(generation, &list);
            st = self.state.lock().expect("state lock");
            match ran {
                Err(e) => {
                    st.failure = Some(e);
                    st.halt = Some(Halt::Done);
                    return None;
                }
                Ok(Some(halt)) => {
                    st.halt = Some(halt);
                    return None;
                }
                Ok(None) => {}
            }
            let dir = self.generation_dir(generation);
            for (n, &k) in new.iter().enumerate() {
                let index = first + n;
                let name = &list[n].name;
                match self.read_point(&dir, name) {
                    Ok((figures, features)) => {
                        let distance = self.fit.distance(&features, &figures, self.reference);
                        let d = distance.total;
                        st.points.push(Evaluated {
                            index,
                            generation,
                            name: name.clone(),
                            values: texts[k].clone(),
                            x: points[k].clone(),
                            figures,
                            features,
                            distance,
                        });
                        st.cache.insert(texts[k].clone(), index);
                        let best = st
                            .points
                            .iter()
                            .map(|p| p.distance.total)
                            .fold(f64::INFINITY, f64::min);
                        drop(st);
                        self.tell(Progress::Evaluated {
                            index,
                            distance: d,
                            best,
                        });
                        st = self.state.lock().expect("state lock");
                    }
                    Err(e) => {
                        st.failure = Some(e);
                        st.halt = Some(Halt::Done);
                        return None;
                    }
                }
            }
            st.next = first + new.len();
            st.generation += 1;
        }
        if truncated {
            st.halt = Some(Halt::Done);
            return None;
        }
        Some(
            texts
                .iter()
                .map(|t| st.points[st.cache[t]].distance.total)
                .collect(),
        )
    }

    fn generation_dir(&self, generation: usize) -> PathBuf {
        self.dir.join(format!("gen-{generation:03}"))
    }

    fn point(&self, index: usize, texts: &[String], _x: &[f64]) -> Point {
        let mut name = format!("{index:03}");
        for (v, t) in self.fit.vary.iter().zip(texts) {
            name += &format!("_{}={t}", short(&v.key));
        }
        let mut name = safe(&name);
        name.truncate(MAX_NAME);
        Point {
            index,
            name,
            settings: self
                .fit
                .vary
                .iter()
                .zip(texts)
                .map(|(v, t)| (v.key.clone(), t.clone()))
                .collect(),
            overrides: self.fit.overrides_of(texts),
        }
    }

    /// Runs a generation's points as a sweep (this shard's, if sharded);
    /// `Some(halt)` if not all of them are complete afterwards.
    fn run_generation(&self, generation: usize, list: &[Point]) -> Result<Option<Halt>, FitError> {
        let dir = self.generation_dir(generation);
        let mut plan = Plan::of_points(
            &self.fit.preset,
            list.to_vec(),
            Some(self.fit.frames),
            None,
            "off",
        )?;
        let (lattice, frames) = (self.fit.lattice.clone(), self.fit.frames);
        let horizon = self.horizon.clone();
        plan.measurement = Some(Measurement(Arc::new(move |scene: &Scene| {
            Box::new(Probe::new(lattice.clone(), frames, scene).with_horizon(horizon.clone()))
                as Box<dyn Measure>
        })));
        if self.dry {
            let missing = list.iter().filter(|p| !is_complete(&dir, &p.name)).count();
            return Ok((missing > 0).then_some(Halt::Pending {
                generation,
                missing,
            }));
        }
        let outcome =
            crate::sweep::run(&plan, &dir, self.shard, self.jobs, self.stop, |p| match p {
                crate::sweep::Progress::Start { total, skipped } => {
                    self.tell(Progress::Generation {
                        generation,
                        run: total - skipped,
                        done: skipped,
                    })
                }
                crate::sweep::Progress::Done(r, t) => self.tell(Progress::Ran {
                    name: r.name.clone(),
                    time: t,
                }),
                crate::sweep::Progress::Error(_) => {}
            })?;
        if !outcome.errors.is_empty() {
            return Err(FitError::Points(outcome.errors));
        }
        let missing = list.iter().filter(|p| !is_complete(&dir, &p.name)).count();
        if missing == 0 {
            return Ok(None);
        }
        if self.stop.load(Ordering::Relaxed) {
            return Ok(Some(Halt::Interrupted));
        }
        Ok(Some(Halt::Pending {
            generation,
            missing,
        }))
    }

    fn read_point(&self, dir: &Path, name: &str) -> Result<(Figures, Features), FitError> {
        let path = dir.join(format!("{name}.json"));
        let text = std::fs::read_to_string(&path).map_err(file("reading", &path))?;
        let bad = |e: serde_json::Error| FitError::File {
            action: "reading",
            path: path.clone(),
            source: std::io::Error::other(e),
        };
        let result: PointResult = serde_json::from_str(&text).map_err(bad)?;
        let features: Features =
            serde_json::from_value(result.measured.unwrap_or_default()).map_err(bad)?;
        Ok((result.figures, features))
    }
}

impl Evaluate for Evaluator<'_> {
    fn evaluate(&self, points: &[Vec<f64>]) -> Option<Vec<f64>> {
        self.generation(points)
    }
}

/// Runs (or resumes) a fit in `dir`: the points of `shard` (all without
/// one) on `jobs` threads; no new point starts once `stop` is set. A `dry`
/// fit runs nothing: it goes as far as the points on disk take it.
pub fn run(
    fit: &Fit,
    dir: &Path,
    shard: Option<Shard>,
    jobs: usize,
    stop: &AtomicBool,
    dry: bool,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<Outcome, FitError> {
    prepare(dir, &fit.manifest())?;
    let (reference, horizon) = reference_features(fit, dir)?;
    let eval = Evaluator {
        fit,
        dir,
        shard,
        jobs,
        stop,
        dry,
        reference: reference.as_ref(),
        horizon,
        progress: Mutex::new(progress),
        state: Mutex::new(State {
            generation: 0,
            next: 0,
            cache: HashMap::new(),
            points: Vec::new(),
            halt: None,
            errors: Vec::new(),
            failure: None,
        }),
    };
    search::search(fit.method, &fit.start_point(), fit.seed, fit.budget, &eval)?;
    let st = eval.state.into_inner().expect("state lock");
    if let Some(e) = st.failure {
        return Err(e);
    }
    if !st.errors.is_empty() {
        return Err(FitError::Points(st.errors));
    }
    Ok(Outcome {
        halt: st.halt.unwrap_or(Halt::Done),
        points: st.points,
        reference,
    })
}
