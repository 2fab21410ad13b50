//! A live session: the simulation on its own thread, driven by commands from
//! the panel, reporting a [`Status`] back.
//!
//! Every run of a session (the first, and each Reset, Load, Record or
//! Branch) is its own Rerun recording, with a new recording id, a name a
//! person can read (`#2 flag_on_car · curvature 0.1→0.35 · branch of #1 at
//! frame 180`) and recording properties (`weft`: version, preset, run,
//! changes, parent and frame of a branch; `result`, when the run ends: frames,
//! final-state digest, verdict). Earlier runs stay in the viewer's recording
//! list. The thread owns the current [`Run`] (scene + telemetry) and its
//! [`History`] (checkpoints, to branch from any frame). Telemetry goes
//! through a [`Tee`]: always to the viewer (or wherever the caller forwards
//! it), and to an `.rrd` file when the run is being recorded, so the file
//! gets exactly one run, from its first message. A change of parameters
//! applies at the next step and is logged at the frame it takes effect.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;
use rerun::log::LogMsg;
use rerun::sink::FileSink;

use super::history::History;
use super::preset_diff;
use crate::record::{Check, Run, Snapshot, verdict};
use crate::scene::{Loaded, Preset, Scene, Tuning, load, preset::TelemetrySettings};
use crate::solver::{Family, PerFamily};
use crate::telemetry::{Telemetry, blueprint};

/// What the panel asks of the session.
#[derive(Clone, Debug)]
pub enum Command {
    /// Run in real time (times the speed).
    Play,
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
    /// Per family, the largest violation of the constraints that involve it.
    pub violation: PerFamily<f32>,
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
    /// Digest of the current state (see `ClothState::digest`), in hex.
    pub digest: String,
    /// The preset's `[expect]` bounds against the run's values so far.
    pub checks: Vec<Check>,
    /// Checkpoints kept for branching, and frames between them.
    pub checkpoints: (usize, u64),
    /// The inspected particle.
    pub particle: Option<ParticleReadout>,
    /// The recording file, while recording.
    pub recording: Option<PathBuf>,
    /// The last error (a solver failure or a file problem).
    pub error: Option<String>,
}

type Forward = Arc<dyn Fn(&LogMsg) + Send + Sync>;

/// Forwards every message to `forward`, and to a file while recording.
pub struct Tee {
    forward: Forward,
    file: Mutex<Option<FileSink>>,
}

impl Tee {
    fn send(&self, msg: &LogMsg) {
        (self.forward)(msg);
        if let Some(file) = self.file.lock().expect("not poisoned").as_ref() {
            file.send(msg.clone());
        }
    }

    /// Writes the footer and closes the file, if there is one.
    fn stop(&self) -> Result<(), String> {
        let file = self.file.lock().expect("not poisoned").take();
        match file {
            Some(f) => f
                .flush_blocking(Duration::from_secs(10))
                .map_err(|e| format!("the recording file may be incomplete: {e}")),
            None => Ok(()),
        }
    }
}

/// A new recording named `name`, with weft's blueprint, whose messages go
/// to `forward` and, from the first one, to `file`.
pub fn stream(
    forward: Forward,
    name: &str,
    file: Option<FileSink>,
) -> (rerun::RecordingStream, Arc<Tee>) {
    let tee = Arc::new(Tee {
        forward,
        file: Mutex::new(file),
    });
    let sink_tee = tee.clone();
    let rec = rerun::RecordingStreamBuilder::new("weft")
        .recording_name(name)
        .with_default_blueprint(blueprint::default())
        .buffered()
        .expect("a buffered stream always opens");
    rec.set_sink(Box::new(rerun::sink::CallbackSink::new(move |msgs| {
        for m in msgs {
            sink_tee.send(m);
        }
    })));
    (rec, tee)
}

/// The handle the panel holds.
pub struct Session {
    tx: Sender<Command>,
    status: Arc<Mutex<Status>>,
    thread: Option<JoinHandle<()>>,
}

impl Session {
    /// Starts a paused session of `loaded`, its telemetry forwarded to `forward`.
    pub fn start(
        loaded: Loaded,
        name: String,
        forward: impl Fn(&LogMsg) + Send + Sync + 'static,
    ) -> Result<Self, String> {
        let status = Arc::new(Mutex::new(Status {
            preset_name: name.clone(),
            preset: Some(loaded.preset.clone()),
            speed: 1.0,
            ..Status::default()
        }));
        let worker = Worker::new(loaded, name, Arc::new(forward), status.clone())?;
        let (tx, rx) = channel();
        let thread = std::thread::Builder::new()
            .name("weft-sim".into())
            .spawn(move || worker.serve(rx))
            .map_err(|e| e.to_string())?;
        Ok(Self {
            tx,
            status,
            thread: Some(thread),
        })
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

/// How a new run starts.
enum Start {
    /// From frame 0 of this preset (the tuning already in it).
    Fresh(Box<Loaded>),
    /// From a frame of the current run.
    Branch {
        snapshot: Box<Snapshot>,
        history: Box<History>,
        tuning: Tuning,
        /// The parent's plotted values, drawn beside the branch's.
        parent_series: Series,
    },
}

/// A run's plotted values per frame (from frame 1): simulated time, max
/// strain, kinetic energy and each family's max violation (in
/// [`Family::index`] order).
pub type Series = Vec<(u64, f64, [f32; 2 + Family::COUNT])>;

struct Worker {
    run: Run,
    history: History,
    series: Series,
    info: RunInfo,
    runs: Vec<RunInfo>,
    loaded: Loaded,
    name: String,
    rec: rerun::RecordingStream,
    tee: Arc<Tee>,
    forward: Forward,
    inspect: Option<usize>,
    status: Arc<Mutex<Status>>,
    playing: bool,
    speed: f32,
    next_step: Instant,
    recent: std::collections::VecDeque<Instant>,
}

/// A new run of `scene` (or `snapshot`) into a new recording.
struct Opened {
    run: Run,
    history: History,
    info: RunInfo,
    rec: rerun::RecordingStream,
    tee: Arc<Tee>,
}

impl Worker {
    fn new(
        loaded: Loaded,
        name: String,
        forward: Forward,
        status: Arc<Mutex<Status>>,
    ) -> Result<Self, String> {
        let base = load::load(&name, &[]).ok().map(|l| l.preset);
        let opened = open(
            &forward,
            Start::Fresh(Box::new(loaded.clone())),
            &name,
            RunInfo {
                number: 1,
                ..RunInfo::default()
            },
            loaded.preset.telemetry,
            base,
            None,
        )?;
        let worker = Self {
            run: opened.run,
            history: opened.history,
            series: Series::new(),
            runs: vec![opened.info.clone()],
            info: opened.info,
            loaded,
            name,
            rec: opened.rec,
            tee: opened.tee,
            forward,
            inspect: None,
            status,
            playing: false,
            speed: 1.0,
            next_step: Instant::now(),
            recent: Default::default(),
        };
        worker.publish();
        Ok(worker)
    }

    fn serve(mut self, rx: Receiver<Command>) {
        loop {
            // Paused, wait for a command; playing, take what has arrived.
            let first = if self.playing {
                match rx.try_recv() {
                    Ok(c) => Some(c),
                    Err(std::sync::mpsc::TryRecvError::Empty) => None,
                    Err(std::sync::mpsc::TryRecvError::Disconnected) => break,
                }
            } else {
                match rx.recv_timeout(Duration::from_millis(50)) {
                    Ok(c) => Some(c),
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => None,
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
                }
            };
            let mut pending: Vec<Command> = first.into_iter().collect();
            pending.extend(rx.try_iter());
            for c in pending {
                self.handle(c);
            }
            if self.playing {
                let now = Instant::now();
                if now >= self.next_step {
                    self.step();
                    let dt =
                        self.run.scene.solver().params().dt as f64 / self.speed.max(1e-3) as f64;
                    self.next_step += Duration::from_secs_f64(dt);
                    // Too far behind (a big cloth): do not try to catch up.
                    if Instant::now() > self.next_step + Duration::from_millis(250) {
                        self.next_step = Instant::now();
                    }
                } else {
                    std::thread::sleep((self.next_step - now).min(Duration::from_millis(5)));
                }
            }
        }
        self.finish();
        self.stop_recording();
    }

    fn handle(&mut self, c: Command) {
        match c {
            Command::Play => {
                self.playing = true;
                self.next_step = Instant::now();
            }
            Command::Pause => self.playing = false,
            Command::Step => {
                self.playing = false;
                self.step();
            }
            Command::Reset => {
                let loaded = self.current_loaded();
                self.begin(Start::Fresh(Box::new(loaded)), None);
            }
            Command::Speed(s) => self.speed = s.clamp(0.01, 100.0),
            Command::Tune(t) => {
                if let Err(e) = self.run.set_tuning(&t) {
                    self.set_error(Some(e.to_string()));
                }
            }
            Command::Telemetry(t) => {
                let (frame, time) = (self.run.scene.frame(), self.run.scene.time());
                let text = format!(
                    "telemetry settings: {}",
                    crate::scene::load::to_toml(&t).replace('\n', " ")
                );
                if let Err(e) = self.run.telemetry.log_event(frame, time, &text) {
                    self.set_error(Some(e.to_string()));
                }
                self.run.telemetry.set_settings(t);
            }
            Command::Load(loaded, name) => {
                self.name = name;
                self.loaded = *loaded.clone();
                self.begin(Start::Fresh(loaded), None);
            }
            Command::StartRecording(path) => {
                // A recording is a new run from frame 0 with the current
                // tuning (stored in its preset), so `weft replay`
                // reproduces it.
                match FileSink::new(&path) {
                    Ok(file) => {
                        let loaded = self.current_loaded();
                        self.loaded = loaded.clone();
                        if self.begin(Start::Fresh(Box::new(loaded)), Some(file)) {
                            self.status.lock().expect("not poisoned").recording = Some(path);
                        }
                    }
                    Err(e) => {
                        self.set_error(Some(format!("cannot record to {}: {e}", path.display())))
                    }
                }
            }
            Command::StopRecording => {
                self.finish();
                self.stop_recording();
            }
            Command::Branch(at) => self.branch(at),
            Command::Inspect(p) => {
                let n = self.run.scene.solver().state().len();
                self.inspect = p.filter(|&i| i < n);
            }
        }
        self.publish();
    }

    /// The loaded preset with the current tuning and telemetry settings.
    fn current_loaded(&self) -> Loaded {
        let tuning = self.run.scene.tuning();
        let mut loaded = self.loaded.clone();
        tuning.apply_to(&mut loaded.preset);
        loaded.preset.telemetry = *self.run.telemetry.settings();
        loaded.resolved = load::to_toml(&loaded.preset);
        loaded
    }

    fn branch(&mut self, at: BranchAt) {
        let last = self.history.last_frame();
        let frame = match at {
            BranchAt::Frame(f) => f,
            BranchAt::Time(t) => self.history.frame_at(t),
        };
        if frame > last {
            return self.set_error(Some(format!(
                "cannot branch at frame {frame}: run #{} has reached frame {last}",
                self.info.number
            )));
        }
        let tuning = self.run.scene.tuning();
        match self.history.state_at(frame) {
            Ok(snapshot) => {
                let history = self.history.branch(frame, tuning);
                let parent_series = self.series.clone();
                self.playing = false;
                if self.begin(
                    Start::Branch {
                        snapshot: Box::new(snapshot),
                        history: Box::new(history),
                        tuning,
                        parent_series,
                    },
                    None,
                ) {
                    // The two runs are the same up to the branch frame.
                    self.series.retain(|(f, _, _)| *f <= frame);
                }
            }
            Err(e) => self.set_error(Some(format!("cannot branch at frame {frame}: {e}"))),
        }
    }

    /// Ends the current run and starts a new one; false if it could not.
    fn begin(&mut self, start: Start, file: Option<FileSink>) -> bool {
        let number = self.runs.len() as u32 + 1;
        let parent = match &start {
            Start::Branch { snapshot, .. } => Some((
                self.info.number,
                self.info.recording_id.clone(),
                snapshot.scene.frame(),
            )),
            Start::Fresh(_) => None,
        };
        let info = RunInfo {
            number,
            parent,
            ..RunInfo::default()
        };
        let settings = *self.run.telemetry.settings();
        // The base a run's name is described against: the preset as named.
        let base = load::load(&self.name, &[]).ok().map(|l| l.preset);
        match open(&self.forward, start, &self.name, info, settings, base, file) {
            Ok(opened) => {
                // A new run starts with a clean status; what goes wrong in
                // closing the old one still shows.
                self.set_error(None);
                self.finish();
                self.stop_recording();
                if opened.info.parent.is_none() {
                    self.series.clear();
                }
                self.tee = opened.tee;
                let old = std::mem::replace(&mut self.rec, opened.rec);
                let flushed = old.flush_blocking();
                self.run = opened.run;
                self.history = opened.history;
                self.info = opened.info.clone();
                self.runs.push(opened.info);
                if let Err(e) = flushed {
                    self.set_error(Some(format!("the previous run: {e}")));
                }
                true
            }
            Err(e) => {
                self.set_error(Some(e));
                false
            }
        }
    }

    /// Logs the run's summary and its result properties, and flushes; a
    /// failure shows in the status.
    fn finish(&mut self) {
        if let Err(e) = self.end_run() {
            self.set_error(Some(format!("ending the run: {e}")));
        }
    }

    fn end_run(&mut self) -> Result<(), String> {
        let figures = self.run.log_summary().map_err(|e| e.to_string())?;
        let checks = self
            .run
            .scene
            .preset()
            .expect
            .map(|e| verdict(&e, &figures))
            .unwrap_or_default();
        self.rec
            .send_property(
                "result",
                &rerun::AnyValues::default()
                    .with_component::<rerun::components::Text>(
                        "frames",
                        [figures.frames.to_string()],
                    )
                    .with_component::<rerun::components::Text>(
                        "final_state",
                        [figures.final_state.clone()],
                    )
                    .with_component::<rerun::components::Text>("verdict", [verdict_text(&checks)]),
            )
            .map_err(|e| e.to_string())?;
        self.rec.flush_blocking().map_err(|e| e.to_string())
    }

    /// Closes the recording file, if there is one.
    fn stop_recording(&mut self) {
        if let Err(e) = self.tee.stop() {
            self.set_error(Some(e));
        }
        self.status.lock().expect("not poisoned").recording = None;
    }

    fn step(&mut self) {
        let start = Instant::now();
        let frame = self.run.scene.frame() + 1;
        self.history.tuning(frame, self.run.scene.tuning());
        match self.run.step() {
            Ok(()) => {
                let run = &self.run;
                self.history
                    .stepped(frame, run.scene.time(), || run.snapshot());
                if let Some(d) = run.scene.solver().diagnostics() {
                    let mut values = [0.0; 2 + Family::COUNT];
                    values[0] = d.max_strain;
                    values[1] = d.kinetic_energy;
                    for f in Family::ALL {
                        values[2 + f.index()] = d.family(f).violation.max;
                    }
                    self.series.push((frame, run.scene.time(), values));
                }
            }
            Err(e) => {
                self.playing = false;
                self.set_error(Some(e.to_string()));
            }
        }
        let now = Instant::now();
        self.recent.push_back(now);
        while self
            .recent
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.recent.pop_front();
        }
        let mut s = self.status.lock().expect("not poisoned");
        s.step_ms = start.elapsed().as_secs_f32() * 1e3;
        drop(s);
        self.publish_progress();
    }

    fn set_error(&self, e: Option<String>) {
        self.status.lock().expect("not poisoned").error = e;
    }

    /// Publishes everything, the preset included (after a command).
    fn publish(&self) {
        let mut preset = self.run.scene.preset().clone();
        preset.telemetry = *self.run.telemetry.settings();
        let progress = self.progress();
        // One lock, so a reader never sees a new run with an old frame.
        let mut s = self.status.lock().expect("not poisoned");
        s.preset_name = self.name.clone();
        s.preset = Some(preset);
        s.run = self.info.clone();
        s.runs = self.runs.clone();
        progress.write(&mut s);
    }

    /// Publishes what a step changes (the preset does not change on a step).
    fn publish_progress(&self) {
        let progress = self.progress();
        progress.write(&mut self.status.lock().expect("not poisoned"));
    }

    fn progress(&self) -> Progress {
        let scene = &self.run.scene;
        let figures = self.run.figures();
        let checks = scene
            .preset()
            .expect
            .map(|e| verdict(&e, &figures))
            .unwrap_or_default();
        Progress {
            frame: scene.frame(),
            time: scene.time(),
            playing: self.playing,
            speed: self.speed,
            steps_per_second: self.recent.len() as f32,
            violations: scene
                .solver()
                .diagnostics()
                .map(|d| (d.families.map(|_, f| f.violation.max), d.max_strain)),
            digest: figures.final_state,
            checks,
            checkpoints: self.history.checkpoints(),
            particle: self.inspect.map(|i| readout(scene, i)),
        }
    }
}

/// What a step changes in the [`Status`], gathered before taking its lock.
struct Progress {
    frame: u64,
    time: f64,
    playing: bool,
    speed: f32,
    steps_per_second: f32,
    violations: Option<(PerFamily<f32>, f32)>,
    digest: String,
    checks: Vec<Check>,
    checkpoints: (usize, u64),
    particle: Option<ParticleReadout>,
}

impl Progress {
    fn write(self, s: &mut Status) {
        s.frame = self.frame;
        s.time = self.time;
        s.playing = self.playing;
        s.speed = self.speed;
        s.steps_per_second = self.steps_per_second;
        if let Some((max_violation, max_strain)) = self.violations {
            s.max_violation = max_violation;
            s.max_strain = max_strain;
        }
        s.digest = self.digest;
        s.checks = self.checks;
        s.checkpoints = self.checkpoints;
        s.particle = self.particle;
    }
}

/// Opens a new recording and starts (or resumes) a run in it.
fn open(
    forward: &Forward,
    start: Start,
    preset_name: &str,
    mut info: RunInfo,
    settings: TelemetrySettings,
    base: Option<Preset>,
    file: Option<FileSink>,
) -> Result<Opened, String> {
    let mut parent_series = Series::new();
    let (scene, history, tuning, snapshot) = match start {
        Start::Fresh(loaded) => {
            let scene = Scene::new(&loaded.preset).map_err(|e| e.to_string())?;
            (Some((scene, loaded.resolved)), None, None, None)
        }
        Start::Branch {
            snapshot,
            history,
            tuning,
            parent_series: series,
        } => {
            parent_series = series;
            (None, Some(*history), Some(tuning), Some(*snapshot))
        }
    };
    // What the run is, for its name: the preset with the tuning it runs.
    let mut current = match (&scene, &snapshot) {
        (Some((s, _)), _) => s.preset().clone(),
        (_, Some(s)) => s.scene.preset().clone(),
        _ => unreachable!("a run starts from a scene or a snapshot"),
    };
    if let Some(t) = tuning {
        t.apply_to(&mut current);
    }
    let changes = base
        .as_ref()
        .map(|b| preset_diff::describe(b, &current))
        .unwrap_or_default();
    let stem = preset_name
        .trim_end_matches(".toml")
        .rsplit('/')
        .next()
        .unwrap_or(preset_name);
    let mut name = format!("#{} {stem}", info.number);
    if !changes.is_empty() {
        name += &format!(" · {changes}");
    }
    if let Some((parent, _, frame)) = &info.parent {
        name += &format!(" · branch of #{parent} at frame {frame}");
    }
    let (rec, tee) = stream(forward.clone(), &name, file);
    let mut telemetry = Telemetry::new(rec.clone(), settings);
    telemetry.forget();
    // For hovering a particle in the viewer (at level full).
    telemetry.set_particle_values(true);
    let mut run = match (scene, snapshot) {
        (Some((scene, resolved)), _) => Run::start(scene, telemetry, preset_name, &resolved),
        (_, Some(snapshot)) => {
            let resolved = load::to_toml(snapshot.scene.preset());
            Run::resume(snapshot, telemetry, preset_name, &resolved)
        }
        _ => unreachable!("a run starts from a scene or a snapshot"),
    }
    .map_err(|e| e.to_string())?;
    // The panel's readouts need diagnostics whatever the telemetry level,
    // and the panel can switch to level full or colouring by correction at
    // any step, so every particle's corrections are recorded too.
    let solver = run.scene.solver_mut();
    solver.set_diagnostics(true);
    solver.record_corrections(true);
    if let Some(t) = tuning {
        run.set_tuning(&t).map_err(|e| e.to_string())?;
    }
    let history = match history {
        Some(h) => h,
        None => History::new(run.snapshot(), run.scene.tuning()),
    };
    info.recording_id = rec
        .store_info()
        .map(|i| i.store_id.recording_id().to_string())
        .unwrap_or_default();
    info.name = name.clone();
    let mut props = rerun::AnyValues::default()
        .with_component::<rerun::components::Text>(
            "version",
            [env!("CARGO_PKG_VERSION").to_string()],
        )
        .with_component::<rerun::components::Text>("preset", [preset_name.to_string()])
        .with_component::<rerun::components::Text>("run", [info.number.to_string()])
        .with_component::<rerun::components::Text>("changes", [changes]);
    if let Some((number, id, frame)) = &info.parent {
        props = props
            .with_component::<rerun::components::Text>("parent", [id.clone()])
            .with_component::<rerun::components::Text>("parent_run", [number.to_string()])
            .with_component::<rerun::components::Text>("parent_frame", [frame.to_string()]);
    }
    rec.send_property("weft", &props)
        .map_err(|e| e.to_string())?;
    if let Some((number, _, _)) = &info.parent {
        log_parent_series(&rec, *number, &parent_series).map_err(|e| e.to_string())?;
    }
    Ok(Opened {
        run,
        history,
        info,
        rec,
        tee,
    })
}

/// Logs a parent run's plotted values into a branch's recording, beside the
/// branch's own in the same plots: `metrics/strain/parent`,
/// `metrics/energy/parent`, `metrics/violation/{family}/parent`, thin and
/// grey, named after the parent run.
fn log_parent_series(
    rec: &rerun::RecordingStream,
    parent: u32,
    series: &Series,
) -> rerun::RecordingStreamResult<()> {
    use crate::telemetry::paths;
    let frames: Vec<i64> = series.iter().map(|(f, _, _)| *f as i64).collect();
    let times: Vec<f64> = series.iter().map(|(_, t, _)| *t).collect();
    let mut plots = vec![
        (
            paths::STRAIN.replace("/max", "/parent"),
            0,
            "max".to_string(),
        ),
        (
            paths::ENERGY.replace("/kinetic", "/parent"),
            1,
            "kinetic".to_string(),
        ),
    ];
    for f in Family::ALL {
        plots.push((
            paths::violation(f, "parent"),
            2 + f.index(),
            format!("{} max", f.name()),
        ));
    }
    for (path, k, label) in plots {
        rec.log_static(
            path.as_str(),
            &rerun::SeriesLines::new()
                .with_colors([rerun::Color::from_rgb(150, 150, 150)])
                .with_widths([0.75])
                .with_names([format!("{label}, run #{parent}")]),
        )?;
        let values: Vec<f64> = series.iter().map(|(_, _, v)| v[k] as f64).collect();
        rec.send_columns(
            path.as_str(),
            [
                rerun::TimeColumn::new_sequence(paths::FRAME, frames.clone()),
                rerun::TimeColumn::new_duration_secs(paths::SIM_TIME, times.clone()),
            ],
            rerun::Scalars::new(values).columns_of_unit_batches()?,
        )?;
    }
    Ok(())
}

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

/// What the inspector shows of particle `i`.
fn readout(scene: &Scene, i: usize) -> ParticleReadout {
    let solver = scene.solver();
    let weft = solver.spec().weft;
    let mut r = ParticleReadout {
        index: i,
        cell: (i as u32 % weft, i as u32 / weft),
        strain: solver.particle_strain()[i],
        ..ParticleReadout::default()
    };
    for f in Family::ALL {
        r.violation[f] = solver.particle_violation(f)[i];
        if let Some(d) = solver.diagnostics().filter(|d| d.corrections) {
            r.dx[f] = d.family(f).dx[i];
            r.dtheta[f] = d.family(f).dtheta[i];
        }
    }
    r
}
