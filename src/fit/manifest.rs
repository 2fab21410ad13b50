//! `fit.json`, the fit's manifest: what a fit is, written before it runs and
//! checked when it resumes; read back to make its page again.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::distance::Target;
use super::search::Method;
use super::space::Vary;
use super::{FitError, MANIFEST, Request};
use crate::scene::load;
use crate::sweep::storage::{file, write_shared};

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
        Err(_) => Ok(write_shared(
            &path,
            serde_json::to_string_pretty(manifest)
                .expect("manifest serializes")
                .as_bytes(),
        )?),
    }
}
