//! A live session: the simulation on its own thread, driven by commands from
//! the panel, reporting a [`Status`] back.
//!
//! The thread owns a [`Run`] (scene + telemetry). Its telemetry goes through
//! a [`Tee`]: always to the viewer (or wherever the caller forwards it), and
//! to an `.rrd` file while the session is being recorded, so the file gets
//! the same stream the viewer gets. A change of parameters applies at the
//! next step and is logged at the frame it takes effect.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use rerun::log::LogMsg;
use rerun::sink::FileSink;

use crate::record::Run;
use crate::scene::{Loaded, Scene, Tuning, preset::TelemetrySettings};
use crate::solver::PerFamily;
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
    /// Start the scene over from its preset, keeping the tuning.
    Reset,
    /// Simulated seconds per wall-clock second.
    Speed(f32),
    /// New solver parameters and wind, from the next step.
    Tune(Tuning),
    /// New telemetry settings.
    Telemetry(TelemetrySettings),
    /// Load another preset (validated by the caller) and start over.
    Load(Box<Loaded>, String),
    /// Start recording to an `.rrd` file.
    StartRecording(PathBuf),
    /// Stop recording and close the file.
    StopRecording,
}

/// What the session reports to the panel.
#[derive(Clone, Debug, Default)]
pub struct Status {
    /// The preset's name or path.
    pub preset_name: String,
    /// The loaded preset, with the current tuning applied.
    pub preset: Option<crate::scene::Preset>,
    /// Frames stepped since the last reset.
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
    /// The recording file, while recording.
    pub recording: Option<PathBuf>,
    /// The last error (a solver failure or a file problem).
    pub error: Option<String>,
}

/// Forwards every message to `forward`, and to a file while recording.
pub struct Tee {
    forward: Box<dyn Fn(&LogMsg) + Send + Sync>,
    file: Mutex<Option<FileSink>>,
    store_info: Mutex<Option<LogMsg>>,
}

impl Tee {
    fn send(&self, msg: &LogMsg) {
        if matches!(msg, LogMsg::SetStoreInfo(_)) {
            let mut info = self.store_info.lock().expect("not poisoned");
            if info.is_none() {
                *info = Some(msg.clone());
            }
        }
        (self.forward)(msg);
        if let Some(file) = self.file.lock().expect("not poisoned").as_ref() {
            file.send(msg.clone());
        }
    }

    fn start(&self, path: &std::path::Path) -> Result<(), String> {
        let file =
            FileSink::new(path).map_err(|e| format!("cannot record to {}: {e}", path.display()))?;
        if let Some(info) = self.store_info.lock().expect("not poisoned").clone() {
            file.send(info);
        }
        *self.file.lock().expect("not poisoned") = Some(file);
        Ok(())
    }

    fn stop(&self) {
        // Dropping the sink writes the footer and closes the file.
        let file = self.file.lock().expect("not poisoned").take();
        if let Some(f) = file {
            let _ = f.flush_blocking(Duration::from_secs(10));
        }
    }
}

/// A recording stream whose messages go to `forward` (and a file on demand).
pub fn stream(
    forward: impl Fn(&LogMsg) + Send + Sync + 'static,
) -> (rerun::RecordingStream, Arc<Tee>) {
    let tee = Arc::new(Tee {
        forward: Box::new(forward),
        file: Mutex::new(None),
        store_info: Mutex::new(None),
    });
    let sink_tee = tee.clone();
    let rec = rerun::RecordingStreamBuilder::new("weft")
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
        let (rec, tee) = stream(forward);
        let run = new_run(&loaded, &name, rec.clone())?;
        let status = Arc::new(Mutex::new(Status {
            preset_name: name.clone(),
            preset: Some(loaded.preset.clone()),
            speed: 1.0,
            ..Status::default()
        }));
        let (tx, rx) = channel();
        let shared = status.clone();
        let thread = std::thread::Builder::new()
            .name("weft-sim".into())
            .spawn(move || {
                let worker = Worker {
                    run,
                    loaded,
                    name,
                    rec,
                    tee,
                    status: shared,
                    playing: false,
                    speed: 1.0,
                    next_step: Instant::now(),
                    recent: Default::default(),
                };
                worker.serve(rx)
            })
            .map_err(|e| e.to_string())?;
        Ok(Self {
            tx,
            status,
            thread: Some(thread),
        })
    }

    /// Sends a command; it is handled before the next step.
    pub fn send(&self, c: Command) {
        let _ = self.tx.send(c);
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
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn new_run(loaded: &Loaded, name: &str, rec: rerun::RecordingStream) -> Result<Run, String> {
    let scene = Scene::new(&loaded.preset).map_err(|e| e.to_string())?;
    let mut telemetry = Telemetry::new(rec, loaded.preset.telemetry);
    telemetry.forget();
    let mut run =
        Run::start(scene, telemetry, name, &loaded.resolved).map_err(|e| e.to_string())?;
    // The panel's readouts need diagnostics whatever the telemetry level,
    // and the panel can switch to level full or colouring by correction at
    // any step, so every particle's corrections are recorded too.
    let solver = run.scene.solver_mut();
    solver.set_diagnostics(true);
    solver.record_corrections(true);
    Ok(run)
}

struct Worker {
    run: Run,
    loaded: Loaded,
    name: String,
    rec: rerun::RecordingStream,
    tee: Arc<Tee>,
    status: Arc<Mutex<Status>>,
    playing: bool,
    speed: f32,
    next_step: Instant,
    recent: std::collections::VecDeque<Instant>,
}

impl Worker {
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
        self.stop_recording();
        let _ = self.rec.flush_blocking();
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
                self.stop_recording();
                let tuning = self.run.scene.tuning();
                let telemetry = *self.run.telemetry.settings();
                let mut loaded = self.loaded.clone();
                loaded.preset.telemetry = telemetry;
                self.restart(loaded, tuning);
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
                let _ = self.run.telemetry.log_event(frame, time, &text);
                self.run.telemetry.set_settings(t);
            }
            Command::Load(loaded, name) => {
                self.stop_recording();
                self.name = name;
                let tuning = Tuning::of(&loaded.preset);
                self.loaded = *loaded.clone();
                self.restart(*loaded, tuning);
            }
            Command::StartRecording(path) => {
                self.stop_recording();
                // A recording starts the scene over with the current tuning
                // (stored in its preset), so `weft replay` reproduces it.
                let tuning = self.run.scene.tuning();
                let mut loaded = self.loaded.clone();
                tuning.apply_to(&mut loaded.preset);
                loaded.preset.telemetry = *self.run.telemetry.settings();
                loaded.resolved = crate::scene::load::to_toml(&loaded.preset);
                // What is already logged goes to the viewer only.
                let _ = self.rec.flush_blocking();
                match self.tee.start(&path) {
                    Ok(()) => {
                        self.loaded = loaded.clone();
                        self.restart(loaded, tuning);
                        self.status.lock().expect("not poisoned").recording = Some(path);
                    }
                    Err(e) => self.set_error(Some(e)),
                }
            }
            Command::StopRecording => self.stop_recording(),
        }
        self.publish();
    }

    /// Ends a recording, if one is running: the summary, then the file closes.
    fn stop_recording(&mut self) {
        if self
            .status
            .lock()
            .expect("not poisoned")
            .recording
            .is_none()
        {
            return;
        }
        let _ = self.run.log_summary();
        let _ = self.rec.flush_blocking();
        self.tee.stop();
        // Only now is the file complete.
        self.status.lock().expect("not poisoned").recording = None;
    }

    fn restart(&mut self, mut loaded: Loaded, tuning: Tuning) {
        tuning.apply_to(&mut loaded.preset);
        match new_run(&loaded, &self.name, self.rec.clone()) {
            Ok(run) => {
                self.run = run;
                self.set_error(None);
            }
            Err(e) => self.set_error(Some(e)),
        }
    }

    fn step(&mut self) {
        let start = Instant::now();
        if let Err(e) = self.run.step() {
            self.playing = false;
            self.set_error(Some(e.to_string()));
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
        {
            let mut s = self.status.lock().expect("not poisoned");
            s.preset_name = self.name.clone();
            s.preset = Some(preset);
        }
        self.publish_progress();
    }

    /// Publishes what a step changes (the preset does not change on a step).
    fn publish_progress(&self) {
        let scene = &self.run.scene;
        let mut s = self.status.lock().expect("not poisoned");
        s.frame = scene.frame();
        s.time = scene.time();
        s.playing = self.playing;
        s.speed = self.speed;
        s.steps_per_second = self.recent.len() as f32;
        if let Some(d) = scene.solver().diagnostics() {
            s.max_violation = d.families.map(|_, f| f.violation.max);
            s.max_strain = d.max_strain;
        }
    }
}
