//! The terminal report of `weft compare`: inputs, preset diff, tuning
//! changes, figures side by side with deltas, and particle-state differences.

use super::{RunData, figure, incomparable, preset_diff, state_diff};
use crate::solver::Family;

/// How many per-frame distances are printed before sampling.
const MAX_ROWS: usize = 12;

/// The whole report.
pub fn report(runs: &[RunData]) -> String {
    let mut s = String::new();
    let w = runs.iter().map(|r| r.name.len()).max().unwrap_or(1);
    s += "runs:\n";
    for r in runs {
        let status = if r.rec.truncated {
            format!(
                "CUT SHORT: the file ends mid-message after frame {}; compared up to there",
                r.last_frame()
            )
        } else if !r.finished {
            format!(
                "CUT SHORT: no end-of-run summary (the run did not finish); compared up to frame {}",
                r.last_frame()
            )
        } else {
            format!("{} frames", r.figures.frames)
        };
        s += &format!("  {:<w$}  {}  ({status})\n", r.name, r.path.display());
    }

    let diff = preset_diff(runs);
    if diff.is_empty() {
        s += "\npresets: identical\n";
    } else {
        s += "\npresets (resolved, the keys that differ):\n";
        let rows: Vec<Vec<String>> = diff
            .iter()
            .map(|(k, vs)| {
                std::iter::once(k.clone())
                    .chain(vs.iter().map(|v| v.clone().unwrap_or_else(|| "—".into())))
                    .collect()
            })
            .collect();
        s += &grid(&header(runs, "key"), &rows);
    }

    s += "\ntuning changes during the runs:\n";
    for r in runs {
        if r.changes.is_empty() {
            s += &format!("  {:<w$}  none\n", r.name);
        }
        for (frame, what) in &r.changes {
            let t = r.rec.sim_time.get(frame).copied().unwrap_or(0.0);
            s += &format!("  {:<w$}  frame {frame} ({t:.2} s): {what}\n", r.name);
        }
    }

    s += "\nfigures:\n";
    let mut rows = Vec::new();
    let mut row = |label: &str, name: &str, fmt: fn(f64) -> String| {
        let a = figure(&runs[0].figures, name).unwrap_or(0.0);
        let mut cells = vec![label.to_string()];
        for (i, r) in runs.iter().enumerate() {
            let v = figure(&r.figures, name).unwrap_or(0.0);
            cells.push(if i == 0 {
                fmt(v)
            } else {
                format!("{} ({})", fmt(v), delta(a, v))
            });
        }
        rows.push(cells);
    };
    row("max strain", "max_strain", |v| format!("{v:.4}"));
    for f in Family::ALL {
        row(
            &format!("max violation {}", f.name()),
            &format!("max_violation.{}", f.name()),
            |v| format!("{v:.4}"),
        );
    }
    row("final kinetic energy (J)", "final_energy", |v| {
        format!("{v:.3e}")
    });
    row("steps/s", "steps_per_second", |v| format!("{v:.1}"));
    row("frames", "frames", |v| format!("{v}"));
    rows.push(
        std::iter::once("verdict".to_string())
            .chain(runs.iter().map(RunData::verdict))
            .collect(),
    );
    s += &grid(&header(runs, "figure"), &rows);
    for r in runs {
        for c in r.checks.iter().filter(|c| !c.ok) {
            s += &format!(
                "  {:<w$}  {} {:.4e} > {:.4e}\n",
                r.name, c.bound, c.value, c.limit
            );
        }
    }

    if runs.len() > 1 {
        s += &format!("\nparticle states (against {}):\n", runs[0].name);
        for r in &runs[1..] {
            s += &states(&runs[0], r, w);
        }
    }
    s
}

fn states(a: &RunData, b: &RunData, w: usize) -> String {
    if let Some(why) = incomparable(a, b) {
        return format!("  {:<w$}  not compared: {why}\n", b.name);
    }
    let d = state_diff(a, b);
    if d.per_frame.is_empty() {
        return format!("  {:<w$}  not compared: no frame logged by both\n", b.name);
    }
    let Some(first) = d.first_difference else {
        return format!(
            "  {:<w$}  identical at all {} frames both logged\n",
            b.name,
            d.per_frame.len()
        );
    };
    let (at, most) = d
        .per_frame
        .iter()
        .copied()
        .fold((0, 0.0f32), |m, x| if x.1 > m.1 { x } else { m });
    let mut s = format!(
        "  {:<w$}  first differs at frame {first}; largest distance {most:.4e} m at frame {at}\n",
        b.name
    );
    let n = d.per_frame.len();
    let picks: Vec<usize> = if n <= MAX_ROWS {
        (0..n).collect()
    } else {
        (0..MAX_ROWS)
            .map(|k| k * (n - 1) / (MAX_ROWS - 1))
            .collect()
    };
    s += &format!(
        "  {:<w$}  largest distance per logged frame{}:\n",
        "",
        if n > MAX_ROWS {
            format!(" ({MAX_ROWS} of {n}; all in the comparison .rrd)")
        } else {
            String::new()
        }
    );
    for k in picks {
        let (frame, dist) = d.per_frame[k];
        s += &format!("  {:<w$}    frame {frame:>6}  {dist:.4e} m\n", "");
    }
    s
}

fn header(runs: &[RunData], first: &str) -> Vec<String> {
    std::iter::once(first.to_string())
        .chain(runs.iter().map(|r| r.name.clone()))
        .collect()
}

/// `+5.8 %`, or `=` when equal, or the absolute change from zero.
fn delta(a: f64, b: f64) -> String {
    if a == b {
        "=".into()
    } else if a != 0.0 {
        format!("{:+.1} %", 100.0 * (b - a) / a.abs())
    } else {
        format!("{:+.3e}", b - a)
    }
}

/// Left-aligned columns, two spaces apart.
pub fn grid(header: &[String], rows: &[Vec<String>]) -> String {
    let cols = header.len();
    let width: Vec<usize> = (0..cols)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .chain(std::iter::once(&header[c]))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[String]| -> String {
        let mut l = String::from(" ");
        for (c, cell) in cells.iter().enumerate() {
            l += &format!(" {cell:<0$} ", width[c]);
        }
        l.trim_end().to_string() + "\n"
    };
    let mut s = line(header);
    for r in rows {
        s += &line(r);
    }
    s
}
