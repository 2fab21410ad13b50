//! `sweep.json`, the sweep's manifest: the preset, the axes, frames, level
//! and every point; written before the first point runs and checked when a
//! sweep resumes, so that a directory holding another sweep is refused.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::storage::file;
use super::{MANIFEST, SweepError};

/// The manifest, `sweep.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The weft that wrote it, with its solver revision
    /// ([`crate::solver::version`]): points of another solver are not mixed in.
    pub weft: String,
    /// The preset.
    pub preset: String,
    /// Frames per point, if fixed.
    pub frames: Option<u64>,
    /// Seconds per point, if given.
    pub seconds: Option<f32>,
    /// Telemetry level.
    pub level: String,
    /// The axes: key and values as written.
    pub axes: Vec<ManifestAxis>,
    /// Every point.
    pub points: Vec<ManifestPoint>,
}

/// One axis in the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestAxis {
    /// Dotted key.
    pub key: String,
    /// Values, as written.
    pub values: Vec<String>,
}

/// One point in the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestPoint {
    /// Index in grid order.
    pub index: usize,
    /// Name (of its files).
    pub name: String,
    /// Key → value, as written.
    pub settings: Vec<(String, String)>,
}

/// Creates `dir` and writes the manifest, or checks that the one there is
/// this sweep's. Nothing in `dir` is removed or overwritten otherwise.
pub fn prepare(dir: &Path, manifest: &Manifest) -> Result<(), SweepError> {
    std::fs::create_dir_all(dir).map_err(file("cannot create", dir))?;
    let path = dir.join(MANIFEST);
    let json = serde_json::to_string_pretty(manifest).expect("manifest serializes");
    match std::fs::read_to_string(&path) {
        Ok(old) => {
            let old: Manifest =
                serde_json::from_str(&old).map_err(|source| SweepError::Manifest {
                    path: path.clone(),
                    source,
                })?;
            if old != *manifest {
                let what = if old.weft != manifest.weft {
                    format!(
                        "written by weft {}, this is weft {}: its results may differ",
                        old.weft, manifest.weft
                    )
                } else if old.preset != manifest.preset {
                    format!("preset {} instead of {}", old.preset, manifest.preset)
                } else if old.axes != manifest.axes {
                    "other --set values".to_string()
                } else if old.points != manifest.points {
                    "other points".to_string()
                } else {
                    "other frames, seconds or level".to_string()
                };
                return Err(SweepError::Another {
                    dir: dir.into(),
                    what,
                });
            }
            Ok(())
        }
        Err(_) => {
            // Several shards may start at once: each writes through its own
            // temporary name, and the renames all put the same bytes in place.
            let tmp = dir.join(format!(".{MANIFEST}.{}", std::process::id()));
            std::fs::write(&tmp, &json).map_err(file("cannot write in", dir))?;
            Ok(std::fs::rename(&tmp, &path).map_err(file("writing", &path))?)
        }
    }
}
