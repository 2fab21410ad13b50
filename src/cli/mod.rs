//! The `weft` command line: list, check, show, record and replay presets;
//! compare runs, sweep grids and fit weights. Each subcommand's options and output live
//! here (`compare.rs`, `sweep.rs`, `fit.rs`); the libraries below (`compare`,
//! `sweep`, `fit`, `record`, …) print nothing. Output goes through [`output`].

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand};

use crate::record::{Run, RunError, table, verdict};
use crate::scene::{Override, Scene, load, shipped};
use crate::telemetry::{self, DEFAULT_VIEWER, Telemetry, blueprint};

mod compare;
mod failure;
mod fit;
pub mod output;
mod sweep;

use output::{out, outln};

/// weft: oriented-particle cloth simulator and live-telemetry debugger.
#[derive(Debug, Parser)]
#[command(name = "weft", version, about, long_about = None)]
pub struct Cli {
    /// What to do (default: open the desktop debugger on flag_on_car).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the desktop debugger: the Rerun viewer and a tuning panel in one window.
    Gui(GuiArgs),
    /// List the shipped presets with a one-line description each.
    Presets,
    /// Validate preset files (or shipped names); exits non-zero if any is invalid.
    Check {
        /// Preset files or shipped preset names.
        #[arg(required = true)]
        presets: Vec<String>,
        /// Override a preset field, e.g. `--set solver.weights.normality=0.3`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
    },
    /// Print a preset as TOML, with `extend` and `--set` resolved: a start for your own.
    Show {
        /// Preset file or shipped preset name.
        preset: String,
        /// Override a preset field.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<Override>,
    },
    /// Run a preset headless and record its telemetry (to a file, a viewer or stdout).
    Record(RecordArgs),
    /// Re-run a recording and check that it reproduces its final state bit for bit.
    Replay {
        /// The `.rrd` file written by `weft record`.
        file: PathBuf,
    },
    /// Compare recorded runs side by side, write a comparison for the viewer, gate on regressions.
    Compare(compare::CompareArgs),
    /// Run a preset over a grid of settings (resumable, sharded on clusters), or collect one.
    Sweep(sweep::SweepArgs),
    /// Search live keys for the values that bring a preset closest to a reference run or target figures.
    Fit(fit::FitArgs),
    /// Open recordings in the embedded Rerun viewer, each with the layout weft gave it.
    View(ViewArgs),
    /// Make the page of a sweep's, a fit's or a comparison's results (DIR/report.html, with plots).
    #[command(after_help = "\
The commands write this page themselves as they finish (weft sweep, weft sweep --collect,
weft fit, weft compare --out); this makes it again, e.g. of a sweep run in shards.
Nothing is run: a sweep or fit not finished gives a page of what is done, labelled partial.")]
    Report {
        /// A directory written by `weft sweep`, `weft fit` or `weft compare --out`.
        dir: PathBuf,
    },
}

/// The live viewer's memory limit unless `--memory-limit` says otherwise:
/// about ten minutes of `flag_on_car` played at level `full`.
const VIEWER_MEMORY_LIMIT: &str = "1GB";

/// Options of `weft gui`.
#[derive(Debug, Args)]
pub struct GuiArgs {
    /// Preset file or shipped preset name.
    #[arg(default_value = "flag_on_car")]
    pub preset: String,
    /// Override a preset field, e.g. `--set solver.weights.normality=0.3`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<Override>,
    /// Play `--frames` frames, save a screenshot of the whole window to
    /// this PNG file, and quit (for checking the window, e.g. under Xvfb).
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Frames to play before the screenshot.
    #[arg(long, value_name = "N", default_value_t = 60, requires = "screenshot")]
    pub frames: u64,
    /// The most memory the viewer's recordings may take (`1GB`, `500MB`, a
    /// share of the machine's RAM such as `25%`, or `unlimited`); past it
    /// the viewer drops the oldest frames, farthest from its time cursor,
    /// first (docs/debugger.md, "Memory while playing").
    #[arg(long, value_name = "LIMIT", default_value = VIEWER_MEMORY_LIMIT)]
    pub memory_limit: String,
    /// Also save this many pictures while playing, evenly spread over the
    /// frames, beside the screenshot (`FILE-1.png`, `FILE-2.png`, …).
    #[arg(long, value_name = "K", default_value_t = 0, requires = "screenshot")]
    pub burst: u32,
    /// With `--screenshot`: record the run played to this `.rrd` file, as
    /// the panel's Record does.
    #[arg(long, value_name = "FILE.rrd", requires = "screenshot")]
    pub record: Option<PathBuf>,
}

/// Options of `weft view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Recordings (`.rrd`) written by weft (`record`, `sweep`, `compare`,
    /// `fit`, the window's sessions) or any Rerun 0.36 recording.
    #[arg(required = true, value_name = "FILE.rrd")]
    pub files: Vec<PathBuf>,
    /// Save a screenshot of the window to this PNG file a few seconds after
    /// it opens, and quit (for checking, e.g. under Xvfb).
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
}

/// Options of `weft record`.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// Preset file or shipped preset name.
    pub preset: String,
    /// Number of frames to run (default: the preset's `duration`).
    #[arg(long, conflicts_with = "seconds")]
    pub frames: Option<u64>,
    /// Simulated seconds to run (default: the preset's `duration`).
    #[arg(long)]
    pub seconds: Option<f32>,
    /// Override a preset field, e.g. `--set solver.iterations=20`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<Override>,
    /// Telemetry level: off, summary or full (same as `--set telemetry.level=…`).
    #[arg(long)]
    pub level: Option<String>,
    /// Log every N-th frame (same as `--set telemetry.log_every=N`).
    #[arg(long, value_name = "N")]
    pub log_every: Option<u32>,
    /// Smallest correction drawn as an arrow (same as `--set telemetry.arrow_threshold=X`).
    #[arg(long, value_name = "X")]
    pub arrow_threshold: Option<f32>,
    /// Colour particles by strain, speed, correction or none.
    #[arg(long, value_name = "QUANTITY")]
    pub color_by: Option<String>,
    /// Write the run's figures and verdicts as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub summary: Option<PathBuf>,
    /// Save the recording to this `.rrd` file.
    #[arg(long, value_name = "FILE.rrd", group = "sink")]
    pub save: Option<PathBuf>,
    /// Stream to a running Rerun viewer.
    #[arg(long, value_name = "URL", num_args = 0..=1, default_missing_value = DEFAULT_VIEWER, group = "sink")]
    pub connect: Option<String>,
    /// Write the recording to standard output (e.g. `| rerun -`).
    #[arg(long, short = 'o', group = "sink")]
    pub stdout: bool,
}

impl RecordArgs {
    /// The `--set` overrides, with the telemetry shortcuts appended.
    fn overrides(&self) -> Vec<Override> {
        let mut sets = self.set.clone();
        let mut add = |key: &str, value: toml::Value| {
            sets.push(Override {
                key: key.into(),
                value,
            })
        };
        if let Some(l) = &self.level {
            add("telemetry.level", toml::Value::String(l.clone()));
        }
        if let Some(n) = self.log_every {
            add("telemetry.log_every", toml::Value::Integer(n as i64));
        }
        if let Some(x) = self.arrow_threshold {
            add("telemetry.arrow_threshold", toml::Value::Float(x as f64));
        }
        if let Some(c) = &self.color_by {
            add("telemetry.color_by", toml::Value::String(c.clone()));
        }
        sets
    }
}

/// Runs a parsed command line; returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let command = cli.command.unwrap_or(Command::Gui(GuiArgs {
        preset: "flag_on_car".into(),
        set: Vec::new(),
        screenshot: None,
        memory_limit: VIEWER_MEMORY_LIMIT.into(),
        frames: 60,
        burst: 0,
        record: None,
    }));
    match command {
        Command::Gui(args) => gui(args),
        Command::Presets => {
            let width = shipped::ALL.iter().map(|p| p.name.len()).max().unwrap_or(0);
            for p in shipped::ALL {
                outln!("{:<width$}  {}", p.name, p.description());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Check { presets, set } => {
            let mut failed = 0;
            for p in &presets {
                match load::load(p, &set) {
                    Ok(l) => {
                        warn(&l);
                        let c = &l.preset.cloth;
                        outln!(
                            "ok      {p}: {}×{} cloth, {} bodies, {} colliders",
                            c.weft,
                            c.warp,
                            l.preset.bodies.len(),
                            l.preset.colliders.len()
                        );
                    }
                    Err(e) => {
                        failed += 1;
                        outln!("error   {e}");
                    }
                }
            }
            Ok(if failed == 0 {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            })
        }
        Command::Show { preset, set } => {
            let loaded = load::load(&preset, &set)?;
            warn(&loaded);
            out!("{}", load::to_toml(&loaded.preset));
            Ok(ExitCode::SUCCESS)
        }
        Command::Record(args) => record(args),
        Command::Compare(args) => compare::compare(args),
        Command::Sweep(args) => sweep::sweep(args),
        Command::Fit(args) => fit::fit(args),
        Command::View(args) => view(args),
        Command::Report { dir } => {
            let (kind, path) = crate::report::from_dir(&dir)?;
            eprintln!(
                "the {kind}'s page: {} (open it in a browser)",
                path.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Replay { file } => {
            let r = crate::replay::replay(&file)?;
            if r.truncated {
                outln!(
                    "{}: the file is cut short; compared what it holds",
                    file.display()
                );
            }
            let stored = r
                .recorded_digest
                .as_deref()
                .unwrap_or("none (the run did not finish)");
            outln!(
                "replayed {} frames with {} parameter changes: final state {}, recorded {}",
                r.frames,
                r.changes,
                r.digest,
                stored
            );
            if let Some(m) = r.positions_match {
                outln!(
                    "particles at the last logged frame: {}",
                    if m { "identical" } else { "DIFFERENT" }
                );
            }
            if r.reproduced() {
                outln!("reproduced bit for bit");
                Ok(ExitCode::SUCCESS)
            } else {
                outln!("NOT reproduced");
                match r.why_not() {
                    Some(why) => outln!(
                        "{}: {why}; this weft cannot reproduce it bit for bit (record it again to replay it)",
                        file.display()
                    ),
                    None => outln!(
                        "{} was made by this solver revision ({}): the same preset and parameters should step to the same state, so this is a fault of weft's determinism; please report it with the file",
                        file.display(),
                        crate::solver::REVISION
                    ),
                }
                Ok(ExitCode::FAILURE)
            }
        }
    }
}

#[cfg(feature = "viewer")]
fn gui(args: GuiArgs) -> anyhow::Result<ExitCode> {
    let screenshot = args.screenshot.map(|path| crate::app::Screenshot {
        path,
        frames: args.frames,
        burst: args.burst,
        record: args.record,
    });
    crate::app::run(&args.preset, &args.set, &args.memory_limit, screenshot)?;
    Ok(ExitCode::SUCCESS)
}

/// `weft view`: every file is checked before the window opens.
fn view(args: ViewArgs) -> anyhow::Result<ExitCode> {
    for f in &args.files {
        telemetry::read::check(f)?;
    }
    open_view(&args)
}

#[cfg(feature = "viewer")]
fn open_view(args: &ViewArgs) -> anyhow::Result<ExitCode> {
    crate::app::view(&args.files, args.screenshot.as_deref())?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(not(feature = "viewer"))]
fn open_view(_args: &ViewArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "this weft was built without the desktop debugger (feature `viewer`); rebuild with default features"
    )
}

#[cfg(not(feature = "viewer"))]
fn gui(_args: GuiArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "this weft was built without the desktop debugger (feature `viewer`); rebuild with default features"
    )
}

fn record(args: RecordArgs) -> anyhow::Result<ExitCode> {
    let loaded = load::load(&args.preset, &args.overrides())?;
    warn(&loaded);
    let preset = &loaded.preset;
    let scene =
        Scene::new(preset).with_context(|| format!("building the scene of {}", args.preset))?;
    let frames = match (args.frames, args.seconds) {
        (Some(n), _) => n,
        (None, Some(s)) if s.is_finite() && s > 0.0 => scene.frames_in(s),
        (None, Some(s)) => bail!("--seconds {s}: expected a positive number of seconds"),
        (None, None) => scene.frames_in(preset.duration),
    };

    // The sink is opened before anything is simulated: an unwritable path or
    // an unreachable viewer fails here.
    let rec = open_sink(&args)?;
    let telemetry = Telemetry::new(rec.clone(), preset.telemetry);
    let mut run = Run::start(scene, telemetry, &args.preset, &loaded.resolved)?;
    if let Some(url) = &args.connect {
        rec.flush_with_timeout(std::time::Duration::from_secs(10)).map_err(|e| {
            anyhow::anyhow!(
                "could not reach a Rerun viewer at {url} ({e}); start one with `rerun` (pip install rerun-sdk==0.36.3), or record to a file with --save FILE.rrd"
            )
        })?;
    }

    // The first Ctrl-C stops after the current frame and closes the file
    // cleanly; a second one quits at once.
    let stop = crate::interrupt::stop_flag(None);

    let bar = indicatif::ProgressBar::new(frames).with_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} frames, {per_sec}, eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message(args.preset.clone());
    let outcome = run.run(frames, &stop, |_| bar.inc(1));
    bar.finish_and_clear();

    let mut failed = outcome.is_err();
    // Rerun's file writer says only that it stopped: say what happened,
    // whether a frame's logging or the summary's found it stopped.
    let frame = run.scene.frame();
    let told = |e: &RunError| match (e, &args.save) {
        (RunError::Telemetry(_) | RunError::Flush(_), Some(path)) => {
            failure::write_failure(path, frame)
        }
        _ => e.to_string(),
    };
    let figures = match outcome {
        Err(e) => {
            eprintln!("error: {}", told(&e));
            // A stream that failed takes no summary; the figures are told.
            run.figures()
        }
        Ok(()) => match run.close() {
            (figures, Ok(())) => figures,
            (figures, Err(e)) if args.save.is_some() => {
                eprintln!("error: {}", told(&e));
                failed = true;
                figures
            }
            (_, Err(e)) => return Err(e.into()),
        },
    };
    drop(rec);
    let checks = verdict(preset.expect.as_ref(), &figures);
    eprint!("{}", table(&figures, &checks));
    if let Some(path) = &args.summary {
        let json = serde_json::json!({ "figures": figures, "checks": checks });
        std::fs::write(path, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("writing the summary to {}", path.display()))?;
    }
    if failed {
        return Ok(ExitCode::FAILURE);
    }
    // An interrupted run cannot be judged (it did not reach its end).
    if figures.interrupted {
        return Ok(ExitCode::from(130));
    }
    if checks.iter().any(|c| !c.ok) {
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints a loaded preset's warnings to standard error.
fn warn(loaded: &load::Loaded) {
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
}

/// The recording stream `args` ask for, its layout sent first.
fn open_sink(args: &RecordArgs) -> anyhow::Result<rerun::RecordingStream> {
    let rec = open_stream(args)?;
    blueprint::send_default(&rec).context("sending the viewer layout")?;
    Ok(rec)
}

fn open_stream(args: &RecordArgs) -> anyhow::Result<rerun::RecordingStream> {
    let builder = rerun::RecordingStreamBuilder::new("weft");
    if let Some(path) = &args.save {
        return builder
            .batcher_config(telemetry::file_batching()?)
            .save(path)
            .map_err(|e| anyhow::anyhow!("cannot write the recording to {}: {e}", path.display()));
    }
    if let Some(url) = &args.connect {
        return builder
            .connect_grpc_opts(url.clone())
            .map_err(|e| anyhow::anyhow!("cannot connect to a Rerun viewer at {url}: {e}"));
    }
    if args.stdout {
        return builder
            .batcher_config(telemetry::file_batching()?)
            .stdout()
            .context("streaming the recording to standard output");
    }
    eprintln!("note: no --save, --connect or --stdout: the telemetry is not kept");
    Ok(rerun::RecordingStream::disabled())
}
