//! `weft compare`: its options and what it prints, writes and exits with.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use glam::Vec3;

use super::output::{out, outln};
use crate::compare::gate::{self, Bound};
use crate::compare::recording::{self, Placement};
use crate::compare::{RunData, incomparable, read_all, report};
use crate::report::compare::Manifest;
use crate::report::shell;

/// Options of `weft compare`.
#[derive(Debug, Args)]
#[command(after_help = "\
Exit codes: 0 compared; 1 a --fail-if bound regressed (a table says what); 2 bad input
(not a weft recording, a recording cut short, runs of different scenes), after printing
what could be compared.

--fail-if FIGURE OP LIMIT: the run fails when `value OP LIMIT` holds.
  FIGURE  max_strain, max_violation.FAMILY (a family's name, as in the
          preset's [solver.weights]), final_energy, steps_per_second,
          wall_seconds, frames, sim_seconds
  OP      >  >=  <  <=
  LIMIT   a number (checks every run), or relative to the first run A
          (checks every other run): A, 1.1*A, A*1.1, A+0.002, 1.1*A-0.001
  e.g.    --fail-if 'max_strain > 1.1*A' --fail-if 'steps_per_second < 0.8*A'")]
pub struct CompareArgs {
    /// Recordings (`.rrd`) written by `weft record`, `weft sweep` or the
    /// debugger; the first is the baseline `A`.
    #[arg(required = true, value_name = "FILE.rrd")]
    pub files: Vec<PathBuf>,
    /// Write the comparison recording to this `.rrd` file.
    #[arg(long, value_name = "FILE.rrd", group = "sink")]
    pub save: Option<PathBuf>,
    /// Write the comparison into this directory: the comparison recording
    /// (comparison.rrd), a page with plots (report.html) and which files were
    /// compared (compare.json, for `weft report DIR`).
    #[arg(long, value_name = "DIR", group = "sink")]
    pub out: Option<PathBuf>,
    /// Stream the comparison to a running Rerun viewer.
    #[arg(long, value_name = "URL", num_args = 0..=1, default_missing_value = crate::telemetry::DEFAULT_VIEWER, group = "sink")]
    pub connect: Option<String>,
    /// Draw the cloths on top of each other instead of side by side.
    #[arg(long)]
    pub overlay: bool,
    /// The axis the cloths are set side by side along: x, y, z, or auto (of
    /// the two the cloth spans, the one it moves least along).
    #[arg(long, default_value = "auto", value_parser = ["auto", "x", "y", "z"])]
    pub axis: String,
    /// Exit with 1 if a run crosses this bound (repeatable); see below.
    #[arg(long = "fail-if", value_name = "BOUND")]
    pub fail_if: Vec<Bound>,
}

/// Runs `weft compare`.
pub fn compare(args: CompareArgs) -> anyhow::Result<ExitCode> {
    let runs = read_all(&args.files)?;
    let text = report::report(&runs);
    out!("{text}");

    let save = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            Some(dir.join(crate::fit::report::COMPARISON))
        }
        None => args.save.clone(),
    };
    if save.is_some() || args.connect.is_some() {
        let rec = recording::open(&runs, save.as_deref(), args.connect.as_deref())?;
        let placement = if args.overlay {
            Placement::Overlay
        } else {
            Placement::SideBySide(match args.axis.as_str() {
                "x" => Some(Vec3::X),
                "y" => Some(Vec3::Y),
                "z" => Some(Vec3::Z),
                _ => None,
            })
        };
        recording::write(&rec, &runs, placement, &text)?;
        drop(rec);
        if let Some(path) = &save {
            outln!(
                "\ncomparison written to {} (open it with `weft view {}`)",
                path.display(),
                path.display()
            );
        }
    }

    if let Some(dir) = &args.out {
        let manifest = Manifest::new(command(&args), &args.files);
        manifest.write(dir)?;
        let page =
            crate::report::write(dir, &crate::report::compare::page(&runs, &manifest, dir)?)?;
        outln!(
            "the comparison's page: {} (open it in a browser)",
            page.display()
        );
    }

    let regressions = gate::check(&args.fail_if, &runs);
    if !regressions.is_empty() {
        out!("\n{}", gate::table(&regressions, &args.fail_if));
    } else if !args.fail_if.is_empty() {
        outln!("\nno regression against {} bound(s)", args.fail_if.len());
    }

    let mut problems = Vec::new();
    for r in runs.iter().filter(|r| r.cut_short()) {
        problems.push(format!(
            "{} is cut short (it holds frames up to {}{}): only what it holds was compared",
            r.path.display(),
            r.last_frame(),
            if r.rec.truncated {
                ", then the file ends mid-message"
            } else {
                ", and no end-of-run summary"
            }
        ));
    }
    let different: Vec<(&RunData, String)> = runs
        .iter()
        .skip(1)
        .filter_map(|r| Some((r, incomparable(&runs[0], r)?)))
        .filter(|(_, why)| why.starts_with("their scenes differ"))
        .collect();
    for (r, why) in different {
        problems.push(format!(
            "{} and {} are runs of different scenes ({}): their figures are shown, their particle states are not compared",
            runs[0].name,
            r.name,
            why.trim_start_matches("their scenes differ beyond the tuning (").trim_end_matches(')')
        ));
    }
    if !problems.is_empty() {
        for p in &problems {
            eprintln!("error: {p}");
        }
        return Ok(ExitCode::from(2));
    }
    Ok(if regressions.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The command line that made this comparison, as a person would type it.
fn command(args: &CompareArgs) -> String {
    let mut s = "weft compare".to_string();
    for f in &args.files {
        s += &format!(" {}", shell(&f.display().to_string()));
    }
    if args.overlay {
        s += " --overlay";
    }
    if args.axis != "auto" {
        s += &format!(" --axis {}", args.axis);
    }
    for b in &args.fail_if {
        s += &format!(" --fail-if {}", shell(&b.to_string()));
    }
    if let Some(dir) = &args.out {
        s += &format!(" --out {}", shell(&dir.display().to_string()));
    }
    s
}
