//! `weft sweep`: its options, the progress bar, Ctrl-C, and `--collect`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use std::sync::atomic::Ordering;

use anyhow::bail;
use clap::Args;

use super::output::out;
use crate::compare::{read_all, recording, report};
use crate::sweep::collect::{self, Format};
use crate::sweep::grid::Axis;
use crate::sweep::shard::{self, Shard};
use crate::sweep::{MAX_POINTS, MAX_SECONDS, Plan, Progress};

/// Options of `weft sweep`.
#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  weft sweep flag_on_car --set solver.weights.normality=0.1,0.2,0.3,0.45 \\
      --set solver.iterations=5,10 --out runs/
  weft sweep hanging_sheet --set solver.weights.normality=0.1..0.5:8 --frames 120 --out runs/
  weft sweep --collect runs/ --sort max_strain

Points are named INDEX_KEY=VALUE_…; each writes NAME.rrd and NAME.json under --out, and
sweep.json describes the grid. Re-running the same command skips finished points.
Inside a Slurm array task (or with --shard I/N, or JOB_COMPLETION_INDEX and --shards N)
only the points whose index is I modulo N run; see docs/cluster.md.")]
pub struct SweepArgs {
    /// Preset file or shipped preset name.
    #[arg(required_unless_present = "collect")]
    pub preset: Option<String>,
    /// A swept key: `KEY=V1,V2,…` or a range `KEY=A..B:N` (N values from A to
    /// B); repeat for a grid. The first varies slowest.
    #[arg(long = "set", value_name = "KEY=V1,V2,…")]
    pub set: Vec<Axis>,
    /// The directory for the points' files.
    #[arg(long, value_name = "DIR", required_unless_present = "collect")]
    pub out: Option<PathBuf>,
    /// Telemetry level of each point's recording: off, summary or full.
    #[arg(long, default_value = "summary")]
    pub level: String,
    /// Frames per point (default: the preset's `duration`).
    #[arg(long, conflicts_with = "seconds")]
    pub frames: Option<u64>,
    /// Simulated seconds per point.
    #[arg(long)]
    pub seconds: Option<f32>,
    /// Points run at once (default: the number of cores).
    #[arg(long, short = 'j')]
    pub jobs: Option<usize>,
    /// Run only the points whose index is I modulo N.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// The number of shards, with the index from the environment
    /// (`JOB_COMPLETION_INDEX` of a Kubernetes Indexed Job).
    #[arg(long, value_name = "N", conflicts_with = "shard")]
    pub shards: Option<usize>,
    /// Run even a sweep larger than 256 points or longer than an hour.
    #[arg(long, short = 'y')]
    pub yes: bool,

    /// Collect a sweep directory into one table instead of running.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["preset", "out", "set", "shard", "shards"])]
    pub collect: Option<PathBuf>,
    /// Sort the table by this figure, swept key, `name` or `index`.
    #[arg(
        long,
        value_name = "FIGURE",
        default_value = "index",
        requires = "collect"
    )]
    pub sort: String,
    /// Sort in descending order (e.g. for steps_per_second).
    #[arg(long, requires = "collect")]
    pub desc: bool,
    /// Print the table as CSV.
    #[arg(long, requires = "collect", group = "format")]
    pub csv: bool,
    /// Print the table as JSON.
    #[arg(long, requires = "collect", group = "format")]
    pub json: bool,
    /// Print the table as Markdown.
    #[arg(long, requires = "collect", group = "format")]
    pub markdown: bool,
    /// How many of the first points of the sorted table go into the
    /// comparison recording (0: none).
    #[arg(long, value_name = "K", default_value_t = 3, requires = "collect")]
    pub best: usize,
    /// Where the comparison of the best points goes (default: DIR/best.rrd).
    #[arg(long, value_name = "FILE.rrd", requires = "collect")]
    pub save: Option<PathBuf>,
}

/// Runs `weft sweep`.
pub fn sweep(args: SweepArgs) -> anyhow::Result<ExitCode> {
    if let Some(dir) = &args.collect {
        return collect_command(dir, &args);
    }
    let (Some(preset), Some(out)) = (&args.preset, &args.out) else {
        bail!("a sweep needs a preset and --out DIR");
    };
    let shard = shard::resolve(args.shard, args.shards, |k| std::env::var(k).ok())?;
    let plan = Plan::new(
        preset,
        args.set.clone(),
        args.frames,
        args.seconds,
        &args.level,
    )?;
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    let mine = plan
        .points
        .iter()
        .filter(|(p, _)| shard.is_none_or(|s| s.contains(p.index)))
        .count();
    let estimate = plan.estimate(shard, jobs);
    if !args.yes && (mine > MAX_POINTS || estimate > MAX_SECONDS) {
        bail!(
            "this sweep has {} points{} and would take about {} on {jobs} job(s) (from timing a few frames here); pass --yes to run it, or shard it (docs/cluster.md)",
            mine,
            shard
                .map(|s| format!(" in shard {s} ({} in all)", plan.points.len()))
                .unwrap_or_default(),
            duration(estimate)
        );
    }

    let stop = crate::interrupt::stop_flag(Some(
        "stopping after the points running now (Ctrl-C again to quit at once)",
    ));

    let bar = indicatif::ProgressBar::new(0).with_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} points, eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(preset.clone());
    let where_ = shard.map(|s| format!(", shard {s}")).unwrap_or_default();
    let outcome = crate::sweep::run(&plan, out, shard, jobs, &stop, |p| match p {
        Progress::Start { total, skipped } => {
            bar.set_length(total as u64);
            bar.set_position(skipped as u64);
            bar.reset_eta();
            bar.suspend(|| {
                eprintln!(
                    "sweep of {preset}: {} points{where_}, {total} here, {skipped} already done, {jobs} job(s), into {}",
                    plan.points.len(),
                    out.display()
                )
            });
        }
        Progress::Done(r, t) => {
            bar.inc(1);
            bar.suspend(|| {
                eprintln!(
                    "  {} in {:.1} s: max strain {:.4}, {}",
                    r.name,
                    t.as_secs_f64(),
                    r.figures.max_strain,
                    r.verdict()
                )
            });
        }
        Progress::Error(e) => bar.suspend(|| eprintln!("  error: {e}")),
    })?;
    bar.finish_and_clear();
    if shard.is_none() {
        // Shards write no page: `weft sweep --collect` makes it of the whole.
        let c = crate::sweep::collect::read(out)?;
        let page = crate::report::write(out, &crate::report::sweep::page(&c, out)?)?;
        eprintln!(
            "the sweep's page: {} (open it in a browser)",
            page.display()
        );
    }
    eprintln!(
        "{} run, {} already done{}{}; collect with `weft sweep --collect {}`",
        outcome.ran,
        outcome.skipped,
        if outcome.left > 0 {
            format!(
                ", {} not run (interrupted: run the same command again to resume)",
                outcome.left
            )
        } else {
            String::new()
        },
        if outcome.errors.is_empty() {
            String::new()
        } else {
            format!(", {} could not be run or written", outcome.errors.len())
        },
        out.display()
    );
    if !outcome.errors.is_empty() {
        return Ok(ExitCode::from(2));
    }
    if outcome.left > 0 || stop.load(Ordering::Relaxed) {
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::SUCCESS)
}

fn duration(secs: f64) -> String {
    let s = secs.round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, (s % 3600) / 60),
    }
}

fn collect_command(dir: &Path, args: &SweepArgs) -> anyhow::Result<ExitCode> {
    let mut c = collect::read(dir)?;
    collect::sort(&mut c.points, &args.sort, args.desc)?;
    let format = if args.csv {
        Format::Csv
    } else if args.json {
        Format::Json
    } else if args.markdown {
        Format::Markdown
    } else {
        Format::Text
    };
    out!("{}", collect::render(&c.points, format));
    let page = crate::report::write(dir, &crate::report::sweep::page(&c, dir)?)?;
    eprintln!(
        "the sweep's page: {} (open it in a browser)",
        page.display()
    );
    if !c.missing.is_empty() {
        eprintln!(
            "{} of {} points not finished: {}",
            c.missing.len(),
            c.missing.len() + c.points.len(),
            c.missing.join(", ")
        );
    }
    let best: Vec<PathBuf> = c
        .points
        .iter()
        .take(args.best)
        .map(|p| dir.join(format!("{}.rrd", p.name)))
        .collect();
    if !best.is_empty() {
        let path = args.save.clone().unwrap_or_else(|| dir.join("best.rrd"));
        let runs = read_all(&best)?;
        let text = report::report(&runs);
        let rec = recording::open(&runs, Some(&path), None)?;
        recording::write(&rec, &runs, recording::Placement::SideBySide(None), &text)?;
        drop(rec);
        eprintln!(
            "the first {} by {}: {} → {} (weft compare {} for the details)",
            runs.len(),
            args.sort,
            runs.iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            path.display(),
            best.iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    Ok(ExitCode::SUCCESS)
}
