//! A live session: the simulation on its own thread, driven by commands from
//! the panel, reporting a [`Status`] back.
//!
//! Every run of a session (the first, and each Reset, Load, Record or
//! Branch) is its own Rerun recording, with a new recording id, a name a
//! person can read (`#2 flag_on_car · normality 0.2→0.45 · branch of #1 at
//! frame 180`) and recording properties (`weft`: version, preset, run,
//! changes, parent and frame of a branch; `result`, when the run ends: frames,
//! final-state digest, verdict). Earlier runs stay in the viewer's recording
//! list. The thread owns the current [`Run`](crate::record::Run) (scene + telemetry) and its
//! [`History`](crate::app::history::History) (checkpoints, to branch from any frame). Telemetry goes
//! through a `Tee` (`runs.rs`): always to the viewer (or wherever the caller forwards
//! it), and to an `.rrd` file when the run is being recorded, so the file
//! gets exactly one run, from its first message. A change of parameters
//! applies at the next step and is logged at the frame it takes effect.

pub mod follow;
mod runs;
pub mod trace;
mod worker;

use std::path::PathBuf;
use std::sync::mpsc::{Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;
use rerun::log::LogMsg;

use crate::record::Check;
use crate::scene::{Loaded, Tuning, preset::TelemetrySettings};
use crate::solver::PerFamily;

pub use runs::Series;
use worker::Worker;

/// What the panel asks of the session.
#[derive(Clone, Debug)]
pub enum Command {
    /// Run in real time (times the speed).
    Play,
    /// Play until this frame, then pause there (`weft gui --screenshot`).
    PlayTo(u64),
    /// Stop stepping.
    Pause,
    /// Step one frame (pauses).
    Step,
    /// Start the scene over from its preset, keeping the tuning (a new run).
    Reset,
    /// Simulated seconds per wall-clock second.
    Speed(f32),
    /// New solver parameters and wind, from the next step.
    Tune(Tuning),
    /// New telemetry settings.
    Telemetry(TelemetrySettings),
    /// Whether the correction arrows are drawn (level full; off at start).
    Arrows(bool),
    /// Inspect the particle nearest this point (world coordinates, at the
    /// current frame): a click on the cloth's mesh in the 3D view.
    InspectNear([f32; 3]),
    /// Load another preset (validated by the caller) and start over.
    Load(Box<Loaded>, String),
    /// Start recording to an `.rrd` file (a new run).
    StartRecording(PathBuf),
    /// Stop recording and close the file.
    StopRecording,
    /// Start a new run from a frame of the current one, with the current
    /// tuning from the next step on (pauses).
    Branch(BranchAt),
    /// Which particle the inspector follows.
    Inspect(Option<usize>),
    /// Whether a branch's 3D view draws its parent's cloth, faint, beside
    /// its own (on at start; kept for later runs).
    Ghost(bool),
    /// Grab the particle nearest this point (world coordinates, at the
    /// current frame): from the next step it is pulled with a spring
    /// towards where it is now, until [`Command::Release`]
    /// ([`crate::app::pull`]).
    Grab([f32; 3]),
    /// Grab the particle nearest the ray from a point along a unit vector
    /// (world coordinates), if one is near enough ([`crate::app::pull::grab_along`]):
    /// a press beside the cloth's surface.
    GrabAlong([f32; 3], [f32; 3]),
    /// Move the grabbed particle's target (world coordinates) from the
    /// next step on.
    PullTo([f64; 3]),
    /// Let go of the grabbed particle from the next step on.
    Release,
}

/// What the viewer last showed, for pacing the simulation to it.
#[derive(Default)]
pub(crate) struct Shown {
    /// Whether the simulation waits for the viewer (a window has one).
    pub(crate) pace: bool,
    /// The recording id, where the viewer's time cursor was, and when it
    /// moved there.
    pub(crate) at: Option<(String, BranchAt, Instant)>,
    /// How many times the window has drawn: a paced simulation sends a
    /// frame's drawing only once the window has drawn since the last one
    /// (the other frames' scalars only), so the viewer is never sent more
    /// than it shows.
    pub(crate) drawn: u64,
    /// The viewer's time cursor, moved by the session while it plays.
    pub(crate) follow: follow::Follow,
}

/// Where the viewer's time cursor is, for pacing the simulation
/// ([`Session::viewer_shows`]).
#[derive(Clone)]
pub struct CursorReports(Arc<Mutex<Shown>>);

impl CursorReports {
    /// See [`Session::viewer_shows`].
    pub fn shows(&self, recording: String, at: BranchAt) {
        let mut shown = self.0.lock().expect("not poisoned");
        let back = match (&shown.at, at) {
            (Some((id, BranchAt::Time(a), _)), BranchAt::Time(b)) => *id == recording && b < *a,
            (Some((id, BranchAt::Frame(a), _)), BranchAt::Frame(b)) => *id == recording && b < *a,
            _ => false,
        };
        shown.follow.reported(&recording, at, back);
        shown.at = (!back).then(|| (recording, at, Instant::now()));
    }
}

/// Where a branch starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BranchAt {
    /// At this frame.
    Frame(u64),
    /// At the frame shown at this simulated time (the viewer's time cursor).
    Time(f64),
}

/// One run of the session: one Rerun recording.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunInfo {
    /// 1 for the session's first run, then 2, 3…
    pub number: u32,
    /// The Rerun recording id.
    pub recording_id: String,
    /// The recording's name.
    pub name: String,
    /// For a branch: the parent's number and recording id, and the frame.
    pub parent: Option<(u32, String, u64)>,
}

/// What the inspector shows of one particle, after the last step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParticleReadout {
    /// Index in the cloth.
    pub index: usize,
    /// Grid cell: `i` along the weft, `j` along the warp.
    pub cell: (u32, u32),
    /// Largest strain of its weft and warp edges.
    pub strain: f32,
    /// The angle between its normal and the surface's, radians (above
    /// π/2: it faces the other way).
    pub normal_offset: f32,
    /// Per family, the largest violation of the constraints that involve it.
    pub violation: PerFamily<f32>,
    /// Whether the last step recorded its corrections (`dx` and `dtheta`
    /// are zero if not): from the step after the particle is picked, or at
    /// every step at level full or colouring by correction.
    pub corrections: bool,
    /// Per family, the translation applied to it in the last adjust.
    pub dx: PerFamily<Vec3>,
    /// Per family, the rotation applied to it (axis × angle, radians).
    pub dtheta: PerFamily<Vec3>,
}

/// What the session reports to the panel.
#[derive(Clone, Debug, Default)]
pub struct Status {
    /// The preset's name or path.
    pub preset_name: String,
    /// The loaded preset, with the current tuning applied.
    pub preset: Option<crate::scene::Preset>,
    /// The current run.
    pub run: RunInfo,
    /// Every run of the session, oldest first.
    pub runs: Vec<RunInfo>,
    /// The current frame.
    pub frame: u64,
    /// Simulated seconds.
    pub time: f64,
    /// Whether it is playing.
    pub playing: bool,
    /// Simulation speed.
    pub speed: f32,
    /// Frames per wall-clock second, recently.
    pub steps_per_second: f32,
    /// Wall time of the last step, in milliseconds.
    pub step_ms: f32,
    /// Violation after the last step, per family.
    pub max_violation: PerFamily<f32>,
    /// Largest edge strain after the last step.
    pub max_strain: f32,
    /// Edges of the cloth crossing one of its triangles after the last
    /// step (the cloth passing through itself), whatever self-collision's
    /// weight.
    pub crossings: usize,
    /// Digest of the current state (see `ClothState::digest`), in hex.
    pub digest: String,
    /// The preset's `[expect]` bounds against the run's values so far.
    pub checks: Vec<Check>,
    /// Checkpoints kept for branching, and frames between them.
    pub checkpoints: (usize, u64),
    /// The inspected particle.
    pub particle: Option<ParticleReadout>,
    /// The grabbed particle, where it is and where it is pulled to.
    pub pull: Option<crate::app::pull::Pulled>,
    /// The last [`Command::InspectNear`]'s particle, with how many have
    /// been handled (so the panel sees each once).
    pub picked: Option<(u64, usize)>,
    /// The recording file, while recording.
    pub recording: Option<PathBuf>,
    /// The last error (a solver failure or a file problem).
    pub error: Option<String>,
}

/// Called by the simulation thread whenever the [`Status`] changes (the
/// window asks egui for a repaint: nothing else repaints it while paused).
pub type Waker = Arc<dyn Fn() + Send + Sync>;

/// The handle the panel holds.
pub struct Session {
    tx: Sender<Command>,
    status: Arc<Mutex<Status>>,
    waker: Arc<Mutex<Option<Waker>>>,
    shown: Arc<Mutex<Shown>>,
    thread: Option<JoinHandle<()>>,
}

/// What went wrong in the simulation thread: starting or ending a run,
/// recording, or replaying a run's history to a frame.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The preset's scene could not be built.
    #[error(transparent)]
    Setup(#[from] crate::solver::SetupError),
    /// A run could not be started, logged or finished.
    #[error(transparent)]
    Run(#[from] Box<crate::record::RunError>),
    /// Parameters that do not apply.
    #[error(transparent)]
    Params(#[from] crate::solver::ParamError),
    /// Rerun refused a message (the layout, a property).
    #[error(transparent)]
    Stream(#[from] rerun::RecordingStreamError),
    /// The viewer or the file did not take everything logged.
    #[error(transparent)]
    Flush(#[from] rerun::sink::SinkFlushError),
    /// The recording file could not be completed.
    #[error("the recording file may be incomplete: {0}")]
    File(rerun::external::re_log_encoding::FileFlushError),
    /// The simulation thread could not be started.
    #[error("starting the simulation thread: {0}")]
    Thread(std::io::Error),
    /// A frame the run's history does not reach.
    #[error("frame {0} is before this run started")]
    BeforeRun(u64),
    /// The tuning stored for a frame does not apply.
    #[error("the tuning at frame {frame}: {source}")]
    Tuning {
        /// The frame.
        frame: u64,
        /// Why.
        source: crate::solver::ParamError,
    },
    /// The solver failed replaying the history.
    #[error("stepping to frame {frame}: {source}")]
    Step {
        /// The frame.
        frame: u64,
        /// The failure.
        source: crate::solver::StepError,
    },
}

impl From<crate::record::RunError> for SessionError {
    fn from(e: crate::record::RunError) -> Self {
        Self::Run(Box::new(e))
    }
}

impl Session {
    /// Starts a paused session of `loaded`, its telemetry forwarded to `forward`.
    pub fn start(
        loaded: Loaded,
        name: String,
        forward: impl Fn(&LogMsg) + Send + Sync + 'static,
    ) -> Result<Self, SessionError> {
        let status = Arc::new(Mutex::new(Status {
            preset_name: name.clone(),
            preset: Some(loaded.preset.clone()),
            speed: 1.0,
            ..Status::default()
        }));
        let waker: Arc<Mutex<Option<Waker>>> = Arc::default();
        let shown: Arc<Mutex<Shown>> = Arc::default();
        let worker = Worker::new(
            loaded,
            name,
            Arc::new(forward),
            status.clone(),
            waker.clone(),
            shown.clone(),
        )?;
        let (tx, rx) = channel();
        let thread = std::thread::Builder::new()
            .name("weft-sim".into())
            .spawn(move || worker.serve(rx))
            .map_err(SessionError::Thread)?;
        Ok(Self {
            tx,
            status,
            waker,
            shown,
            thread: Some(thread),
        })
    }

    /// Has the simulation wait for the viewer (see [`Session::viewer_shows`]);
    /// the window does, a session without a viewer does not.
    pub fn pace_to_viewer(&self) {
        self.shown.lock().expect("not poisoned").pace = true;
    }

    /// Notes that the window has drawn a frame (see [`Shown::drawn`]).
    pub fn window_drew(&self) {
        self.shown.lock().expect("not poisoned").drawn += 1;
    }

    /// Notes where the viewer's time cursor is on recording `recording`
    /// (reported each time it moves). While it moves forward, following the
    /// stream, a paced simulation keeps no more than [`MAX_LEAD`] seconds
    /// ahead of it: it never runs ahead of what the viewer can take in and
    /// draw. A cursor moved back (the user scrubbed), or on another
    /// recording, does not hold it back, nor, unless the session moves the
    /// cursor ([`follow`]), one standing still for [`FOLLOWING`] (the
    /// viewer's timeline paused).
    pub fn viewer_shows(&self, recording: String, at: BranchAt) {
        self.cursor_reports().shows(recording, at);
    }

    /// What the viewer's event callback reports the time cursor to, at once
    /// (the panel, which also reads it, draws only at the next frame).
    pub fn cursor_reports(&self) -> CursorReports {
        CursorReports(self.shown.clone())
    }

    /// Has the simulation thread call `hook` after it has sent the whole
    /// drawing of a frame, while it moves the viewer's time cursor
    /// ([`follow`]): the window sends the viewer, after the frame's drawing,
    /// a command to put the cursor on that frame.
    pub fn on_whole_frame(&self, hook: impl Fn(&follow::WholeFrame) + Send + Sync + 'static) {
        self.shown.lock().expect("not poisoned").follow.hook = Some(Arc::new(hook));
    }

    /// Has the simulation thread call `waker` after every change of the
    /// status (a step, a command handled, an error).
    pub fn set_waker(&self, waker: impl Fn() + Send + Sync + 'static) {
        *self.waker.lock().expect("not poisoned") = Some(Arc::new(waker));
    }

    /// Sends a command; it is handled before the next step.
    /// If the simulation thread has ended (it only does on a bug), the
    /// status says so.
    pub fn send(&self, c: Command) {
        if self.tx.send(c).is_err() {
            self.status.lock().expect("not poisoned").error =
                Some("the simulation thread has stopped; restart weft".into());
        }
    }

    /// The latest status.
    pub fn status(&self) -> Status {
        self.status.lock().expect("not poisoned").clone()
    }

    /// Waits (up to `timeout`) until `done` holds for the status.
    pub fn wait_for(&self, timeout: Duration, done: impl Fn(&Status) -> bool) -> bool {
        let start = Instant::now();
        while start.elapsed() < timeout {
            if done(&self.status()) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        done(&self.status())
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // Closing the channel ends the worker, which closes any recording.
        let (tx, _) = channel();
        drop(std::mem::replace(&mut self.tx, tx));
        if let Some(t) = self.thread.take()
            && t.join().is_err()
        {
            eprintln!("error: the simulation thread panicked");
        }
    }
}

/// How far (simulated seconds) the simulation may run ahead of the frame
/// the viewer shows while the viewer follows it.
pub const MAX_LEAD: f64 = 0.25;

/// A viewer cursor that has not moved for this long is not following the
/// stream (see [`Session::viewer_shows`]).
pub const FOLLOWING: Duration = Duration::from_secs(2);

/// `ok`, or `FAIL: expect.max_strain, …` (empty without bounds).
pub fn verdict_text(checks: &[Check]) -> String {
    if checks.is_empty() {
        return "no [expect] bounds".into();
    }
    let failed: Vec<&str> = checks
        .iter()
        .filter(|c| !c.ok)
        .map(|c| c.bound.as_str())
        .collect();
    if failed.is_empty() {
        "ok".into()
    } else {
        format!("FAIL: {}", failed.join(", "))
    }
}
