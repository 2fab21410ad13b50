//! `weft fit`: its options, the progress bar, Ctrl-C, shards, and the report.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;

use clap::Args;

use super::output::out;
use crate::fit::distance::Target;
use crate::fit::search::Method;
use crate::fit::space::Vary;
use crate::fit::{Fit, Halt, Progress, Request, report};
use crate::scene::Override;
use crate::sweep::shard::{self, Shard};

/// Options of `weft fit`.
#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  weft fit windy_flag --set cloth.weft=24 --set cloth.warp=16 --set solver.substeps=8 \\
      --vary solver.weights.curvature=0.01..0.9 --vary solver.damping=0.9..1 \\
      --to fine.rrd --seconds 6 --budget 64 --out fit/
  weft fit presets/cusick_drape.toml --vary solver.weights.curvature=0.5..0.95 \\
      --target drape_coefficient=0.45 --budget 24 --out drape/

Targets: FIGURE=VALUE (as close as can be), FIGURE<=VALUE or FIGURE>=VALUE (a bound),
each optionally @WEIGHT. Figures: drape_coefficient, mean_drop, sag, edge_amplitude,
edge_frequency, mean_strain, and the run summary's (max_strain, max_violation.FAMILY, …).
Every run's files stay under --out (gen-NNN/, as weft sweep's); the same command resumes.
At the end: a table, OUT/fitted.toml (weft show / weft gui load it) and OUT/comparison.rrd.
Inside a Slurm array task (or with --shard I/N) only that shard's points of the next
generation run; see docs/cluster.md.")]
pub struct FitArgs {
    /// Preset file or shipped preset name.
    pub preset: String,
    /// A searched key and its range, `KEY=LO..HI` (any live key: solver
    /// settings, wind); repeat for several.
    #[arg(long = "vary", value_name = "KEY=LO..HI")]
    pub vary: Vec<Vary>,
    /// A reference recording to bring the preset close to (another run of
    /// the same scene: another resolution, iterations, substeps, families).
    #[arg(long = "to", value_name = "REFERENCE.rrd")]
    pub to: Option<PathBuf>,
    /// The reference's weight against the targets.
    #[arg(long = "to-weight", value_name = "W", default_value_t = 1.0)]
    pub to_weight: f64,
    /// A target figure, `FIGURE=VALUE`, `FIGURE<=VALUE` or `FIGURE>=VALUE`,
    /// optionally `@WEIGHT`; repeat for several.
    #[arg(long = "target", value_name = "FIGURE=VALUE")]
    pub target: Vec<Target>,
    /// Override a preset field in every run, e.g. `--set cloth.weft=24`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<Override>,
    /// At most this many runs (the start included).
    #[arg(long, value_name = "N", default_value_t = 64)]
    pub budget: usize,
    /// The optimiser's seed: the same seed gives the same fit, bit for bit.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The optimiser: swarm (argmin's particle swarm) or nelder-mead.
    #[arg(long, default_value = "swarm")]
    pub method: Method,
    /// Simulated seconds per run (default: the preset's `duration`).
    #[arg(long)]
    pub seconds: Option<f32>,
    /// The directory for the fit's files.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Runs at once (default: the number of cores).
    #[arg(long, short = 'j')]
    pub jobs: Option<usize>,
    /// Run only this shard's points of the next generation (I/N).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// The number of shards, with the index from the environment.
    #[arg(long, value_name = "N", conflicts_with = "shard")]
    pub shards: Option<usize>,
    /// Run nothing: measure the reference if needed, then say whether the fit
    /// is complete (exit 0) or has points to run (exit 3).
    #[arg(long)]
    pub status: bool,
}

/// Runs `weft fit`.
pub fn fit(args: FitArgs) -> anyhow::Result<ExitCode> {
    let shard = if args.status {
        None
    } else {
        shard::resolve(args.shard, args.shards, |k| std::env::var(k).ok())?
    };
    let fit = Fit::new(Request {
        preset: args.preset.clone(),
        base: args.set.clone(),
        vary: args.vary.clone(),
        reference: args.to.clone(),
        reference_weight: args.to_weight,
        targets: args.target.clone(),
        budget: args.budget,
        seed: args.seed,
        method: args.method,
        seconds: args.seconds,
    })?;
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    let stop = crate::interrupt::stop_flag(Some(
        "stopping after the runs going now; every finished run is kept (Ctrl-C again to quit at once)",
    ));
    let out_dir = &args.out;
    if fit.reference.is_some() && !out_dir.join(crate::fit::REFERENCE).is_file() {
        eprintln!("measuring the reference (re-running its stored preset once)…");
    }
    let bar = indicatif::ProgressBar::new(fit.budget as u64).with_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{bar:40}] {pos}/{len} runs, {msg}, eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix(args.preset.clone());
    bar.set_message("best distance –");
    let where_ = shard.map(|s| format!(", shard {s}")).unwrap_or_default();
    // Runs with a distance, and runs of the current generation finished.
    let (mut done, mut ran) = (0u64, 0u64);
    let mut progress = |p: Progress| match p {
        Progress::Generation {
            generation,
            run,
            done: skipped,
        } => {
            ran = skipped as u64;
            if run > 0 {
                bar.suspend(|| {
                    eprintln!(
                        "generation {generation}: {run} run(s) here{where_}{}",
                        if skipped > 0 {
                            format!(", {skipped} already done")
                        } else {
                            String::new()
                        }
                    )
                });
            }
        }
        Progress::Ran { .. } => {
            ran += 1;
            bar.set_position((done + ran).min(fit.budget as u64));
        }
        Progress::Evaluated { index, best, .. } => {
            done = index as u64 + 1;
            ran = 0;
            bar.set_position(done);
            bar.set_message(format!("best distance {best:.4}"));
        }
    };
    let outcome = crate::fit::run(
        &fit,
        out_dir,
        shard,
        jobs,
        &stop,
        args.status,
        &mut progress,
    )?;
    bar.finish_and_clear();
    match &outcome.halt {
        Halt::Interrupted => {
            write_page(&fit, &outcome, out_dir)?;
            eprintln!(
                "interrupted: {} run(s) kept in {}; run the same command again to resume",
                outcome.points.len(),
                out_dir.display()
            );
            return Ok(ExitCode::from(130));
        }
        Halt::Pending {
            generation,
            missing,
        } => {
            if args.status {
                eprintln!(
                    "pending: generation {generation} has {missing} run(s) to do ({} evaluated)",
                    outcome.points.len()
                );
                return Ok(ExitCode::from(3));
            }
            eprintln!(
                "this shard's runs of generation {generation} are done; {missing} run(s) of it are left to other shards: submit the array job again when they end"
            );
            return Ok(ExitCode::SUCCESS);
        }
        Halt::Done => {}
    }
    if stop.load(Ordering::Relaxed) {
        return Ok(ExitCode::from(130));
    }
    if args.status || shard.is_some() {
        eprintln!(
            "the fit is complete ({} runs){}",
            outcome.points.len(),
            if args.status {
                ""
            } else {
                "; run it without --shard for the report"
            }
        );
        return Ok(ExitCode::SUCCESS);
    }
    let table = report::table(&fit, &outcome);
    out!("{table}");
    let best = outcome.best().expect("a complete fit has its start");
    let fitted = report::write_fitted(&fit, best, out_dir)?;
    let comparison = report::write_comparison(&fit, &outcome, out_dir, &table)?;
    write_page(&fit, &outcome, out_dir)?;
    eprintln!(
        "fitted preset: {} (weft show {0}; weft gui {0})\ncomparison of {}: {} (weft view {2})",
        fitted.display(),
        if fit.reference.is_some() {
            "the start, the fit and the reference"
        } else {
            "the start and the fit"
        },
        comparison.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Writes the fit's page (`DIR/report.html`) and says where.
fn write_page(
    fit: &Fit,
    outcome: &crate::fit::Outcome,
    dir: &std::path::Path,
) -> anyhow::Result<()> {
    let page = crate::report::write(dir, &crate::report::fit::page(fit, outcome, dir)?)?;
    eprintln!("the fit's page: {} (open it in a browser)", page.display());
    Ok(())
}
