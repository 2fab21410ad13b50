//! The end of a fit: the table (start, fitted, reference), the fitted
//! preset, and the start and the fit recorded beside the reference in
//! `weft compare`'s comparison recording.

use std::path::{Path, PathBuf};

use super::{Evaluated, Fit, FitError, Outcome, file};
use crate::compare::recording::{self, Placement};
use crate::compare::report::grid;
use crate::compare::{RunData, read_all};
use crate::scene::load;
use crate::sweep::grid::Point;
use crate::sweep::{Plan, is_complete, run_point};

/// The fitted preset's file name.
pub const FITTED: &str = "fitted.toml";
/// The comparison recording's file name.
pub const COMPARISON: &str = "comparison.rrd";

fn number(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.4e}")
    } else {
        format!("{v:.4}")
    }
}

/// The table: every varied key and target figure, and the distance (with
/// its terms against a reference), for the start, the fit and the reference.
pub fn table(fit: &Fit, outcome: &Outcome) -> String {
    let (Some(best), (header, rows)) = (outcome.best(), rows(fit, outcome)) else {
        return "no point was evaluated\n".into();
    };
    let ran = outcome.points.len();
    format!(
        "{}{} run(s) of a budget of {}; best at run #{} (generation {})\n",
        grid(&header, &rows),
        ran,
        fit.budget,
        best.index,
        best.generation
    )
}

/// The table's header and rows (none before a point is evaluated).
pub fn rows(fit: &Fit, outcome: &Outcome) -> (Vec<String>, Vec<Vec<String>>) {
    let (Some(start), Some(best)) = (outcome.start(), outcome.best()) else {
        return (Vec::new(), Vec::new());
    };
    let reference = fit.reference.as_ref();
    let mut header = vec![
        String::new(),
        "start".to_string(),
        format!("fitted (#{})", best.index),
    ];
    if let Some(r) = reference {
        header.push(format!("reference ({})", r.run.name));
    }
    let mut rows = Vec::new();
    for (k, v) in fit.vary.iter().enumerate() {
        let mut row = vec![
            v.key.clone(),
            start.values[k].clone(),
            best.values[k].clone(),
        ];
        if let Some(r) = reference {
            row.push(r.run.settings.get(&v.key).cloned().unwrap_or("–".into()));
        }
        rows.push(row);
    }
    for (k, t) in fit.targets.iter().enumerate() {
        let mut row = vec![
            format!("{} (target {t})", t.figure),
            number(start.distance.values[k]),
            number(best.distance.values[k]),
        ];
        if reference.is_some() {
            let value = outcome.reference.as_ref().and_then(|f| {
                super::distance::figure_of(f, &reference.expect("some").run.figures, &t.figure)
            });
            row.push(value.map_or("–".into(), number));
        }
        rows.push(row);
    }
    if reference.is_some() {
        let term = |e: &Evaluated, f: fn(&super::Terms) -> f64| {
            e.distance
                .terms
                .as_ref()
                .map_or("–".into(), |t| number(f(t)))
        };
        type Term = fn(&super::Terms) -> f64;
        let terms: [(&str, Term); 7] = [
            ("  shape (of L)", |t| t.shape),
            ("  spread (of L)", |t| t.spread),
            ("  edge amplitude (relative)", |t| t.amplitude),
            ("  edge frequency (octaves)", |t| t.frequency),
            ("  drape coefficient", |t| t.drape),
            ("  mean strain (relative, same grid only)", |t| t.strain),
            ("  short horizon (of L, same grid only)", |t| t.horizon),
        ];
        rows.push(vec![
            "distance to the reference".into(),
            term(start, |t| t.total()),
            term(best, |t| t.total()),
            "0".into(),
        ]);
        for (name, f) in terms {
            rows.push(vec![name.into(), term(start, f), term(best, f), "0".into()]);
        }
    }
    let mut total = vec![
        "distance (weighted total)".to_string(),
        number(start.distance.total),
        number(best.distance.total),
    ];
    if reference.is_some() {
        total.push("0".into());
    }
    rows.push(total);
    (header, rows)
}

/// Writes the fitted preset to `dir/fitted.toml` (`weft show` and
/// `weft gui` load it); returns its path.
pub fn write_fitted(fit: &Fit, best: &Evaluated, dir: &Path) -> Result<PathBuf, FitError> {
    let loaded = load::load(&fit.preset, &fit.overrides_of(&best.values)).map_err(Box::new)?;
    let mut text = format!(
        "# Fitted by weft fit from {}: {}\n# distance {} (run #{} of {})\n",
        fit.preset,
        fit.vary
            .iter()
            .zip(&best.values)
            .map(|(v, t)| format!("{}={t}", v.key))
            .collect::<Vec<_>>()
            .join(", "),
        number(best.distance.total),
        best.index,
        fit.budget,
    );
    text += &load::to_toml(&loaded.preset);
    let path = dir.join(FITTED);
    std::fs::write(&path, text).map_err(file("writing", &path))?;
    Ok(path)
}

/// Records the start and the fit (telemetry level `full`, the fit's
/// length) as `dir/start.rrd` and `dir/fitted.rrd`, then writes the
/// comparison of them and the reference to `dir/comparison.rrd`.
pub fn write_comparison(
    fit: &Fit,
    outcome: &Outcome,
    dir: &Path,
    table: &str,
) -> Result<PathBuf, FitError> {
    let (Some(start), Some(best)) = (outcome.start(), outcome.best()) else {
        return Err(FitError::Points(vec!["no point was evaluated".into()]));
    };
    let points: Vec<Point> = [("start", start), ("fitted", best)]
        .iter()
        .enumerate()
        .map(|(index, (name, e))| Point {
            index,
            name: name.to_string(),
            settings: fit
                .vary
                .iter()
                .zip(&e.values)
                .map(|(v, t)| (v.key.clone(), t.clone()))
                .collect(),
            overrides: fit.overrides_of(&e.values),
        })
        .collect();
    let plan = Plan::of_points(&fit.preset, points, Some(fit.frames), None, "full")?;
    for (point, loaded) in &plan.points {
        if !is_complete(dir, &point.name) {
            run_point(&plan, point, loaded, dir)?;
        }
    }
    let mut files = vec![dir.join("start.rrd"), dir.join("fitted.rrd")];
    if let Some(r) = &fit.reference {
        files.push(r.run.path.clone());
    }
    let path = dir.join(COMPARISON);
    let failed = |source: anyhow::Error| FitError::Comparison {
        path: path.clone(),
        source,
    };
    let runs: Vec<RunData> = read_all(&files).map_err(|e| failed(e.into()))?;
    let text = format!("{table}\n{}", crate::compare::report::report(&runs));
    let rec = recording::open(&runs, Some(&path), None).map_err(failed)?;
    recording::write(&rec, &runs, Placement::SideBySide(None), &text).map_err(failed)?;
    drop(rec);
    Ok(path)
}
