//! The tuning panel: immediate-mode egui beside the viewer.
//!
//! Every edit is validated like a preset value before it reaches the
//! session; a rejected value leaves the parameter as it was and shows the
//! message in the status line at the top of the panel. A typed value is
//! taken on Enter or when the field loses focus, never keystroke by
//! keystroke; dragging a slider applies as it moves. The panel holds only
//! edit buffers; the session owns the scene. What the viewer reports (its
//! time cursor, the particle selected in the 3D view) reaches the panel
//! through a [`ViewerLink`].
//!
//! Keyboard shortcuts: [`SHORTCUTS`]. The window hands Space, → and
//! Backspace to the panel before the viewer sees them
//! ([`take_simulation_keys`]); Ctrl+→ and the viewer's other keys stay its
//! own.
//!
//! One file per part of the panel, each an `impl Panel` block:
//!
//! - `status`: the status line at the top, and how a preset error reads;
//! - `preset`: the preset picker and loading, and "Set any field";
//! - `transport`: Play / Pause, Step, Reset, Branch at frame, the parent
//!   as a ghost, speed;
//! - `figures`: the readouts, the verdicts and the particle inspector;
//! - `tuning`: the solver's and the wind's sliders, the telemetry settings;
//! - `files`: saving the preset, recording a session;
//! - `keys`: the keyboard shortcuts;
//! - `link`: what the viewer reports (time cursor, selection).

mod figures;
mod files;
mod keys;
mod link;
mod preset;
mod status;
mod transport;
mod tuning;

use std::sync::{Arc, Mutex};

use super::session::{BranchAt, Session, Status};
use crate::scene::{
    Tuning, load,
    preset::{Preset, TelemetrySettings},
};

pub use keys::{SHORTCUTS, take_simulation_keys};
pub use link::ViewerLink;
pub use status::error_text;

/// Where in the panel a message belongs: beside the control it answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    Preset,
    Solver,
    Wind,
    Set,
    Save,
    Record,
}

/// The answer to an edit or action.
#[derive(Clone, Debug)]
struct Message {
    place: Place,
    ok: bool,
    text: String,
}

/// The panel's state between frames.
pub struct Panel {
    tuning: Tuning,
    telemetry: TelemetrySettings,
    /// Whether the correction arrows are drawn (off at start).
    arrows: bool,
    /// Whether a branch's parent is drawn as a ghost (on at start).
    ghost: bool,
    speed: f32,
    open: String,
    save_path: String,
    record_path: String,
    set_text: String,
    /// The answer to the last edit or action, shown beside its control
    /// until the next valid input.
    message: Option<Message>,
    /// The run the panel last showed (a new run's branch field follows it).
    run_seen: String,
    branch_frame: u64,
    branch_at: Option<BranchAt>,
    /// Whether the branch field had the keyboard focus last frame (it is
    /// not overwritten while it is being typed in).
    branch_editing: bool,
    /// Whether the branch frame was typed: then it stays until the user
    /// clears it (or branches), whatever the time cursor does.
    branch_typed: bool,
    particle: usize,
    inspecting: bool,
    save_diff: bool,
    link: Arc<Mutex<ViewerLink>>,
    seen: (u64, u64, u64),
    /// The viewer's memory limit, as `--memory-limit` gave it (shown
    /// beside the heap's size).
    pub memory_limit: String,
}

impl Panel {
    /// A panel showing the session's current preset.
    pub fn new(status: &Status) -> Self {
        let preset = status
            .preset
            .clone()
            .expect("a session always has a preset");
        let stem = status
            .preset_name
            .trim_end_matches(".toml")
            .rsplit('/')
            .next()
            .unwrap_or("preset")
            .to_string();
        let mut p = Self {
            tuning: Tuning::of(&preset),
            telemetry: preset.telemetry,
            arrows: false,
            ghost: true,
            speed: 1.0,
            open: status.preset_name.clone(),
            save_path: format!("{stem}_tuned.toml"),
            record_path: format!("{stem}_session.rrd"),
            set_text: String::new(),
            message: None,
            run_seen: status.run.recording_id.clone(),
            branch_frame: 0,
            branch_at: None,
            branch_editing: false,
            branch_typed: false,
            particle: 0,
            inspecting: false,
            save_diff: load::load(&status.preset_name, &[]).is_ok(),
            link: Arc::default(),
            seen: (0, 0, 0),
            memory_limit: "unlimited".into(),
        };
        p.sync(&preset);
        p
    }

    /// Sets where "Save preset" writes.
    pub fn set_save_path(&mut self, path: impl Into<String>) {
        self.save_path = path.into();
    }

    /// The link the viewer's event callback writes to.
    pub fn link(&self) -> Arc<Mutex<ViewerLink>> {
        self.link.clone()
    }

    /// Sets where "Record" writes.
    pub fn set_record_path(&mut self, path: impl Into<String>) {
        self.record_path = path.into();
    }

    fn sync(&mut self, preset: &Preset) {
        self.tuning = Tuning::of(preset);
        self.telemetry = preset.telemetry;
    }

    /// Answers an edit or action of the control at `place`: beside it, in
    /// red if it was refused.
    fn say(&mut self, place: Place, ok: bool, text: impl Into<String>) {
        self.message = Some(Message {
            place,
            ok,
            text: text.into(),
        });
    }

    /// Draws the panel and sends what the user changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        let status = session.status();
        self.shortcuts(ui.ctx(), session, &status);
        self.follow_viewer(session, &status);
        ui.heading("weft");
        self.status_line(ui, &status);
        ui.separator();
        egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .show(ui, |ui| {
                self.preset_ui(ui, session, &status);
                ui.separator();
                self.transport_ui(ui, session, &status);
                ui.separator();
                self.readouts_ui(ui, &status);
                ui.separator();
                self.verdicts_ui(ui, &status);
                ui.separator();
                self.inspector_ui(ui, session, &status);
                ui.separator();
                self.solver_ui(ui, session);
                ui.separator();
                self.wind_ui(ui, session);
                ui.separator();
                self.telemetry_ui(ui, session);
                ui.separator();
                self.set_ui(ui, session, &status);
                ui.separator();
                self.files_ui(ui, session, &status);
            });
    }
}
