//! The desktop debugger: one eframe window with the Rerun viewer embedded,
//! fed directly by the running simulation, beside the egui tuning panel.
//!
//! - [`session`]: the simulation thread, its commands and status, and the
//!   stream that feeds the viewer (and a file, while recording);
//! - [`panel`]: the tuning panel.
//!
//! The viewer is fed in-process: every message of the session's recording
//! stream goes into a `re_log_channel` that the embedded viewer reads, so no
//! server or network is involved.

pub mod panel;
pub mod session;

use anyhow::Context;
use re_viewer::external::re_log_channel;

use crate::scene::load;
use panel::Panel;
use session::Session;

/// The window: the viewer and the panel.
pub struct WeftApp {
    viewer: re_viewer::App,
    panel: Panel,
    session: Session,
}

impl eframe::App for WeftApp {
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        self.viewer.save(storage);
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        egui::Panel::right("weft_panel")
            .default_size(320.0)
            .show(ui, |ui| self.panel.ui(ui, &self.session));
        self.viewer.ui(ui, frame);
        // The simulation runs on its own thread; keep showing its frames.
        ui.ctx()
            .request_repaint_after(std::time::Duration::from_millis(16));
    }

    fn logic(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        self.viewer.logic(ctx, frame);
    }
}

/// Opens the window on `preset` (a shipped name or a file); blocks until it closes.
pub fn run(preset: &str) -> anyhow::Result<()> {
    let loaded = load::load(preset, &[])?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    let _guard = runtime.enter();
    let main_thread_token = re_viewer::MainThreadToken::i_promise_i_am_on_the_main_thread();
    let (tx, rx) = re_log_channel::log_channel(re_log_channel::LogSource::Sdk);
    let session = Session::start(loaded, preset.to_string(), move |msg| {
        let _ = tx.send(msg.clone().into());
    })
    .map_err(anyhow::Error::msg)?;
    let panel = Panel::new(&session.status());
    let mut options = re_viewer::native::eframe_options(None);
    options.viewport = options
        .viewport
        .with_app_id("weft")
        .with_inner_size([1400.0, 860.0]);
    eframe::run_native(
        "weft",
        options,
        Box::new(move |cc| {
            re_viewer::customize_eframe_and_setup_renderer(cc)?;
            let mut viewer = re_viewer::App::new(
                main_thread_token,
                re_viewer::build_info(),
                re_viewer::AppEnvironment::Custom("weft".into()),
                re_viewer::StartupOptions::default(),
                cc,
                None,
                re_viewer::AsyncRuntimeHandle::from_current_tokio_runtime_or_wasmbindgen()?,
            );
            viewer.add_log_receiver(rx);
            Ok(Box::new(WeftApp {
                viewer,
                panel,
                session,
            }))
        }),
    )
    .map_err(|e| anyhow::anyhow!("the window failed: {e}"))
}
