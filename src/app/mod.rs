//! The desktop debugger: one eframe window with the Rerun viewer embedded,
//! fed directly by the running simulation, beside the egui tuning panel.
//!
//! - [`session`]: the simulation thread, its commands and status, and the
//!   streams that feed the viewer (and a file, while recording), one Rerun
//!   recording per run;
//! - [`history`]: checkpoints, for branching a run from any frame;
//! - [`panel`]: the tuning panel;
//! - [`preset_diff`]: what a tuning changed against its preset (run names,
//!   saving as `extend` plus changed keys);
//! - [`ruler`]: a drag on the viewer's time ruler scrubs instead of making
//!   a loop selection;
//! - `driver`: a warning at start for a graphics driver known to leak
//!   memory while the window plays;
//! - `view`: `weft view`, recordings opened in the same viewer.
//!
//! The viewer is fed in-process: every message of the session's recording
//! streams goes into a `re_log_channel` that the embedded viewer reads, so
//! no server or network is involved. The viewer reports back through its
//! event callback (time cursor, selection), which the panel reads from a
//! [`panel::ViewerLink`].

mod driver;
pub mod history;
pub mod panel;
pub mod preset_diff;
pub mod pull;
pub mod ruler;
pub mod session;
mod view;
pub mod whole;

pub use view::view;

use std::path::PathBuf;
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::Context;
use re_viewer::external::re_log_channel;
use re_viewer::external::re_view_spatial::SpatialView3D;
use re_viewer::external::re_viewer_context::ViewClass as _;
use re_viewer::{SelectionChangeItem, ViewerEvent, ViewerEventKind};

use crate::scene::{Override, load};
use crate::telemetry::paths;
use panel::Panel;
use session::{BranchAt, Command, Session};

/// `weft gui --screenshot`: play some frames, save the window, quit.
#[derive(Clone, Debug)]
pub struct Screenshot {
    /// The PNG file.
    pub path: PathBuf,
    /// Frames to play first.
    pub frames: u64,
    /// A recording to start at once, before playing.
    pub record: Option<PathBuf>,
    /// Pictures to take while playing as well, evenly spread over the
    /// frames (`FILE-1.png`, `FILE-2.png`, …).
    pub burst: u32,
}

/// Marks a screenshot weft asks egui for (the viewer has its own): the
/// last picture (`None`) or one of a burst taken while playing.
#[derive(Clone, Copy, Debug)]
struct WeftScreenshot(Option<u32>);

/// Where `--screenshot` is: playing, waiting for the viewer to show the
/// last frame, then waiting for egui's picture.
enum Shot {
    Start,
    Playing,
    Settling(u32),
    Requested,
}

/// The window: the viewer and the panel.
pub struct WeftApp {
    viewer: re_viewer::App,
    panel: Panel,
    session: Session,
    screenshot: Option<(Screenshot, Shot, Instant)>,
    /// With `--screenshot`: how far (simulated seconds) the viewer's time
    /// cursor was at most behind the simulation while playing.
    lag: f64,
    /// With `--screenshot`: how many times the window drew while playing,
    /// and how many of those the 3D view mixed two frames ([`whole`]).
    drawn: (u64, u64),
    /// With `--screenshot`: the most Rerun's "Latency" (the top bar's:
    /// seconds from logging to the viewer, averaged over a second) read
    /// while playing.
    latency: f32,
    /// With `--screenshot --burst`: the burst pictures asked for so far.
    burst_taken: u32,
    /// A drag begun on the viewer's time ruler, moved to scrub.
    scrub: ruler::Scrub,
    /// Ctrl-drag on the cloth ([`pull`]).
    gesture: pull::Gesture,
}

impl eframe::App for WeftApp {
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        self.viewer.save(storage);
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        egui::Panel::right("weft_panel")
            .default_size(340.0)
            .show(ui, |ui| self.panel.ui(ui, &self.session));
        self.viewer.ui(ui, frame);
        self.session.window_drew();
        self.gesture.update(ui.ctx(), &self.session);
        // No repaint is asked for here: the session asks for one when its
        // status changes, and the viewer when a message arrives, so a
        // paused window with nobody at it does not redraw.
        self.take_screenshot(ui.ctx());
    }

    fn logic(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        self.viewer.logic(ctx, frame);
    }

    /// With `--screenshot`, the window shows what it shows nobody pointing
    /// at it: wherever the display leaves the pointer (Xvfb, the middle of
    /// the screen), no tooltip opens over a plot.
    ///
    /// The simulation's keys that the viewer would take for its timeline
    /// (Space, →, Backspace) are handed to the panel as its function keys
    /// before the viewer sees them, unless a text field is being typed in.
    ///
    /// A press on the viewer's time ruler, and its drag, move the time
    /// cursor instead of making a loop selection ([`ruler`]).
    fn raw_input_hook(&mut self, ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        let ruler = ctx.viewport(|v| ruler::find(&v.prev_pass.widgets));
        self.scrub.remap(&mut raw_input.events, ruler);
        if !ctx.text_edit_focused() {
            panel::take_simulation_keys(&mut raw_input.events);
        }
        self.gesture.take_events(&mut raw_input.events);
        if self.screenshot.is_some() {
            raw_input
                .events
                .retain(|e| !matches!(e, egui::Event::PointerMoved(_)));
            raw_input.events.push(egui::Event::PointerGone);
        }
    }
}

impl WeftApp {
    /// Drives `--screenshot` with egui's screenshot viewport command: the
    /// picture is what the window rendered, whatever the display does.
    /// While playing, it also counts the times the 3D view mixed two
    /// frames, and takes the `--burst` pictures.
    fn take_screenshot(&mut self, ctx: &egui::Context) {
        let Some((shot, state, started)) = &mut self.screenshot else {
            return;
        };
        if started.elapsed() > Duration::from_secs(300) {
            re_log::error!("--screenshot: gave up after 300 s");
            std::process::exit(2);
        }
        for (k, image) in shots_taken(ctx) {
            if let Some(k) = k {
                let path = burst_path(&shot.path, k);
                save_png(&image, &path);
            }
        }
        match state {
            Shot::Start => {
                if let Some(file) = &shot.record {
                    self.session.send(Command::StartRecording(file.clone()));
                }
                self.session.send(Command::PlayTo(shot.frames));
                *state = Shot::Playing;
            }
            Shot::Playing => {
                let status = self.session.status();
                let link = self.panel.link();
                let cursor = link.lock().expect("not poisoned").cursor.clone();
                if let Some((id, at)) = cursor
                    && id == status.run.recording_id
                    && status.playing
                {
                    let dt = status.preset.as_ref().map_or(0.0, |p| p.solver.dt) as f64;
                    let shown = match at {
                        BranchAt::Frame(f) => f as f64 * dt,
                        BranchAt::Time(t) => t,
                    };
                    self.lag = self.lag.max(status.time - shown);
                }
                let latency = self
                    .viewer
                    .recording_db()
                    .and_then(|db| db.ingestion_stats().latency_snapshot().e2e());
                if status.playing && self.drawn.0 > 0 {
                    self.latency = self.latency.max(latency.unwrap_or(0.0));
                    re_log::debug!(
                        "frame {} at {:.2} s, Rerun's latency {latency:?}, view behind by at most {:.2} s",
                        status.frame,
                        started.elapsed().as_secs_f64(),
                        self.lag
                    );
                }
                if status.playing
                    && let Some(times) = whole::last_logged(&self.viewer)
                {
                    self.drawn.0 += 1;
                    if whole::mixed(&times) {
                        self.drawn.1 += 1;
                        re_log::debug!("the 3D view mixed frames: {times:?}");
                    }
                }
                let next =
                    shot.frames * u64::from(self.burst_taken + 1) / u64::from(shot.burst + 1);
                if self.burst_taken < shot.burst && status.playing && status.frame >= next {
                    self.burst_taken += 1;
                    ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(egui::UserData::new(
                        WeftScreenshot(Some(self.burst_taken)),
                    )));
                }
                if status.frame >= shot.frames && !status.playing {
                    *state = Shot::Settling(30);
                }
            }
            Shot::Settling(0) => {
                ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(egui::UserData::new(
                    WeftScreenshot(None),
                )));
                *state = Shot::Requested;
            }
            Shot::Settling(n) => *n -= 1,
            Shot::Requested => {
                if let Some((_, image)) = shots_taken(ctx).into_iter().find(|(k, _)| k.is_none()) {
                    let [w, h] = save_png(&image, &shot.path);
                    eprintln!(
                        "saved the window ({w}×{h}) at frame {} to {}; while playing, the view was at most {:.2} s behind the simulation (Rerun's latency at most {:.2} s), and of the {} times the window drew, the 3D view mixed two frames {} times",
                        self.session.status().frame,
                        shot.path.display(),
                        self.lag,
                        self.latency,
                        self.drawn.0,
                        self.drawn.1,
                    );
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
        }
        ctx.request_repaint();
    }
}

/// The smallest memory limit the live viewer takes: below it, frames would
/// be dropped as soon as they arrive.
const LEAST_MEMORY_LIMIT: u64 = 100_000_000;

/// `--memory-limit`'s text as the viewer's limit, or an error that says
/// what is allowed.
fn viewer_memory_limit(text: &str) -> anyhow::Result<re_memory::MemoryLimit> {
    let allowed = "allowed: 100MB or more (`500MB`, `2GB`), a share of the machine's RAM \
                   (`25%`), or `unlimited`";
    let limit = re_memory::MemoryLimit::parse(text)
        .map_err(|e| anyhow::anyhow!("--memory-limit {text}: {e}; {allowed}"))?;
    if limit.as_bytes() < LEAST_MEMORY_LIMIT {
        anyhow::bail!(
            "--memory-limit {text}: under 100MB the viewer would drop every frame as it \
             arrives; {allowed}"
        );
    }
    Ok(limit)
}

/// Where `--burst`'s picture `k` goes: beside `path`, numbered.
fn burst_path(path: &std::path::Path, k: u32) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!("{stem}-{k}.png"))
}

/// The embedded viewer, set up in the window being created (with a warning
/// for a graphics driver known to leak).
fn viewer_app(
    token: re_viewer::MainThreadToken,
    startup: re_viewer::StartupOptions,
    cc: &eframe::CreationContext<'_>,
) -> Result<re_viewer::App, Box<dyn std::error::Error + Send + Sync>> {
    re_viewer::customize_eframe_and_setup_renderer(cc)?;
    let render = cc.wgpu_render_state.as_ref();
    if let Some(w) = render.and_then(|r| driver::warning(&r.adapter.get_info())) {
        eprintln!("warning: {w}");
    }
    Ok(re_viewer::App::new(
        token,
        re_viewer::build_info(),
        re_viewer::AppEnvironment::Custom("weft".into()),
        startup,
        cc,
        None,
        re_viewer::AsyncRuntimeHandle::from_current_tokio_runtime_or_wasmbindgen()?,
    ))
}

/// The window's options: weft's id and size. For a screenshot, the window
/// opens as it would the first time, whatever the last window on this
/// machine left: it reads and writes its state (the window's size, egui's
/// memory) in a scratch file of its own, not the user's, returned to be
/// removed.
fn window_options(screenshot: bool) -> (eframe::NativeOptions, Option<PathBuf>) {
    let mut options = re_viewer::native::eframe_options(None);
    options.viewport = options
        .viewport
        .with_app_id("weft")
        .with_inner_size([1400.0, 860.0]);
    let scratch = screenshot
        .then(|| std::env::temp_dir().join(format!("weft-screenshot-{}.ron", std::process::id())));
    options.persistence_path = scratch.clone();
    (options, scratch)
}

/// The pictures egui took for [`WeftScreenshot`]s that arrived this frame.
fn shots_taken(ctx: &egui::Context) -> Vec<(Option<u32>, std::sync::Arc<egui::ColorImage>)> {
    ctx.input(|i| {
        i.raw
            .events
            .iter()
            .filter_map(|e| match e {
                egui::Event::Screenshot {
                    image, user_data, ..
                } => user_data
                    .data
                    .as_ref()
                    .and_then(|d| d.downcast_ref::<WeftScreenshot>())
                    .map(|w| (w.0, image.clone())),
                _ => None,
            })
            .collect()
    })
}

/// Saves egui's picture as a PNG and returns its size; a picture that
/// cannot be saved ends the process with status 2, saying why.
fn save_png(image: &egui::ColorImage, path: &std::path::Path) -> [usize; 2] {
    let [w, h] = image.size;
    let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
    match image::RgbaImage::from_raw(w as u32, h as u32, bytes).map(|img| img.save(path)) {
        Some(Ok(())) => [w, h],
        Some(Err(e)) => {
            re_log::error!("cannot save {}: {e}", path.display());
            std::process::exit(2);
        }
        None => {
            re_log::error!("egui's screenshot has the wrong size");
            std::process::exit(2);
        }
    }
}

/// What the viewer reports, passed on to the panel: the time cursor and
/// timeline, and a particle selected in the 3D view, or the point where
/// the cloth's mesh was clicked (the panel inspects the particle nearest
/// it).
pub fn on_viewer_event(link: &std::sync::Mutex<panel::ViewerLink>, event: ViewerEvent) {
    let recording = event.recording_id.to_string();
    let mut link = link.lock().expect("not poisoned");
    match event.kind {
        ViewerEventKind::TimelineChange {
            timeline_name,
            time,
        } => {
            link.timeline = Some(timeline_name.as_str().to_string());
            link.time(recording, time.as_f64());
        }
        ViewerEventKind::TimeUpdate { time } => link.time(recording, time.as_f64()),
        ViewerEventKind::SelectionChange { items } => {
            let particles = re_viewer::external::re_log_types::EntityPath::from(paths::PARTICLES);
            let mesh = re_viewer::external::re_log_types::EntityPath::from(paths::MESH);
            for item in items {
                if let SelectionChangeItem::Entity {
                    entity_path,
                    instance_id,
                    position,
                    ..
                } = item
                {
                    if entity_path == particles && !instance_id.is_all() {
                        link.select(recording.clone(), instance_id.get() as usize);
                    } else if entity_path == mesh
                        && let Some(at) = position
                    {
                        link.pick(recording.clone(), at.to_array());
                    }
                }
            }
        }
        _ => {}
    }
}

/// Opens the window on `preset` (a shipped name or a file) with `--set`
/// overrides; blocks until it closes.
pub fn run(
    preset: &str,
    overrides: &[Override],
    memory_limit: &str,
    screenshot: Option<Screenshot>,
) -> anyhow::Result<()> {
    let memory_text = memory_limit.to_string();
    let memory_limit = viewer_memory_limit(memory_limit)?;
    let loaded = load::load(preset, overrides)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    let _guard = runtime.enter();
    let main_thread_token = re_viewer::MainThreadToken::i_promise_i_am_on_the_main_thread();
    let (tx, rx) = re_log_channel::log_channel(re_log_channel::LogSource::Sdk);
    let cursor_tx = tx.clone();
    let session = Session::start(
        loaded,
        preset.to_string(),
        move |msg: &rerun::log::LogMsg| {
            // The viewer's end closes only with the window, when nothing is
            // left to show a message to.
            tx.send(msg.clone().into()).ok();
        },
    )
    .map_err(anyhow::Error::msg)?;
    let mut panel = Panel::new(&session.status());
    panel.memory_limit = memory_text;
    let link = panel.link();
    let timeline = panel.link();
    let reports = session.cursor_reports();
    session.on_whole_frame(move |frame| {
        let timeline = timeline.lock().expect("not poisoned").timeline.clone();
        // Sent after the frame's drawing: the viewer takes it in order.
        cursor_tx
            .send(whole::cursor_command(frame, timeline.as_deref()))
            .ok();
    });
    let (options, scratch) = window_options(screenshot.is_some());
    let startup = re_viewer::StartupOptions {
        on_event: Some(Rc::new(move |e| {
            let moves = link.lock().expect("not poisoned").cursor_moves;
            on_viewer_event(&link, e);
            // A simulation waiting for the viewer goes on at once, not when
            // the panel next draws (nothing may ask for that soon).
            let link = link.lock().expect("not poisoned");
            if link.cursor_moves != moves
                && let Some((id, at)) = link.cursor.clone()
            {
                reports.shows(id, at);
            }
        })),
        // A screenshot shows the window as it opens, not as last left.
        persist_state: screenshot.is_none(),
        ..Default::default()
    };
    let ran = eframe::run_native(
        "weft",
        options,
        Box::new(move |cc| {
            let mut viewer = viewer_app(main_thread_token, startup, cc)?;
            viewer.app_options_mut().memory_limit = memory_limit;
            viewer.add_log_receiver(rx);
            viewer.extend_view_class(SpatialView3D::identifier(), |r| {
                r.register_context_system::<pull::Probe>()
            })?;
            let ctx = cc.egui_ctx.clone();
            session.set_waker(move || ctx.request_repaint());
            session.pace_to_viewer();
            Ok(Box::new(WeftApp {
                viewer,
                panel,
                session,
                screenshot: screenshot.map(|s| (s, Shot::Start, Instant::now())),
                lag: 0.0,
                drawn: (0, 0),
                latency: 0.0,
                burst_taken: 0,
                scrub: ruler::Scrub::default(),
                gesture: pull::Gesture::default(),
            }))
        }),
    );
    if let Some(scratch) = scratch {
        // Nothing to keep; a file the window never wrote is not an error.
        std::fs::remove_file(scratch).ok();
    }
    ran.map_err(|e| anyhow::anyhow!("the window failed: {e}"))
}
