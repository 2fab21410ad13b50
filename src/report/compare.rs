//! A comparison's page: the figures over time for each run, the first
//! frame where their particles part, what differs in their inputs, and
//! their figures side by side.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::page::{Cell, Page, code, esc};
use super::plot::{self, Labels, Mark, Series, number};
use super::{ReportError, figures, file_link, violation_unit};
use crate::compare::{RunData, figure, incomparable, preset_diff, read_all, state_diff};
use crate::solver::Family;
use crate::telemetry::paths;

/// The comparison's manifest, beside its page: which files were compared
/// (absolute paths, so that the page can be made again from anywhere).
pub const MANIFEST: &str = "compare.json";

/// `compare.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The weft that compared them, with its solver revision.
    pub weft: String,
    /// The command that made the comparison.
    pub command: String,
    /// The recordings, the baseline first.
    pub files: Vec<PathBuf>,
}

impl Manifest {
    /// The manifest of a comparison of `files` made by `command`.
    pub fn new(command: String, files: &[PathBuf]) -> Self {
        Self {
            weft: crate::solver::version(),
            command,
            files: files
                .iter()
                .map(|f| std::fs::canonicalize(f).unwrap_or_else(|_| f.clone()))
                .collect(),
        }
    }

    /// Writes it to `dir/compare.json`.
    pub fn write(&self, dir: &Path) -> Result<(), ReportError> {
        let path = dir.join(MANIFEST);
        let json = serde_json::to_string_pretty(self).expect("a manifest serializes");
        crate::sweep::storage::write_shared(&path, json.as_bytes())?;
        Ok(())
    }
}

/// A run's series at `path` against simulated time (frames when the
/// recording holds no time).
fn over_time(r: &RunData, path: &str) -> Vec<(f64, f64)> {
    r.rec
        .scalars
        .get(path)
        .map(|s| {
            s.iter()
                .map(|x| {
                    let t = r.rec.sim_time.get(&x.frame).copied();
                    (t.unwrap_or(x.frame as f64), x.value)
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The comparison's page.
pub fn page(runs: &[RunData], manifest: &Manifest, dir: &Path) -> Result<String, ReportError> {
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    let mut page = Page::new(&format!("Comparison of {}", names.join(", ")));
    for r in runs.iter().filter(|r| r.cut_short()) {
        page.banner(&format!(
            "<b>{}</b> is cut short (it holds frames up to {}): only what it holds is compared.",
            esc(&r.name),
            r.last_frame()
        ));
    }
    let Some(a) = runs.first() else {
        page.paragraph("No run to compare.");
        return Ok(page.finish());
    };
    let mut facts: Vec<(&str, String)> = runs
        .iter()
        .enumerate()
        .map(|(i, r)| {
            (
                if i == 0 { "baseline A" } else { "run" },
                format!(
                    "<b>{}</b>: {}, {} frames, {}; made by {}",
                    esc(&r.name),
                    file_link(&r.path, "weft view"),
                    r.last_frame(),
                    esc(&r.verdict()),
                    esc(r.rec.version.as_deref().unwrap_or("an unknown weft"))
                ),
            )
        })
        .collect();
    facts.push(("made by", code(&manifest.command)));
    facts.push(("compared by", esc(&manifest.weft)));
    let comparison = dir.join(crate::fit::report::COMPARISON);
    if comparison.is_file() {
        facts.push(("side by side", file_link(&comparison, "weft view")));
    }
    page.facts(&facts);

    page.section("figures", "Figures");
    let figures = figures();
    let mut header = vec!["figure".to_string()];
    header.extend(runs.iter().map(|r| r.name.clone()));
    let mut rows: Vec<Vec<Cell>> = figures
        .iter()
        .map(|f| {
            let base = figure(&a.figures, &f.name).unwrap_or(f64::NAN);
            let mut row = vec![Cell::text(&f.axis())];
            for (i, r) in runs.iter().enumerate() {
                let v = figure(&r.figures, &f.name).unwrap_or(f64::NAN);
                let delta = if i > 0 && base != 0.0 && base.is_finite() {
                    format!(" ({:+.1} %)", 100.0 * (v - base) / base.abs())
                } else {
                    String::new()
                };
                row.push(Cell::num(&format!("{}{delta}", number(v))));
            }
            row
        })
        .collect();
    let mut verdicts = vec![Cell::text("verdict")];
    verdicts.extend(runs.iter().map(|r| Cell::verdict(&r.verdict())));
    rows.push(verdicts);
    page.table(&header, &rows, None);

    page.section("time", "Over time");
    let mut metrics: Vec<(String, String, &str)> = vec![
        (
            paths::STRAIN.into(),
            "max strain (relative)".into(),
            "max strain",
        ),
        (
            paths::ENERGY.into(),
            "kinetic energy (J)".into(),
            "kinetic energy",
        ),
    ];
    for f in Family::ALL {
        metrics.push((
            paths::violation(f, "max"),
            format!("max violation {} ({})", f.name(), violation_unit(f)),
            "max violation",
        ));
    }
    metrics.push((
        paths::SELF_CROSSINGS.into(),
        "crossing edges".into(),
        "crossing edges",
    ));
    let mut plots = Vec::new();
    for (path, axis, _) in &metrics {
        let series: Vec<Series> = runs
            .iter()
            .map(|r| Series {
                name: r.name.clone(),
                points: over_time(r, path),
                mark: Mark::Line,
                colour: None,
            })
            .collect();
        if series.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let title = axis.split(" (").next().unwrap_or(axis);
        let labels = Labels {
            title,
            x: "simulated time (s)",
            y: axis,
        };
        let caption = format!("{} at each logged frame, a line per run.", code(path));
        plots.push(plot::captioned(labels, &series, &caption)?);
    }
    page.plots(&plots);

    page.section("part", "Where the runs part");
    let mut rows = Vec::new();
    let mut distances = Vec::new();
    for (i, r) in runs.iter().enumerate().skip(1) {
        if let Some(why) = incomparable(a, r) {
            rows.push(vec![
                Cell::text(&r.name),
                Cell::text("not compared"),
                Cell::text(&why),
            ]);
            continue;
        }
        let d = state_diff(a, r);
        let largest = d
            .per_frame
            .iter()
            .copied()
            .fold(None::<(i64, f32)>, |m, (f, v)| match m {
                Some((_, mv)) if mv >= v => m,
                _ => Some((f, v)),
            });
        let time = |f: i64| {
            r.rec
                .sim_time
                .get(&f)
                .map_or(String::new(), |t| format!(" ({} s)", number(*t)))
        };
        rows.push(vec![
            Cell::text(&r.name),
            Cell::text(&match d.first_difference {
                Some(f) => format!("frame {f}{}", time(f)),
                None => "never: the same bits at every frame both logged".into(),
            }),
            Cell::text(&match largest {
                Some((f, v)) => format!("{} m at frame {f}{}", number(f64::from(v)), time(f)),
                None => "–".into(),
            }),
        ]);
        distances.push(Series {
            name: r.name.clone(),
            points: d
                .per_frame
                .iter()
                .map(|&(f, v)| {
                    let t = r.rec.sim_time.get(&f).copied().unwrap_or(f as f64);
                    (t, f64::from(v))
                })
                .collect(),
            mark: Mark::Line,
            colour: Some(i),
        });
    }
    if runs.len() > 1 {
        page.table(
            &[
                "run".into(),
                "first frame its particles differ from A's".into(),
                "largest particle distance to A".into(),
            ],
            &rows,
            None,
        );
    }
    if distances.iter().any(|s| !s.points.is_empty()) {
        let labels = Labels {
            title: "largest particle distance to A",
            x: "simulated time (s)",
            y: "max |x − x_A| (m)",
        };
        let caption = format!(
            "At each frame both logged, the largest distance between a particle and the same particle of {}.",
            esc(&a.name)
        );
        page.plots(&[plot::captioned(labels, &distances, &caption)?]);
    }

    page.section("inputs", "What differs in the inputs");
    let diff = preset_diff(runs);
    if diff.is_empty() {
        page.paragraph("The stored presets are the same, key for key.");
    } else {
        let mut header = vec!["key".to_string()];
        header.extend(runs.iter().map(|r| r.name.clone()));
        let rows: Vec<Vec<Cell>> = diff
            .iter()
            .map(|(k, vs)| {
                std::iter::once(Cell::text(k))
                    .chain(vs.iter().map(|v| Cell::num(v.as_deref().unwrap_or("—"))))
                    .collect()
            })
            .collect();
        page.table(&header, &rows, None);
    }
    let changes: Vec<Vec<Cell>> = runs
        .iter()
        .flat_map(|r| {
            r.changes.iter().map(|(frame, what)| {
                vec![
                    Cell::text(&r.name),
                    Cell::num(&frame.to_string()),
                    Cell::text(what),
                ]
            })
        })
        .collect();
    if changes.is_empty() {
        page.paragraph("No run changed its tuning while it ran.");
    } else {
        page.paragraph("Tuning changed while the runs ran:");
        page.table(
            &["run", "frame", "change"].map(String::from),
            &changes,
            None,
        );
    }
    Ok(page.finish())
}

/// The page of the comparison in `dir`: its recordings read again.
pub fn page_of_dir(dir: &Path) -> Result<String, ReportError> {
    let failed = |why: String| ReportError::Read {
        dir: dir.into(),
        why,
    };
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| failed(format!("{MANIFEST}: {e}")))?;
    let manifest: Manifest =
        serde_json::from_str(&text).map_err(|e| failed(format!("{MANIFEST}: {e}")))?;
    let runs = read_all(&manifest.files).map_err(|e| {
        failed(format!(
            "{e} (the comparison's recordings must stay where they were; `{}` makes it again)",
            manifest.command
        ))
    })?;
    page(&runs, &manifest, dir)
}
