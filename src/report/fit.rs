//! A fit's page: the distance by run and by generation, each varied key's
//! path towards the fit, the distance's terms for the start, the fit and
//! the reference, and the files the fit wrote.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use super::page::{Cell, Page, code, esc};
use super::plot::{self, Labels, Mark, Series, number};
use super::{ReportError, file_link, shell};
use crate::fit::report::{COMPARISON, FITTED};
use crate::fit::{Evaluated, Fit, Halt, Outcome, Request};

/// The command that makes (or resumes) `fit` in `dir`.
fn command(fit: &Fit, dir: &Path) -> String {
    let mut s = format!("weft fit {}", shell(&fit.preset));
    for o in &fit.base {
        s += &format!(" --set {}", shell(&format!("{}={}", o.key, o.value)));
    }
    for v in &fit.vary {
        s += &format!(" --vary {}", shell(&v.to_string()));
    }
    if let Some(r) = &fit.reference {
        s += &format!(" --to {}", shell(&r.run.path.display().to_string()));
        if r.weight != 1.0 {
            s += &format!(" --to-weight {}", r.weight);
        }
    }
    for t in &fit.targets {
        s += &format!(" --target {}", shell(&t.to_string()));
    }
    s += &format!(
        " --budget {} --seed {} --method {} --seconds {} --out {}",
        fit.budget,
        fit.seed,
        fit.method,
        fit.seconds,
        shell(&dir.display().to_string())
    );
    s
}

/// The best distance up to each run, as steps.
fn best_so_far(points: &[Evaluated], y: impl Fn(&Evaluated) -> f64) -> Vec<(f64, f64)> {
    let mut best = f64::INFINITY;
    let mut out = Vec::new();
    for p in points {
        if !p.distance.failed && p.distance.total < best {
            best = p.distance.total;
            out.push((p.index as f64, y(p)));
        }
    }
    if let (Some(last), Some(end)) = (out.last().copied(), points.last()) {
        out.push((end.index as f64, last.1));
    }
    out
}

/// A run's distance, unless it failed.
fn distance(p: &Evaluated) -> f64 {
    if p.distance.failed {
        f64::NAN
    } else {
        p.distance.total
    }
}

/// The fit's page, from the fit and how it ended.
pub fn page(fit: &Fit, outcome: &Outcome, dir: &Path) -> Result<String, ReportError> {
    let mut page = Page::new(&format!("Fit of {}", fit.preset));
    let points = &outcome.points;
    match &outcome.halt {
        Halt::Done => {}
        Halt::Interrupted => page.banner(&format!(
            "<b>Partial:</b> the fit was interrupted after {} of at most {} runs; this page shows those. \
             Run the same <code>weft fit</code> again to resume it.",
            points.len(),
            fit.budget
        )),
        Halt::Pending {
            generation,
            missing,
        } => page.banner(&format!(
            "<b>Partial:</b> generation {generation} has {missing} run(s) still to do (other shards, or \
             an interrupted fit); this page shows the {} run(s) evaluated so far.",
            points.len()
        )),
    }
    let (Some(start), Some(best)) = (outcome.start(), outcome.best()) else {
        page.paragraph("No run has been evaluated yet.");
        return Ok(page.finish());
    };
    let mut facts = vec![
        (
            "varied",
            fit.vary
                .iter()
                .map(|v| format!("{} from {} to {}", code(&v.key), v.lo, v.hi))
                .collect::<Vec<_>>()
                .join("; "),
        ),
        (
            "brought close to",
            fit.reference
                .iter()
                .map(|r| {
                    format!(
                        "the reference {} (weight {})",
                        file_link(&r.run.path, "weft view"),
                        r.weight
                    )
                })
                .chain(
                    fit.targets
                        .iter()
                        .map(|t| format!("the target {}", code(&t.to_string()))),
                )
                .collect::<Vec<_>>()
                .join("; "),
        ),
        (
            "runs",
            format!(
                "{} of a budget of {}, {} generation(s); {} search, seed {}",
                points.len(),
                fit.budget,
                points.last().map_or(0, |p| p.generation + 1),
                fit.method,
                fit.seed
            ),
        ),
        (
            "best",
            format!(
                "run #{} (generation {}): distance {} (the start's: {})",
                best.index,
                best.generation,
                number(best.distance.total),
                number(start.distance.total)
            ),
        ),
        ("made by", code(&command(fit, dir))),
        ("weft and solver revision", esc(&fit.manifest().weft)),
    ];
    let fitted = dir.join(FITTED);
    if fitted.is_file() {
        facts.push((
            "fitted preset",
            format!(
                "{}, or {}",
                file_link(&fitted, "weft show"),
                code(&format!(
                    "weft gui {}",
                    shell(&fitted.display().to_string())
                ))
            ),
        ));
    }
    for (what, file) in [
        ("the start, recorded", "start.rrd"),
        ("the fit, recorded", "fitted.rrd"),
        ("side by side", COMPARISON),
    ] {
        let path = dir.join(file);
        if path.is_file() {
            facts.push((what, file_link(&path, "weft view")));
        }
    }
    page.facts(&facts);

    page.section("distance", "The distance");
    let mut plots = Vec::new();
    let by_run = plot::captioned(
        Labels {
            title: "distance by run",
            x: "run",
            y: "distance (weighted total)",
        },
        &[
            Series {
                name: "each run".into(),
                points: points
                    .iter()
                    .map(|p| (p.index as f64, distance(p)))
                    .collect(),
                mark: Mark::Dots,
                colour: None,
            },
            Series {
                name: "best so far".into(),
                points: best_so_far(points, |p| p.distance.total),
                mark: Mark::Steps,
                colour: None,
            },
        ],
        "Each run's distance (a dot; a failed run has none) and the best so far.",
    )?;
    plots.push(by_run);
    let generations = points.last().map_or(0, |p| p.generation + 1);
    let per_generation = |pick: fn(&mut Vec<f64>) -> f64| -> Vec<(f64, f64)> {
        (0..generations)
            .filter_map(|g| {
                let mut d: Vec<f64> = points
                    .iter()
                    .filter(|p| p.generation == g)
                    .map(distance)
                    .filter(|d| d.is_finite())
                    .collect();
                (!d.is_empty()).then(|| (g as f64, pick(&mut d)))
            })
            .collect()
    };
    let by_generation = plot::captioned(
        Labels {
            title: "distance by generation",
            x: "generation",
            y: "distance (weighted total)",
        },
        &[
            Series {
                name: "best of the generation".into(),
                points: per_generation(|d| d.iter().copied().fold(f64::INFINITY, f64::min)),
                mark: Mark::LineDots,
                colour: None,
            },
            Series {
                name: "median of the generation".into(),
                points: per_generation(|d| {
                    d.sort_by(f64::total_cmp);
                    d[d.len() / 2]
                }),
                mark: Mark::LineDots,
                colour: None,
            },
        ],
        "The best and the median distance of each generation's runs.",
    )?;
    plots.push(by_generation);
    page.plots(&plots);

    page.section("keys", "Each varied key's path");
    let mut plots = Vec::new();
    for (k, v) in fit.vary.iter().enumerate() {
        let value = |p: &Evaluated| p.values[k].parse::<f64>().unwrap_or(f64::NAN);
        let caption = format!(
            "{} in each run (searched from {} to {}) and in the best run so far; the fit: {}.",
            code(&v.key),
            v.lo,
            v.hi,
            esc(&best.values[k])
        );
        plots.push(plot::captioned(
            Labels {
                title: &format!("{} by run", v.key),
                x: "run",
                y: &v.key,
            },
            &[
                Series {
                    name: "each run".into(),
                    points: points.iter().map(|p| (p.index as f64, value(p))).collect(),
                    mark: Mark::Dots,
                    colour: None,
                },
                Series {
                    name: "the best so far".into(),
                    points: best_so_far(points, value),
                    mark: Mark::Steps,
                    colour: None,
                },
            ],
            &caption,
        )?);
    }
    page.plots(&plots);

    page.section("terms", "Start, fit and reference");
    let (header, rows) = crate::fit::report::rows(fit, outcome);
    let rows: Vec<Vec<Cell>> = rows
        .iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .map(|(i, c)| if i == 0 { Cell::text(c) } else { Cell::num(c) })
                .collect()
        })
        .collect();
    page.table(&header, &rows, None);

    page.section("runs", "Every run");
    let mut header: Vec<String> = ["run", "generation"].map(String::from).to_vec();
    header.extend(fit.vary.iter().map(|v| v.key.clone()));
    header.extend(["distance", "max strain", "files"].map(String::from));
    let rows: Vec<Vec<Cell>> = points
        .iter()
        .map(|p| {
            let mut row = vec![
                Cell::num(&p.index.to_string()),
                Cell::num(&p.generation.to_string()),
            ];
            row.extend(p.values.iter().map(|v| Cell::num(v)));
            row.push(if p.distance.failed {
                Cell::verdict("FAILED")
            } else {
                Cell::num(&number(p.distance.total))
            });
            row.push(Cell::num(&number(f64::from(p.figures.max_strain))));
            row.push(Cell::text(&format!(
                "gen-{:03}/{}.json",
                p.generation, p.name
            )));
            row
        })
        .collect();
    let fold = (points.len() > 40).then(|| format!("{} runs (open)", points.len()));
    page.table(&header, &rows, fold.as_deref());
    Ok(page.finish())
}

/// The page of the fit in `dir`, from its manifest and the runs on disk
/// (nothing is run; a fit not finished gives a page labelled partial).
pub fn page_of_dir(dir: &Path) -> Result<String, ReportError> {
    let failed = |why: String| ReportError::Read {
        dir: dir.into(),
        why,
    };
    let manifest = crate::fit::read_manifest(dir).map_err(|e| failed(e.to_string()))?;
    let request = Request::of_manifest(&manifest).map_err(|e| failed(e.to_string()))?;
    let fit = Fit::new(request).map_err(|e| {
        failed(format!(
            "the fit in its manifest does not load from here: {e} (run `weft report` from the directory the fit ran in)"
        ))
    })?;
    let stop = AtomicBool::new(false);
    let outcome = crate::fit::run(&fit, dir, None, 1, &stop, true, &mut |_| {})
        .map_err(|e| failed(e.to_string()))?;
    page(&fit, &outcome, dir)
}
