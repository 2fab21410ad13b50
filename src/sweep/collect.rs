//! `weft sweep --collect DIR`: every finished point's inputs, figures and
//! verdict in one table, sorted by a figure, as text, CSV, JSON or Markdown.

use std::path::{Path, PathBuf};

use super::{MANIFEST, Manifest, PointResult};
use crate::compare::{figure, figure_names, report::grid};
use crate::solver::Family;

/// A collected sweep.
#[derive(Clone, Debug, Default)]
pub struct Collected {
    /// The manifest, if the directory has one.
    pub manifest: Option<Manifest>,
    /// The finished points.
    pub points: Vec<PointResult>,
    /// Points of the manifest with no complete files.
    pub missing: Vec<String>,
}

/// Output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Aligned columns.
    Text,
    /// Comma-separated values.
    Csv,
    /// A JSON array of points.
    Json,
    /// A Markdown table.
    Markdown,
}

/// Why a sweep's results could not be read or sorted.
#[derive(Debug, thiserror::Error)]
pub enum CollectError {
    /// A file or the directory could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The manifest does not parse.
    #[error("{}: {source}", path.display())]
    Manifest {
        /// The manifest.
        path: PathBuf,
        /// What the parser said.
        source: serde_json::Error,
    },
    /// Neither a manifest nor a finished point.
    #[error("{}: no weft sweep here (no {MANIFEST} and no finished point)", .0.display())]
    NoSweep(PathBuf),
    /// `--sort` by something that is neither a figure nor a swept key.
    #[error("--sort {key}: not a figure or a swept key; figures: {}; swept: {}", figure_names().join(", "), swept.join(", "))]
    SortKey {
        /// The key given.
        key: String,
        /// The swept keys.
        swept: Vec<String>,
    },
}

/// Reads every finished point in `dir`.
pub fn read(dir: &Path) -> Result<Collected, CollectError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| CollectError::Io { path, source }
    };
    let entries = std::fs::read_dir(dir).map_err(io(dir))?;
    let manifest =
        match std::fs::read_to_string(dir.join(MANIFEST)) {
            Ok(t) => Some(serde_json::from_str::<Manifest>(&t).map_err(|source| {
                CollectError::Manifest {
                    path: dir.join(MANIFEST),
                    source,
                }
            })?),
            Err(_) => None,
        };
    let mut points = Vec::new();
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|x| x == "json")
                && p.file_name().is_some_and(|n| n != MANIFEST)
        })
        .collect();
    files.sort();
    for f in files {
        let text = std::fs::read_to_string(&f).map_err(io(&f))?;
        let Ok(p) = serde_json::from_str::<PointResult>(&text) else {
            continue;
        };
        if dir.join(format!("{}.rrd", p.name)).is_file() {
            points.push(p);
        }
    }
    if points.is_empty() && manifest.is_none() {
        return Err(CollectError::NoSweep(dir.into()));
    }
    let missing = manifest
        .iter()
        .flat_map(|m| &m.points)
        .filter(|mp| !points.iter().any(|p| p.name == mp.name))
        .map(|mp| mp.name.clone())
        .collect();
    Ok(Collected {
        manifest,
        points,
        missing,
    })
}

/// The keys `--sort` accepts besides the figures: `index`, `name`, and each
/// swept key (full or its last segment).
fn sort_value(p: &PointResult, key: &str) -> Result<SortKey, CollectError> {
    if key == "index" {
        return Ok(SortKey::Number(p.index as f64));
    }
    if key == "name" {
        return Ok(SortKey::Text(p.name.clone()));
    }
    if let Some(v) = figure(&p.figures, key) {
        // A failed run sorts after every finished one.
        let v = if p.figures.failure.is_some() || !v.is_finite() {
            f64::INFINITY
        } else {
            v
        };
        return Ok(SortKey::Number(v));
    }
    let setting = p
        .settings
        .iter()
        .find(|(k, _)| k == key || k.rsplit('.').next() == Some(key));
    match setting {
        Some((_, v)) => Ok(match v.parse::<f64>() {
            Ok(x) => SortKey::Number(x),
            Err(_) => SortKey::Text(v.clone()),
        }),
        None => Err(CollectError::SortKey {
            key: key.to_string(),
            swept: p.settings.iter().map(|(k, _)| k.clone()).collect(),
        }),
    }
}

#[derive(Clone, Debug, PartialEq, PartialOrd)]
enum SortKey {
    Number(f64),
    Text(String),
}

/// Sorts the points by `key`, ascending (or descending), ties by index.
pub fn sort(points: &mut [PointResult], key: &str, descending: bool) -> Result<(), CollectError> {
    let mut keyed = Vec::new();
    for p in points.iter() {
        keyed.push((sort_value(p, key)?, p.index));
    }
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        let o = keyed[a]
            .0
            .partial_cmp(&keyed[b].0)
            .unwrap_or(std::cmp::Ordering::Equal);
        let o = if descending { o.reverse() } else { o };
        // Failed runs (infinite) stay last either way.
        let failed = |k: &SortKey| matches!(k, SortKey::Number(x) if x.is_infinite());
        failed(&keyed[a].0)
            .cmp(&failed(&keyed[b].0))
            .then(o)
            .then(keyed[a].1.cmp(&keyed[b].1))
    });
    let sorted: Vec<PointResult> = order.iter().map(|&i| points[i].clone()).collect();
    points.clone_from_slice(&sorted);
    Ok(())
}

/// The columns: name, each swept key, the figures, the verdict, the digest.
fn table(points: &[PointResult]) -> (Vec<String>, Vec<Vec<String>>) {
    let keys: Vec<String> = points
        .first()
        .map(|p| p.settings.iter().map(|(k, _)| k.clone()).collect())
        .unwrap_or_default();
    let mut header = vec!["name".to_string()];
    header.extend(keys.iter().cloned());
    header.push("max_strain".into());
    header.extend(
        Family::ALL
            .iter()
            .map(|f| format!("max_violation.{}", f.name())),
    );
    header.extend(
        [
            "final_energy",
            "steps_per_second",
            "frames",
            "verdict",
            "final_state",
        ]
        .map(String::from),
    );
    let rows = points
        .iter()
        .map(|p| {
            let f = &p.figures;
            let mut r = vec![p.name.clone()];
            r.extend(keys.iter().map(|k| {
                p.settings
                    .iter()
                    .find(|(pk, _)| pk == k)
                    .map(|(_, v)| v.clone())
                    .unwrap_or_default()
            }));
            r.push(format!("{:.5}", f.max_strain));
            for fam in Family::ALL {
                r.push(format!(
                    "{:.5}",
                    f.max_violation.get(fam.name()).copied().unwrap_or(0.0)
                ));
            }
            r.push(format!("{:.4e}", f.final_kinetic_energy));
            r.push(format!("{:.1}", f.steps_per_second));
            r.push(f.frames.to_string());
            r.push(p.verdict());
            r.push(f.final_state.clone());
            r
        })
        .collect();
    (header, rows)
}

fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The points as a table in `format`.
pub fn render(points: &[PointResult], format: Format) -> String {
    let (header, rows) = table(points);
    match format {
        Format::Text => grid(&header, &rows),
        Format::Csv => std::iter::once(&header)
            .chain(&rows)
            .map(|r| r.iter().map(|c| csv_cell(c)).collect::<Vec<_>>().join(",") + "\n")
            .collect(),
        Format::Markdown => {
            let line = |r: &[String]| format!("| {} |\n", r.join(" | "));
            let mut s = line(&header);
            s += &line(&header.iter().map(|_| "---".to_string()).collect::<Vec<_>>());
            for r in &rows {
                s += &line(r);
            }
            s
        }
        Format::Json => {
            let points: Vec<serde_json::Value> = points
                .iter()
                .map(|p| {
                    let mut v = serde_json::to_value(p).expect("point serializes");
                    v["verdict"] = serde_json::Value::String(p.verdict());
                    v
                })
                .collect();
            serde_json::to_string_pretty(&points).expect("json") + "\n"
        }
    }
}
