//! The simulation thread's state and loop: commands in, steps at real-time
//! pace (here), runs started and ended (`lifecycle`), status out
//! (`publish`), a branch's parent drawn as a ghost (`ghost`).

mod ghost;
mod lifecycle;
mod publish;
mod send;

use std::path::PathBuf;
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rerun::sink::FileSink;

use super::SessionError;
use crate::app::history::History;
use crate::app::pull;
use crate::record::Run;
use crate::scene::{Loaded, load};
use crate::solver::Family;
use crate::telemetry::Collect;

use super::runs::{Forward, SERIES_VALUES, Start, Tee, open};
use super::trace::Trace;
use super::{BranchAt, Command, FOLLOWING, MAX_LEAD, RunInfo, Series, Shown, Status, Waker};
use ghost::Ghost;

/// What the simulation thread owns: the current run and its history, every
/// run of the session, the stream of the current one, and the pacing.
pub(super) struct Worker {
    run: Run,
    history: History,
    series: Series,
    /// The run's cloth, frame by frame (a branch's ghost of its parent).
    trace: Trace,
    /// A branch's parent, drawn faint beside its cloth.
    ghost: Option<Ghost>,
    /// Whether the ghost is drawn.
    show_ghost: bool,
    info: RunInfo,
    runs: Vec<RunInfo>,
    loaded: Loaded,
    name: String,
    rec: rerun::RecordingStream,
    tee: Arc<Tee>,
    forward: Forward,
    inspect: Option<usize>,
    /// The origin at the run's last frames, for points seen in the viewer.
    trail: pull::Trail,
    /// The last particle picked near a point, and how many were.
    picked: Option<(u64, usize)>,
    /// The file the current run is recorded to, if any.
    recording: Option<PathBuf>,
    status: Arc<Mutex<Status>>,
    waker: Arc<Mutex<Option<Waker>>>,
    shown: Arc<Mutex<Shown>>,
    playing: bool,
    /// While playing, the frame to pause at.
    stop_at: Option<u64>,
    speed: f32,
    next_step: Instant,
    recent: std::collections::VecDeque<Instant>,
    /// The window's draw count when a frame's drawing was last sent.
    drawn_seen: u64,
    /// Whether the current frame was logged without its drawing.
    drawing_behind: bool,
}

impl Worker {
    pub(super) fn new(
        loaded: Loaded,
        name: String,
        forward: Forward,
        status: Arc<Mutex<Status>>,
        waker: Arc<Mutex<Option<Waker>>>,
        shown: Arc<Mutex<Shown>>,
    ) -> Result<Self, SessionError> {
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
        let mut worker = Self {
            run: opened.run,
            history: opened.history,
            series: Series::new(),
            trace: Trace::default(),
            ghost: None,
            show_ghost: true,
            runs: vec![opened.info.clone()],
            info: opened.info,
            loaded,
            name,
            rec: opened.rec,
            tee: opened.tee,
            forward,
            inspect: None,
            trail: pull::Trail::default(),
            picked: None,
            recording: None,
            status,
            waker,
            shown,
            playing: false,
            stop_at: None,
            speed: 1.0,
            next_step: Instant::now(),
            recent: Default::default(),
            drawn_seen: 0,
            drawing_behind: false,
        };
        worker.diagnose();
        worker.keep_frame();
        worker.publish();
        Ok(worker)
    }

    pub(super) fn serve(mut self, rx: Receiver<Command>) {
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
            if self.playing && self.stop_at.is_some_and(|f| self.run.scene.frame() >= f) {
                self.playing = false;
                self.stop_at = None;
                self.publish_progress();
            }
            let behind = self.playing && self.viewer_behind();
            if self.drawing_behind && (!self.playing || behind) {
                // Stopped, or waiting for the viewer, on a frame sent
                // without its drawing: send it (the viewer's cursor goes
                // only to frames drawn whole, so waiting for it to reach a
                // frame never drawn would wait for ever).
                self.drawing_behind = false;
                self.run.telemetry.set_visuals(true);
                if let Err(e) = self.run.telemetry.redraw(&self.run.scene) {
                    self.set_error(Some(format!("logging to the viewer failed: {e}")));
                }
                self.draw_ghost(false);
                self.send_drawing();
            }
            if behind {
                // Wait for the viewer; then go on at the usual pace, without
                // catching up.
                std::thread::sleep(Duration::from_millis(2));
                self.next_step = Instant::now();
            } else if self.playing {
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
        self.publish();
    }

    fn handle(&mut self, c: Command) {
        match c {
            Command::Play => {
                self.take_cursor();
                self.playing = true;
                self.stop_at = None;
                self.next_step = Instant::now();
                self.await_viewer();
            }
            Command::PlayTo(frame) => {
                self.take_cursor();
                self.playing = self.run.scene.frame() < frame;
                self.stop_at = Some(frame);
                self.next_step = Instant::now();
                self.await_viewer();
            }
            Command::Pause => self.playing = false,
            Command::Step => {
                self.take_cursor();
                self.playing = false;
                self.step();
            }
            Command::Reset => {
                let loaded = self.current_loaded();
                self.begin(Start::Fresh(Box::new(loaded)), None);
            }
            Command::Speed(s) => self.speed = s.clamp(0.01, 100.0),
            Command::Tune(mut t) => {
                // The panel's tuning has no pull: a grab goes on.
                t.pull = self.run.scene.tuning().pull;
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
            Command::Arrows(on) => self.run.telemetry.set_arrows(on),
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
                            self.recording = Some(path);
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
            Command::InspectNear(at) => {
                if let Some(i) = pull::nearest(&self.run.scene, glam::Vec3::from_array(at)) {
                    let picks = self.picked.map_or(0, |(n, _)| n) + 1;
                    self.picked = Some((picks, i));
                    self.inspect = Some(i);
                    self.diagnose();
                }
            }
            Command::Inspect(p) => {
                let n = self.run.scene.solver().state().len();
                self.inspect = p.filter(|&i| i < n);
                self.diagnose();
            }
            Command::Ghost(on) => {
                self.show_ghost = on;
                self.draw_ghost(true);
                self.send_drawing();
            }
            Command::Grab(at) => {
                let at = glam::Vec3::from_array(at).as_dvec3() + self.seen_to_now();
                let grab = pull::grab(&self.run.scene, at.as_vec3());
                self.set_pull(grab);
            }
            Command::GrabAlong(origin, dir) => {
                let origin = glam::Vec3::from_array(origin).as_dvec3() + self.seen_to_now();
                let dir = glam::Vec3::from_array(dir);
                let grab = pull::grab_along(&self.run.scene, origin.as_vec3(), dir);
                if grab.is_some() {
                    self.set_pull(grab);
                }
            }
            Command::PullTo(target) => {
                if let Some(mut p) = self.run.scene.tuning().pull {
                    p.target = glam::DVec3::from_array(target) + self.seen_to_now();
                    self.set_pull(Some(p));
                }
            }
            Command::Release => self.set_pull(None),
        }
        self.publish();
    }

    /// What to add to a point seen in the viewer to have it at the
    /// simulation's frame: how far the origin moved since the frame the
    /// viewer shows of the current run (nothing without a viewer).
    fn seen_to_now(&self) -> glam::DVec3 {
        let shown = self.shown.lock().expect("not poisoned");
        match &shown.at {
            Some((id, at, _)) if *id == self.info.recording_id => self
                .trail
                .since(*at, self.run.scene.solver().frame().origin),
            _ => glam::DVec3::ZERO,
        }
    }

    /// Pulls a particle (or lets go) from the next step: a change of the
    /// tuning, logged at the frame it takes effect.
    fn set_pull(&mut self, pull: Option<crate::solver::Pull>) {
        let tuning = crate::scene::Tuning {
            pull,
            ..self.run.scene.tuning()
        };
        if let Err(e) = self.run.set_tuning(&tuning) {
            self.set_error(Some(e.to_string()));
        }
    }

    /// Whether the viewer, following the current run, shows a frame more
    /// than [`MAX_LEAD`] seconds behind the simulation's. While the session
    /// moves the viewer's cursor, a cursor that has not moved for a while is
    /// a viewer slow to take in and draw what it was sent, which the
    /// simulation waits for however long it takes; left to the viewer, it
    /// may be one the user stopped.
    ///
    /// A viewer that reports nothing at all for [`FOLLOWING`] while the
    /// session moves its cursor (one that does not take the commands)
    /// lets one frame through each time, so the simulation crawls rather
    /// than stops.
    fn viewer_behind(&self) -> bool {
        let mut shown = self.shown.lock().expect("not poisoned");
        let following = shown.follow.is_on();
        let pace = shown.pace;
        let Some((id, at, when)) = shown.at.as_mut().filter(|_| pace) else {
            return false;
        };
        if *id != self.info.recording_id {
            return false;
        }
        if when.elapsed() > FOLLOWING {
            if following {
                *when = Instant::now();
            }
            return false;
        }
        let frame = match *at {
            BranchAt::Frame(f) => f,
            BranchAt::Time(t) => self.history.frame_at(t),
        };
        let dt = self.run.scene.solver().params().dt as f64;
        self.run.scene.frame().saturating_sub(frame) as f64 * dt > MAX_LEAD
    }

    /// On Play, if the viewer has not reported the current run lately: takes
    /// it to show the current frame, so that the simulation waits (up to
    /// [`FOLLOWING`]) for its first report instead of running ahead.
    fn await_viewer(&self) {
        let mut shown = self.shown.lock().expect("not poisoned");
        let current = shown.at.as_ref().is_some_and(|(id, _, when)| {
            *id == self.info.recording_id && when.elapsed() < FOLLOWING
        });
        if shown.pace && !current {
            shown.at = Some((
                self.info.recording_id.clone(),
                BranchAt::Frame(self.run.scene.frame()),
                Instant::now(),
            ));
        }
    }

    /// Has the run collect what the panel reads after every step, whatever
    /// the telemetry logs: the figures and timings, and while a particle is
    /// inspected its corrections (they cost about an eighth of a step; the
    /// telemetry asks for them itself at level full or colouring by
    /// correction).
    fn diagnose(&mut self) {
        self.run.diagnose_every_step(Collect {
            figures: true,
            corrections: self.inspect.is_some(),
        });
    }

    /// Whether the next frame is sent with its drawing: always, but while
    /// playing paced to a window, only once the window has drawn since the
    /// last drawing was sent (the frames in between send their scalars).
    fn draws_next(&mut self) -> bool {
        let shown = self.shown.lock().expect("not poisoned");
        if !shown.pace || !self.playing {
            return true;
        }
        let drew = shown.drawn != self.drawn_seen;
        self.drawn_seen = shown.drawn;
        drew
    }

    fn step(&mut self) {
        let start = Instant::now();
        let draws = self.draws_next();
        self.run.telemetry.set_visuals(draws);
        self.drawing_behind = !draws;
        let frame = self.run.scene.frame() + 1;
        self.history.tuning(frame, self.run.scene.tuning());
        match self.run.step() {
            Ok(()) => {
                let run = &self.run;
                self.history
                    .stepped(frame, run.scene.time(), || run.snapshot());
                let origin = run.scene.solver().frame().origin;
                self.trail.note(frame, run.scene.time(), origin);
                if let Some(d) = run.scene.solver().diagnostics() {
                    let mut values = [0.0; SERIES_VALUES];
                    values[0] = d.max_strain;
                    values[1] = d.kinetic_energy;
                    for f in Family::ALL {
                        values[2 + f.index()] = d.family(f).violation.max;
                    }
                    values[2 + Family::COUNT] = d.orientation.flipped;
                    self.series.push((frame, run.scene.time(), values));
                }
                self.keep_frame();
                self.draw_ghost(false);
                if draws {
                    // The frame's drawing, the ghost with it, sent whole.
                    self.send_drawing();
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
}
