//! `weft view FILE.rrd…`: recordings opened in the same embedded viewer the
//! window uses, without Python or a separate `rerun`. Each recording weft
//! writes carries its layout (a blueprint), so it opens as `weft record`
//! laid it out; a comparison as `weft compare` did.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::{WeftScreenshot, save_png, shots_taken, viewer_app, window_options};

/// How long `--screenshot` gives the viewer to load the files and draw
/// them before taking the picture.
const SETTLE: Duration = Duration::from_secs(4);

/// The viewer, and with `--screenshot`, when it started and whether the
/// picture is asked for.
struct ViewApp {
    viewer: re_viewer::App,
    screenshot: Option<(PathBuf, Instant, bool)>,
}

impl eframe::App for ViewApp {
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        self.viewer.save(storage);
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.viewer.ui(ui, frame);
        let ctx = ui.ctx();
        let Some((path, started, asked)) = &mut self.screenshot else {
            return;
        };
        if !*asked && started.elapsed() > SETTLE {
            ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(egui::UserData::new(
                WeftScreenshot(None),
            )));
            *asked = true;
        } else if let Some((_, image)) = shots_taken(ctx).pop() {
            let [w, h] = save_png(&image, path);
            eprintln!("saved the window ({w}×{h}) to {}", path.display());
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        ctx.request_repaint();
    }

    fn logic(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        self.viewer.logic(ctx, frame);
    }

    /// With `--screenshot`, nobody points at the window: wherever the
    /// display leaves the pointer, no tooltip opens over a plot.
    fn raw_input_hook(&mut self, _ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        if self.screenshot.is_some() {
            raw_input
                .events
                .retain(|e| !matches!(e, egui::Event::PointerMoved(_)));
            raw_input.events.push(egui::Event::PointerGone);
        }
    }
}

/// Opens `files` in the viewer; blocks until the window closes. With
/// `screenshot`, saves the window a few seconds after it opens, and quits.
pub fn view(files: &[PathBuf], screenshot: Option<&Path>) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Runtime::new()
        .map_err(|e| anyhow::anyhow!("starting the async runtime: {e}"))?;
    let _guard = runtime.enter();
    let main_thread_token = re_viewer::MainThreadToken::i_promise_i_am_on_the_main_thread();
    let (options, scratch) = window_options(screenshot.is_some());
    let startup = re_viewer::StartupOptions {
        persist_state: screenshot.is_none(),
        ..Default::default()
    };
    let files: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    let screenshot = screenshot.map(|p| (p.to_path_buf(), Instant::now(), false));
    let ran = eframe::run_native(
        "weft",
        options,
        Box::new(move |cc| {
            let viewer = viewer_app(main_thread_token, startup, cc)?;
            for f in &files {
                viewer.open_url_or_file(f);
            }
            Ok(Box::new(ViewApp { viewer, screenshot }))
        }),
    );
    if let Some(scratch) = scratch {
        std::fs::remove_file(scratch).ok();
    }
    ran.map_err(|e| anyhow::anyhow!("the window failed: {e}"))
}
