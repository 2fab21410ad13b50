//! Comparing recorded runs: what differs in their inputs, how their figures
//! differ, where their particle states part, a comparison recording for the
//! viewer, and a regression gate for CI.
//!
//! Any `.rrd` weft wrote works: `weft record`, `weft sweep`, and the desktop
//! debugger's session files. Each is read back with [`telemetry::read`](crate::telemetry::read)
//! (Rerun's decoder) into a [`RunData`]:
//!
//! - the **preset diff** flattens each stored preset (with every default
//!   filled in) into dotted keys and lists the keys whose values differ;
//! - the **tuning changes** are the stored parameter sets after the first,
//!   described with [`crate::telemetry::describe_changes`];
//! - the **figures** come from the stored summary; a recording cut short has
//!   none, and its figures are rebuilt from the metrics it holds;
//! - when two runs share everything but their tuning (solver parameters,
//!   wind) and telemetry, their particles are compared frame by frame: the
//!   first logged frame whose positions differ in any bit, and the largest
//!   distance `max_i |x_i^A − x_i^B|` at every frame both logged.
//!
//! [`report`] prints all this, [`recording`] writes the comparison `.rrd`,
//! [`gate`] parses and checks `--fail-if` bounds.

pub mod gate;
pub mod recording;
pub mod report;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::record::{Check, Figures, verdict};
use crate::scene::{Preset, Tuning, load};
use crate::solver::Family;
use crate::telemetry::{describe_changes, paths, read};

/// One recording, read back for comparison.
#[derive(Clone, Debug)]
pub struct RunData {
    /// The run's name: its file name without `.rrd` (made unique among the inputs).
    pub name: String,
    /// The file.
    pub path: PathBuf,
    /// What the file holds.
    pub rec: read::Recording,
    /// The stored preset, if it still loads with this weft.
    pub preset: Option<Preset>,
    /// The stored preset flattened to dotted keys (every default filled in
    /// when it loads).
    pub settings: BTreeMap<String, String>,
    /// The figures: the stored summary, or rebuilt from the metrics of a
    /// recording that was cut short.
    pub figures: Figures,
    /// Whether the recording holds its end-of-run summary.
    pub finished: bool,
    /// The preset's `[expect]` bounds checked against the figures.
    pub checks: Vec<Check>,
    /// Each tuning change after the first: frame and description.
    pub changes: Vec<(i64, String)>,
}

/// Why a recording could not be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] read::ReadError),
    /// It holds no stored preset.
    #[error("{}: not a weft recording, or cut short before its preset was written (it holds no stored preset; weft record, weft sweep and the debugger's session files do)", path.display())]
    NoPreset {
        /// The file.
        path: PathBuf,
    },
    /// Its stored preset is not TOML.
    #[error("{}: the stored preset is not TOML: {source}", path.display())]
    Preset {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        source: toml::de::Error,
    },
    /// Its stored summary does not read as figures.
    #[error("{}: the stored summary is unreadable: {source}", path.display())]
    Summary {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        source: toml::de::Error,
    },
}

impl RunData {
    /// Reads `path`. Fails on a file that is not a Rerun recording or holds no
    /// weft preset.
    pub fn read(path: &Path) -> Result<Self, CompareError> {
        let rec = read::read(path)?;
        let text = rec
            .preset
            .clone()
            .ok_or_else(|| CompareError::NoPreset { path: path.into() })?;
        let table: toml::Table = text.parse().map_err(|source| CompareError::Preset {
            path: path.into(),
            source,
        })?;
        let preset = load::parse(&format!("preset stored in {}", path.display()), &text).ok();
        let full = preset
            .as_ref()
            .and_then(|p| toml::Table::try_from(p).ok())
            .unwrap_or(table);
        let mut settings = BTreeMap::new();
        flatten("", &toml::Value::Table(full), &mut settings);

        let summary = rec.summary.as_deref();
        let finished = summary.is_some();
        let figures = match summary.map(toml::from_str::<Figures>) {
            Some(Ok(f)) => f,
            Some(Err(source)) => {
                return Err(CompareError::Summary {
                    path: path.into(),
                    source,
                });
            }
            None => rebuild_figures(&rec),
        };
        let checks = verdict(preset.as_ref().and_then(|p| p.expect.as_ref()), &figures);

        let mut changes = Vec::new();
        let mut last: Option<Tuning> = None;
        for (frame, text) in &rec.params {
            let Ok(t) = crate::replay::stored_tuning(text) else {
                continue;
            };
            if let Some(old) = &last
                && *old != t
            {
                changes.push((*frame, describe_changes(old, &t)));
            }
            last = Some(t);
        }
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| path.display().to_string());
        Ok(Self {
            name,
            path: path.to_path_buf(),
            rec,
            preset,
            settings,
            figures,
            finished,
            checks,
            changes,
        })
    }

    /// The last frame the recording holds.
    pub fn last_frame(&self) -> i64 {
        self.rec
            .entities
            .values()
            .filter_map(|e| e.frames.last().copied())
            .max()
            .unwrap_or(0)
    }

    /// Whether the run was cut short: no summary, or a truncated file.
    pub fn cut_short(&self) -> bool {
        !self.finished || self.rec.truncated
    }

    /// The verdict in a word or two.
    pub fn verdict(&self) -> String {
        if self.figures.failure.is_some() || !self.figures.finite {
            return "FAILED".into();
        }
        if self.cut_short() {
            return "cut short".into();
        }
        if self.figures.interrupted {
            return "interrupted".into();
        }
        let failed = self.checks.iter().filter(|c| !c.ok).count();
        match (self.checks.is_empty(), failed) {
            (true, _) => "no bounds".into(),
            (false, 0) => "ok".into(),
            (false, n) => format!("FAIL ({n})"),
        }
    }
}

/// Reads every input and makes the names unique (`name`, `name#2`, …).
pub fn read_all(paths: &[PathBuf]) -> Result<Vec<RunData>, CompareError> {
    let mut runs = paths
        .iter()
        .map(|p| RunData::read(p))
        .collect::<Result<Vec<_>, _>>()?;
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for r in &mut runs {
        let n = seen.entry(r.name.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            r.name = format!("{}#{n}", r.name);
        }
    }
    Ok(runs)
}

/// Figures from the metrics a recording holds, for one without a summary.
fn rebuild_figures(rec: &read::Recording) -> Figures {
    let max_of = |path: &str| -> f32 {
        rec.scalars
            .get(path)
            .map(|s| s.iter().map(|x| x.value).fold(0.0, f64::max) as f32)
            .unwrap_or(0.0)
    };
    let frames = rec
        .entities
        .values()
        .filter_map(|e| e.frames.last().copied())
        .max()
        .unwrap_or(0)
        .max(0) as u64;
    let total_ms: f64 = rec
        .scalars
        .get(paths::TIME_TOTAL)
        .map(|s| s.iter().map(|x| x.value).sum())
        .unwrap_or(0.0);
    let failure = rec
        .events
        .iter()
        // A solver failure's event is the `StepError`: `step N (… phase): …`.
        .find(|(_, t)| t.starts_with("step "))
        .map(|(_, t)| t.clone());
    Figures {
        preset: String::new(),
        frames,
        sim_seconds: rec.sim_time.values().copied().fold(0.0, f64::max),
        wall_seconds: total_ms * 1e-3,
        steps_per_second: if total_ms > 0.0 {
            frames as f64 / (total_ms * 1e-3)
        } else {
            0.0
        },
        max_strain: max_of(paths::STRAIN),
        max_violation: Family::ALL
            .iter()
            .map(|f| (f.name().to_string(), max_of(&paths::violation(*f, "max"))))
            .collect(),
        final_kinetic_energy: rec
            .scalars
            .get(paths::ENERGY)
            .and_then(|s| s.last())
            .map(|s| s.value as f32)
            .unwrap_or(0.0),
        finite: failure.is_none(),
        interrupted: true,
        failure,
        final_state: String::new(),
        max_crossings: max_of(paths::SELF_CROSSINGS) as u64,
        crossing_frames: rec
            .scalars
            .get(paths::SELF_CROSSINGS)
            .map_or(0, |s| s.iter().filter(|x| x.value > 0.0).count() as u64),
        final_origin: None,
    }
}

/// Flattens a TOML value into dotted keys (`bodies[0].car.speed`).
pub fn flatten(prefix: &str, value: &toml::Value, out: &mut BTreeMap<String, String>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        toml::Value::Array(a) if a.iter().any(|v| v.is_table()) => {
            for (i, v) in a.iter().enumerate() {
                flatten(&format!("{prefix}[{i}]"), v, out);
            }
        }
        toml::Value::Float(f) => {
            out.insert(prefix.to_string(), (*f as f32).to_string());
        }
        other => {
            out.insert(prefix.to_string(), other.to_string());
        }
    }
}

/// The keys whose values differ between the runs, each with every run's
/// value (`None` where a run does not have the key).
pub fn preset_diff(runs: &[RunData]) -> Vec<(String, Vec<Option<String>>)> {
    let keys: BTreeSet<&String> = runs.iter().flat_map(|r| r.settings.keys()).collect();
    keys.into_iter()
        .filter_map(|k| {
            let values: Vec<Option<String>> =
                runs.iter().map(|r| r.settings.get(k).cloned()).collect();
            (values.iter().any(|v| *v != values[0])).then(|| (k.clone(), values))
        })
        .collect()
}

/// Whether a key may differ between runs whose particle states are still
/// comparable: the tuning (what may change while a scene runs), and what does
/// not touch the simulation (telemetry, bounds, description, duration).
fn is_tuning(key: &str) -> bool {
    Tuning::is_live(key)
        || ["telemetry", "expect", "description", "duration"]
            .iter()
            .any(|s| key == *s || key.starts_with(&format!("{s}.")))
}

/// Why two runs' particle states cannot be compared, if they cannot.
pub fn incomparable(a: &RunData, b: &RunData) -> Option<String> {
    let differs: Vec<&String> = a
        .settings
        .keys()
        .chain(b.settings.keys())
        .filter(|k| !is_tuning(k) && a.settings.get(*k) != b.settings.get(*k))
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    if !differs.is_empty() {
        let mut keys: Vec<&str> = differs.iter().take(4).map(|s| s.as_str()).collect();
        if differs.len() > 4 {
            keys.push("…");
        }
        return Some(format!(
            "their scenes differ beyond the tuning ({})",
            keys.join(", ")
        ));
    }
    let na = a.rec.positions.values().next().map(Vec::len);
    let nb = b.rec.positions.values().next().map(Vec::len);
    match (na, nb) {
        (None, _) | (_, None) => Some("one of them logged no particles (level off)".into()),
        (Some(x), Some(y)) if x != y => Some(format!("{x} and {y} particles")),
        _ => None,
    }
}

/// How two runs' particles compare.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateDiff {
    /// The first frame both logged at which the positions differ in any bit.
    pub first_difference: Option<i64>,
    /// The largest particle distance (metres) at each frame both logged.
    pub per_frame: Vec<(i64, f32)>,
}

/// Compares `b`'s particles with `a`'s at every frame both logged.
pub fn state_diff(a: &RunData, b: &RunData) -> StateDiff {
    let mut out = StateDiff::default();
    for (frame, xa) in &a.rec.positions {
        let Some(xb) = b.rec.positions.get(frame) else {
            continue;
        };
        if xa.len() != xb.len() {
            continue;
        }
        let mut largest = 0.0f32;
        let mut same = true;
        for (p, q) in xa.iter().zip(xb) {
            same &= p.map(f32::to_bits) == q.map(f32::to_bits);
            let d = glam::Vec3::from(*p).distance(glam::Vec3::from(*q));
            largest = largest.max(d);
        }
        if !same && out.first_difference.is_none() {
            out.first_difference = Some(*frame);
        }
        out.per_frame.push((*frame, largest));
    }
    out
}

/// A named figure of a run, for `--fail-if`, `--sort` and the tables.
pub fn figure(f: &Figures, name: &str) -> Option<f64> {
    Some(match name {
        "max_strain" => f.max_strain as f64,
        "final_energy" | "final_kinetic_energy" => f.final_kinetic_energy as f64,
        "steps_per_second" => f.steps_per_second,
        "wall_seconds" => f.wall_seconds,
        "frames" => f.frames as f64,
        "sim_seconds" => f.sim_seconds,
        _ => {
            let family = name.strip_prefix("max_violation.")?;
            *f.max_violation.get(family)? as f64
        }
    })
}

/// Every figure name [`figure`] knows.
pub fn figure_names() -> Vec<String> {
    let mut v: Vec<String> = ["max_strain", "final_energy", "steps_per_second"]
        .map(String::from)
        .to_vec();
    v.extend(
        Family::ALL
            .iter()
            .map(|f| format!("max_violation.{}", f.name())),
    );
    v.extend(["wall_seconds", "frames", "sim_seconds"].map(String::from));
    v
}
