//! A sweep's page: each figure against each varied key (a line per value
//! of the other keys) and over the first two keys as a heatmap; the best
//! point by each figure; every point's verdict, figures and recording.

use std::collections::BTreeMap;
use std::path::Path;

use super::page::{Cell, Page, code, esc};
use super::plot::{self, Grid, Labels, Mark, Series, number};
use super::{Figure, ReportError, figures, rrd_cell, shell};
use crate::compare::figure;
use crate::sweep::PointResult;
use crate::sweep::collect::Collected;

/// At most this many lines in one plot (a line per combination of the
/// other keys' values); the rest are named in the caption.
const MAX_LINES: usize = 10;

/// The command that makes (or resumes) the sweep in `dir`.
fn command(c: &Collected, dir: &Path) -> Option<String> {
    let m = c.manifest.as_ref()?;
    let mut s = format!("weft sweep {}", shell(&m.preset));
    for a in &m.axes {
        s += &format!(
            " --set {}",
            shell(&format!("{}={}", a.key, a.values.join(",")))
        );
    }
    if let Some(f) = m.frames {
        s += &format!(" --frames {f}");
    } else if let Some(sec) = m.seconds {
        s += &format!(" --seconds {sec}");
    }
    s += &format!(
        " --level {} --out {}",
        m.level,
        shell(&dir.display().to_string())
    );
    Some(s)
}

/// The swept keys in order, each with its values in grid order.
fn axes(c: &Collected) -> Vec<(String, Vec<String>)> {
    if let Some(m) = &c.manifest
        && !m.axes.is_empty()
    {
        // A point's settings are its axes' values, as written.
        return m
            .axes
            .iter()
            .map(|a| (a.key.clone(), a.values.clone()))
            .collect();
    }
    // A list of points (a fit's generation) or no manifest: the values the
    // finished points hold, in their order.
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for p in &c.points {
        for (k, v) in &p.settings {
            match out.iter_mut().find(|(key, _)| key == k) {
                Some((_, values)) if !values.contains(v) => values.push(v.clone()),
                Some(_) => {}
                None => out.push((k.clone(), vec![v.clone()])),
            }
        }
    }
    out
}

fn setting<'a>(p: &'a PointResult, key: &str) -> Option<&'a str> {
    p.settings
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// A point's value of `f`, unless the run failed.
fn value(p: &PointResult, f: &Figure) -> Option<f64> {
    if p.figures.failure.is_some() || !p.figures.finite {
        return None;
    }
    figure(&p.figures, &f.name).filter(|v| v.is_finite())
}

/// Line plots of `f` against `key` (numeric values only), a line per
/// combination of the other keys.
fn against(
    points: &[PointResult],
    f: &Figure,
    key: &str,
    others: &[&str],
) -> Result<Option<(String, String)>, ReportError> {
    let mut groups: BTreeMap<Vec<String>, Vec<(f64, f64)>> = BTreeMap::new();
    let mut order: Vec<Vec<String>> = Vec::new();
    for p in points {
        let Some(x) = setting(p, key).and_then(|v| v.parse::<f64>().ok()) else {
            return Ok(None);
        };
        let label: Vec<String> = others
            .iter()
            .map(|k| format!("{}={}", short(k), setting(p, k).unwrap_or("–")))
            .collect();
        if !groups.contains_key(&label) {
            order.push(label.clone());
        }
        groups
            .entry(label)
            .or_default()
            .push((x, value(p, f).unwrap_or(f64::NAN)));
    }
    let series: Vec<Series> = order
        .iter()
        .take(MAX_LINES)
        .map(|label| {
            let mut points = groups[label].clone();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                name: if label.is_empty() {
                    f.label.clone()
                } else {
                    label.join(", ")
                },
                points,
                mark: Mark::LineDots,
                colour: None,
            }
        })
        .collect();
    let title = format!("{} by {}", f.label, short(key));
    let mut caption = format!("{} against {}", esc(&f.label), code(key));
    if !others.is_empty() {
        caption += &format!(
            ", a line per value of {}",
            others
                .iter()
                .map(|k| code(k))
                .collect::<Vec<_>>()
                .join(" and ")
        );
    }
    if order.len() > MAX_LINES {
        caption += &format!(" (the first {MAX_LINES} of {} lines)", order.len());
    }
    caption += "; a failed run leaves a gap.";
    let labels = Labels {
        title: &title,
        x: key,
        y: &f.axis(),
    };
    Ok(Some(plot::captioned(labels, &series, &caption)?))
}

/// A heatmap of `f` over the first two keys: at each cell, the lowest value
/// over the other keys (the highest for a figure where more is better).
fn over_two(
    points: &[PointResult],
    f: &Figure,
    (kx, xs): (&str, &[String]),
    (ky, ys): (&str, &[String]),
    more_keys: bool,
) -> Result<(String, String), ReportError> {
    let mut cells = vec![vec![None::<f64>; xs.len()]; ys.len()];
    for p in points {
        let (Some(i), Some(j)) = (
            setting(p, kx).and_then(|v| xs.iter().position(|x| x == v)),
            setting(p, ky).and_then(|v| ys.iter().position(|y| y == v)),
        ) else {
            continue;
        };
        if let Some(v) = value(p, f) {
            let cell = &mut cells[j][i];
            *cell = Some(match *cell {
                None => v,
                Some(c) if f.higher_is_better => c.max(v),
                Some(c) => c.min(v),
            });
        }
    }
    let title = format!("{} over {} and {}", f.label, short(kx), short(ky));
    let svg = plot::heatmap(
        Labels {
            title: &title,
            x: kx,
            y: ky,
        },
        &Grid {
            columns: xs,
            rows: ys,
            cells: &cells,
        },
    )?;
    let mut caption = format!("{} ({}) at each pair of values", esc(&f.label), esc(f.unit));
    if more_keys {
        caption += &format!(
            ", the {} over the other keys",
            if f.higher_is_better {
                "highest"
            } else {
                "lowest"
            }
        );
    }
    caption += "; grey: no finished run.";
    Ok((svg, caption))
}

/// The key's last segment (`solver.weights.curvature` → `curvature`).
fn short(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

/// The sweep's page.
pub fn page(c: &Collected, dir: &Path) -> Result<String, ReportError> {
    let preset = c
        .manifest
        .as_ref()
        .map(|m| m.preset.clone())
        .unwrap_or_else(|| "(no manifest)".into());
    let mut page = Page::new(&format!("Sweep of {preset}"));
    let total = c.points.len() + c.missing.len();
    if !c.missing.is_empty() {
        page.banner(&format!(
            "<b>Partial:</b> {} of {total} points are finished; this page shows those. Not finished: {}. \
             Run the same <code>weft sweep</code> again to finish them, then this page is made anew.",
            c.points.len(),
            esc(&c.missing.join(", "))
        ));
    }
    let mut points = c.points.clone();
    points.sort_by_key(|p| p.index);
    let axes = axes(c);
    let figures = figures();
    let mut facts = vec![("points", format!("{} finished of {total}", points.len()))];
    for (k, v) in &axes {
        facts.push(("swept", format!("{} = {}", code(k), esc(&v.join(", ")))));
    }
    if let Some(cmd) = command(c, dir) {
        facts.push(("made by", code(&cmd)));
    }
    facts.push((
        "collected by",
        code(&format!(
            "weft sweep --collect {}",
            shell(&dir.display().to_string())
        )),
    ));
    if let Some(m) = &c.manifest {
        facts.push(("weft and solver revision", esc(&m.weft)));
    }
    let verdicts = tally(&points);
    facts.push(("verdicts", esc(&verdicts)));
    page.facts(&facts);

    page.section("best", "The best point by each figure");
    let mut rows = Vec::new();
    for f in figures.iter() {
        let best = points
            .iter()
            .filter_map(|p| Some((p, value(p, f)?)))
            .reduce(|a, b| {
                let better = if f.higher_is_better {
                    b.1 > a.1
                } else {
                    b.1 < a.1
                };
                if better { b } else { a }
            });
        if let Some((p, v)) = best {
            rows.push(vec![
                Cell::text(&format!("{} ({})", f.label, f.better())),
                Cell::num(&number(v)),
                Cell::text(&p.name),
                Cell::text(
                    &p.settings
                        .iter()
                        .map(|(k, v)| format!("{}={v}", short(k)))
                        .collect::<Vec<_>>()
                        .join(", "),
                ),
                Cell::verdict(&p.verdict()),
            ]);
        }
    }
    page.table(
        &["figure", "best", "point", "its settings", "its verdict"].map(String::from),
        &rows,
        None,
    );

    let keys: Vec<&str> = axes
        .iter()
        .filter(|(_, v)| v.len() > 1)
        .map(|(k, _)| k.as_str())
        .collect();
    for f in figures.iter() {
        let mut plots = Vec::new();
        for &k in &keys {
            let others: Vec<&str> = keys.iter().copied().filter(|o| *o != k).collect();
            if let Some(p) = against(&points, f, k, &others)? {
                plots.push(p);
            }
        }
        if keys.len() >= 2 {
            let values = |k: &str| {
                axes.iter()
                    .find(|(key, _)| key == k)
                    .map(|(_, v)| v.as_slice())
                    .unwrap_or_default()
            };
            plots.push(over_two(
                &points,
                f,
                (keys[0], values(keys[0])),
                (keys[1], values(keys[1])),
                keys.len() > 2,
            )?);
        }
        if !plots.is_empty() {
            page.section(&f.name, &format!("{} ({})", f.label, f.unit));
            page.plots(&plots);
        }
    }

    page.section("points", "Every point");
    page.paragraph(&format!(
        "Each point's settings, figures and <code>[expect]</code> verdict, with its recording \
         (open one with {}).",
        code("weft view FILE.rrd")
    ));
    let mut header: Vec<String> = vec!["point".into()];
    header.extend(axes.iter().map(|(k, _)| k.clone()));
    header.extend(figures.iter().map(|f| f.name.clone()));
    header.extend(["verdict", "bounds failed", "recording"].map(String::from));
    let rows: Vec<Vec<Cell>> = points
        .iter()
        .map(|p| {
            let mut row = vec![Cell::text(&p.name)];
            row.extend(
                axes.iter()
                    .map(|(k, _)| Cell::text(setting(p, k).unwrap_or("–"))),
            );
            row.extend(
                figures
                    .iter()
                    .map(|f| Cell::num(&figure(&p.figures, &f.name).map_or("–".into(), number))),
            );
            row.push(Cell::verdict(&p.verdict()));
            let failed: Vec<String> = p
                .checks
                .iter()
                .filter(|c| !c.ok)
                .map(|c| format!("{} {} > {}", c.bound, number(c.value), number(c.limit)))
                .chain(p.figures.failure.clone())
                .collect();
            row.push(Cell::text(&failed.join("; ")));
            row.push(rrd_cell(dir, &format!("{}.rrd", p.name)));
            row
        })
        .collect();
    let fold = (points.len() > 40).then(|| format!("{} points (open)", points.len()));
    page.table(&header, &rows, fold.as_deref());
    Ok(page.finish())
}

/// `N ok, M FAIL, K FAILED`.
fn tally(points: &[PointResult]) -> String {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for p in points {
        let v = p.verdict();
        let v = if v.starts_with("FAIL (") {
            "FAIL".into()
        } else {
            v
        };
        *counts.entry(v).or_default() += 1;
    }
    if counts.is_empty() {
        return "no point finished".into();
    }
    counts
        .iter()
        .map(|(v, n)| format!("{n} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Figures;
    use crate::sweep::{Manifest, ManifestAxis, ManifestPoint};

    /// A finished 10 × 10 × 10 sweep, its figures made up.
    fn thousand() -> Collected {
        let values = |n: usize| (0..n).map(|k| format!("0.{k}")).collect::<Vec<_>>();
        let keys = ["solver.weights.curvature", "solver.damping", "wind.speed"];
        let mut points = Vec::new();
        for index in 0..1000 {
            let settings: Vec<(String, String)> = keys
                .iter()
                .enumerate()
                .map(|(d, k)| {
                    (
                        k.to_string(),
                        format!("0.{}", index / 10usize.pow(2 - d as u32) % 10),
                    )
                })
                .collect();
            let x = index as f32 / 1000.0;
            points.push(PointResult {
                index,
                name: format!("{index:03}"),
                settings,
                figures: Figures {
                    max_strain: 0.02 + 0.01 * x,
                    steps_per_second: 100.0 - f64::from(x),
                    finite: true,
                    ..Figures::default()
                },
                checks: Vec::new(),
                measured: None,
            });
        }
        Collected {
            manifest: Some(Manifest {
                weft: "weft test".into(),
                preset: "hanging_sheet".into(),
                frames: Some(10),
                seconds: None,
                level: "summary".into(),
                axes: keys
                    .iter()
                    .map(|k| ManifestAxis {
                        key: k.to_string(),
                        values: values(10),
                    })
                    .collect(),
                points: points
                    .iter()
                    .map(|p| ManifestPoint {
                        index: p.index,
                        name: p.name.clone(),
                        settings: p.settings.clone(),
                    })
                    .collect(),
            }),
            points,
            missing: Vec::new(),
        }
    }

    #[test]
    fn a_sweep_of_a_thousand_points_makes_a_page_of_a_few_megabytes() {
        let html = page(&thousand(), Path::new("runs")).unwrap();
        assert!(html.len() < 4 << 20, "{} bytes", html.len());
        // Ten lines a plot at most, and the caption says how many there were.
        assert!(html.contains("(the first 10 of 100 lines)"));
        assert!(html.contains("the lowest over the other keys"));
        assert!(html.contains("1000 points (open)"));
    }
}
