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

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use egui::{Color32, Key, RichText, Slider, SliderClamping};

use super::preset_diff;
use super::session::{BranchAt, Command, Session, Status};
use crate::scene::{
    Override, PresetError, Tuning, load,
    preset::{ColorBy, Level, Preset, TelemetrySettings, WindSection},
    shipped,
};
use crate::solver::{Family, Params, Width};

/// The simulation's keyboard shortcuts: key, the key that does the same
/// (taken from the viewer, which would use it for its timeline), what it
/// does. The plain keys act only while no text field is being typed in.
pub const SHORTCUTS: [(Key, Option<Key>, &str); 4] = [
    (Key::F6, Some(Key::Space), "Play / Pause"),
    (Key::F7, Some(Key::ArrowRight), "Step"),
    (Key::F8, None, "Branch"),
    (Key::F9, Some(Key::Backspace), "Reset"),
];

/// Turns the simulation's plain keys (Space, →, Backspace, without
/// modifiers) into its function keys (F6, F7, F9), so that the embedded
/// viewer, which takes Space and the arrows for its timeline at the start
/// of a frame, does not see them. The window calls it on each frame's raw
/// input while no text field has the focus.
pub fn take_simulation_keys(events: &mut [egui::Event]) {
    for event in events {
        if let egui::Event::Key { key, modifiers, .. } = event
            && modifiers.is_none()
            && let Some((f, _, _)) = SHORTCUTS.iter().find(|(_, k, _)| *k == Some(*key))
        {
            *key = *f;
        }
    }
}

/// A preset error as the panel shows it: the key once, the message and the
/// hint (not the `--set …` source, which is the panel's own field).
pub fn error_text(e: &PresetError) -> String {
    let mut text = String::new();
    if !e.source.starts_with("--set") {
        text += &e.source;
        if let Some((line, col)) = e.position {
            text += &format!(":{line}:{col}");
        }
        text += ": ";
    }
    if let Some(key) = &e.key
        && !e.message.contains(&format!("`{key}`"))
    {
        text += &format!("`{key}`: ");
    }
    text += &e.message;
    if let Some(hint) = &e.hint {
        text += &format!(" ({hint})");
    }
    text
}

/// A shortcut's keys as the panel names them: `F6 or Space`.
fn keys_of(f: Key) -> String {
    match SHORTCUTS.iter().find(|(k, _, _)| *k == f) {
        Some((_, Some(plain), _)) => format!("{} or {}", f.name(), key_name(*plain)),
        _ => f.name().to_string(),
    }
}

/// A key's name in the panel's text (whose font has no arrow glyph).
fn key_name(k: Key) -> &'static str {
    match k {
        Key::ArrowRight => "Right arrow",
        k => k.name(),
    }
}

/// What the embedded viewer last reported, written by its event callback.
#[derive(Clone, Debug, Default)]
pub struct ViewerLink {
    /// The timeline the viewer's time cursor is on (`sim_time` until the
    /// viewer says otherwise).
    pub timeline: Option<String>,
    /// The recording id and position of the time cursor.
    pub cursor: Option<(String, BranchAt)>,
    /// Bumped at every cursor move.
    pub cursor_moves: u64,
    /// The recording id and index of the particle selected in the 3D view.
    pub selected: Option<(String, usize)>,
    /// The recording id and the point (world coordinates) of a click on
    /// the cloth's mesh in the 3D view, for picking the nearest particle.
    pub picked_at: Option<(String, [f32; 3])>,
    /// Bumped at every selection.
    pub selections: u64,
}

impl ViewerLink {
    /// Notes the time cursor at `time` (the viewer's units: frames on
    /// `frame`, nanoseconds on `sim_time`) in recording `recording`.
    pub fn time(&mut self, recording: String, time: f64) {
        let at = match self.timeline.as_deref() {
            Some(crate::telemetry::paths::FRAME) => BranchAt::Frame(time.round().max(0.0) as u64),
            _ => BranchAt::Time(time * 1e-9),
        };
        self.cursor = Some((recording, at));
        self.cursor_moves += 1;
    }

    /// Notes a particle selected in recording `recording`.
    pub fn select(&mut self, recording: String, particle: usize) {
        self.selected = Some((recording, particle));
        self.picked_at = None;
        self.selections += 1;
    }

    /// Notes a click on the cloth's mesh at `at` in recording `recording`.
    pub fn pick(&mut self, recording: String, at: [f32; 3]) {
        self.picked_at = Some((recording, at));
        self.selected = None;
        self.selections += 1;
    }
}

/// The panel's state between frames.
pub struct Panel {
    tuning: Tuning,
    telemetry: TelemetrySettings,
    /// Whether the correction arrows are drawn (off at start).
    arrows: bool,
    speed: f32,
    open: String,
    save_path: String,
    record_path: String,
    set_text: String,
    message: Option<(bool, String)>,
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
            speed: 1.0,
            open: status.preset_name.clone(),
            save_path: format!("{stem}_tuned.toml"),
            record_path: format!("{stem}_session.rrd"),
            set_text: String::new(),
            message: None,
            branch_frame: 0,
            branch_at: None,
            branch_editing: false,
            branch_typed: false,
            particle: 0,
            inspecting: false,
            save_diff: load::load(&status.preset_name, &[]).is_ok(),
            link: Arc::default(),
            seen: (0, 0, 0),
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

    fn say(&mut self, ok: bool, text: impl Into<String>) {
        self.message = Some((ok, text.into()));
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

    /// The status line, at the top of the panel whatever is scrolled: the
    /// session's error (a solver failure, a refused branch, a file
    /// problem), and the answer to the panel's last edit or action (a
    /// rejected value in red).
    fn status_line(&self, ui: &mut egui::Ui, status: &Status) {
        let red = Color32::from_rgb(230, 80, 70);
        if let Some(e) = &status.error {
            ui.colored_label(red, e);
        }
        match &self.message {
            Some((true, text)) => {
                ui.colored_label(Color32::from_rgb(110, 190, 110), text);
            }
            Some((false, text)) => {
                ui.colored_label(red, text);
            }
            None if status.error.is_none() => {
                ui.weak("Space play/pause · Right arrow step · Backspace reset · F8 branch");
            }
            None => {}
        }
    }

    fn preset_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Preset").strong());
        let mut chosen = None;
        egui::ComboBox::from_id_salt("preset")
            .selected_text(&status.preset_name)
            .show_ui(ui, |ui| {
                for p in shipped::ALL {
                    if ui
                        .selectable_label(status.preset_name == p.name, p.name)
                        .on_hover_text(p.description())
                        .clicked()
                    {
                        chosen = Some(p.name.to_string());
                    }
                }
            });
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.open)
                    .hint_text("preset file")
                    .desired_width(150.0),
            );
            if ui.button("Load").clicked() {
                chosen = Some(self.open.clone());
            }
        });
        if let Some(name) = chosen {
            self.load(session, name);
        }
    }

    fn load(&mut self, session: &Session, name: String) {
        match load::load(&name, &[]) {
            Ok(loaded) => {
                self.sync(&loaded.preset);
                self.open = name.clone();
                session.send(Command::Load(Box::new(loaded), name.clone()));
                self.say(true, format!("loaded {name}"));
            }
            Err(e) => self.say(false, error_text(&e)),
        }
    }

    /// F6 or Space play/pause, F7 or Right arrow step, F8 branch, F9 or Backspace
    /// reset (see [`SHORTCUTS`]); the plain keys only while no text field is
    /// being typed in.
    fn shortcuts(&mut self, ctx: &egui::Context, session: &Session, status: &Status) {
        let typing = ctx.text_edit_focused();
        let pressed = |f: Key| {
            let plain = SHORTCUTS
                .iter()
                .find(|(k, _, _)| *k == f)
                .and_then(|(_, plain, _)| *plain)
                .filter(|_| !typing);
            ctx.input_mut(|i| {
                i.consume_key(egui::Modifiers::NONE, f)
                    | plain.is_some_and(|k| i.consume_key(egui::Modifiers::NONE, k))
            })
        };
        if pressed(Key::F6) {
            session.send(if status.playing {
                Command::Pause
            } else {
                Command::Play
            });
        }
        if pressed(Key::F7) {
            session.send(Command::Step);
        }
        if pressed(Key::F8) {
            self.branch(session, status);
        }
        if pressed(Key::F9) {
            session.send(Command::Reset);
        }
    }

    /// Takes the viewer's time cursor (on the current run) as the branch
    /// point, and a particle selected in the 3D view as the inspected one.
    fn follow_viewer(&mut self, session: &Session, status: &Status) {
        let link = self.link.lock().expect("not poisoned").clone();
        if link.cursor_moves != self.seen.0 {
            self.seen.0 = link.cursor_moves;
            if let Some((id, at)) = link.cursor
                && id == status.run.recording_id
            {
                session.viewer_shows(id, at);
                if !self.branch_typed {
                    self.branch_at = Some(at);
                    if let BranchAt::Frame(f) = at {
                        self.branch_frame = f;
                    }
                }
            }
        }
        if link.selections != self.seen.1 {
            self.seen.1 = link.selections;
            if let Some((_, i)) = link.selected {
                self.particle = i;
                self.inspecting = true;
                session.send(Command::Inspect(Some(i)));
            } else if let Some((id, at)) = link.picked_at
                && id == status.run.recording_id
            {
                self.inspecting = true;
                session.send(Command::InspectNear(at));
            }
        }
        if let Some((n, i)) = status.picked
            && n != self.seen.2
        {
            self.seen.2 = n;
            self.particle = i;
        }
    }

    fn branch(&mut self, session: &Session, status: &Status) {
        let at = self.branch_at.unwrap_or(BranchAt::Frame(status.frame));
        session.send(Command::Branch(at));
        self.branch_at = None;
        self.branch_typed = false;
    }

    fn transport_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.horizontal(|ui| {
            if status.playing {
                if ui
                    .button("Pause")
                    .on_hover_text(format!("Pause ({})", keys_of(Key::F6)))
                    .clicked()
                {
                    session.send(Command::Pause);
                }
            } else if ui
                .button("Play")
                .on_hover_text(format!("Play ({})", keys_of(Key::F6)))
                .clicked()
            {
                session.send(Command::Play);
            }
            if ui
                .button("Step")
                .on_hover_text(format!("Step one frame ({})", keys_of(Key::F7)))
                .clicked()
            {
                session.send(Command::Step);
            }
            if ui
                .button("Reset")
                .on_hover_text(format!(
                    "Start over from frame 0 with the current tuning, as a new run ({})",
                    keys_of(Key::F9)
                ))
                .clicked()
            {
                session.send(Command::Reset);
            }
        });
        ui.horizontal(|ui| {
            if ui
                .button("Branch")
                .on_hover_text(format!(
                    "A new run from this frame of the current one, with the current tuning ({})",
                    keys_of(Key::F8)
                ))
                .clicked()
            {
                self.branch(session, status);
            }
            ui.label("at frame");
            match self.branch_at {
                // Being typed in: the text is the user's.
                _ if self.branch_editing => {}
                None => self.branch_frame = status.frame,
                // Shown as a frame; the session finds the exact one.
                Some(BranchAt::Time(t)) => {
                    let dt = status.preset.as_ref().map_or(1.0, |p| p.solver.dt) as f64;
                    self.branch_frame = (t / dt).round() as u64;
                }
                Some(BranchAt::Frame(_)) => {}
            }
            // Not bounded by the run's frame: a frame past it is refused by
            // the session, with the reason, rather than quietly clamped.
            let field =
                ui.add(egui::DragValue::new(&mut self.branch_frame).update_while_editing(false));
            self.branch_editing = field.has_focus();
            if field.changed() {
                self.branch_at = Some(BranchAt::Frame(self.branch_frame));
                self.branch_typed = true;
            }
            if self.branch_typed {
                if ui
                    .small_button("clear")
                    .on_hover_text("follow the current frame and the viewer's time cursor again")
                    .clicked()
                {
                    self.branch_typed = false;
                    self.branch_at = None;
                }
            } else if let Some(BranchAt::Time(t)) = self.branch_at {
                ui.label(format!("(time cursor {t:.2} s)"));
            }
        });
        if ui
            .add(
                slider(&mut self.speed, 0.05..=4.0)
                    .logarithmic(true)
                    .text("speed ×"),
            )
            .changed()
        {
            session.send(Command::Speed(self.speed));
        }
    }

    fn readouts_ui(&mut self, ui: &mut egui::Ui, status: &Status) {
        egui::Grid::new("readouts")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let row = |ui: &mut egui::Ui, k: &str, v: String| {
                    ui.label(k);
                    ui.monospace(v);
                    ui.end_row();
                };
                row(
                    ui,
                    "frame",
                    format!("{} ({:.2} s)", status.frame, status.time),
                );
                row(ui, "steps/s", format!("{:.0}", status.steps_per_second));
                row(ui, "step time", format!("{:.2} ms", status.step_ms));
                row(ui, "max strain", format!("{:.4}", status.max_strain));
                for (f, v) in status.max_violation.iter() {
                    row(ui, &format!("max {}", f.name()), format!("{v:.4}"));
                }
                row(ui, "crossing edges", status.crossings.to_string());
                row(
                    ui,
                    "checkpoints",
                    format!(
                        "{} (every {} frames)",
                        status.checkpoints.0, status.checkpoints.1
                    ),
                );
            });
        ui.label(RichText::new(format!("run {}", status.run.name)).small())
            .on_hover_text(format!(
                "Rerun recording {}; {} runs in this session (the viewer's recording list)",
                status.run.recording_id,
                status.runs.len()
            ));
    }

    /// The preset's `[expect]` bounds against the run so far.
    fn verdicts_ui(&mut self, ui: &mut egui::Ui, status: &Status) {
        ui.label(RichText::new("Verdicts").strong())
            .on_hover_text("the preset's [expect] bounds against this run's values so far");
        if status.checks.is_empty() {
            ui.label("no [expect] bounds in this preset");
            return;
        }
        egui::Grid::new("verdicts")
            .num_columns(4)
            .striped(true)
            .show(ui, |ui| {
                for c in &status.checks {
                    ui.label(c.bound.trim_start_matches("expect."));
                    ui.monospace(figure(c.value));
                    ui.monospace(format!("≤ {}", figure(c.limit)));
                    if c.ok {
                        ui.colored_label(Color32::from_rgb(110, 190, 110), "ok");
                    } else {
                        ui.colored_label(Color32::from_rgb(230, 80, 70), "FAIL");
                    }
                    ui.end_row();
                }
            });
    }

    /// One particle's numbers: pick it in the 3D view, or type its index.
    fn inspector_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Particle").strong())
            .on_hover_text("click a particle in the 3D view, or type its index");
        let n = status
            .preset
            .as_ref()
            .map_or(1, |p| (p.cloth.weft * p.cloth.warp) as usize);
        ui.horizontal(|ui| {
            let mut changed = ui
                .checkbox(&mut self.inspecting, "inspect particle")
                .changed();
            changed |= ui
                .add(
                    egui::DragValue::new(&mut self.particle)
                        .range(0..=n.saturating_sub(1))
                        .update_while_editing(false),
                )
                .changed();
            if changed {
                session.send(Command::Inspect(self.inspecting.then_some(self.particle)));
            }
        });
        let Some(p) = status.particle.as_ref().filter(|_| self.inspecting) else {
            return;
        };
        ui.monospace(format!(
            "#{}  (i, j) = ({}, {})   strain {:.4}",
            p.index, p.cell.0, p.cell.1, p.strain
        ));
        let offset = p.normal_offset.to_degrees();
        let turned = if offset > 90.0 { ", turned over" } else { "" };
        ui.monospace(format!("normal {offset:.1}° off the surface's{turned}"))
            .on_hover_text(
                "the angle between the element's normal and the surface its neighbours make",
            );
        egui::Grid::new("particle")
            .num_columns(4)
            .striped(true)
            .show(ui, |ui| {
                ui.label("family");
                ui.label("violation");
                ui.label("|δx| (mm)");
                ui.label("|δθ| (mrad)");
                ui.end_row();
                // Until a step records them (at level summary, the step
                // after the particle is picked), the corrections read "–".
                let correction = |ui: &mut egui::Ui, v: glam::Vec3| {
                    if p.corrections {
                        ui.monospace(format!("{:.4}", v.length() * 1e3));
                    } else {
                        ui.monospace("–")
                            .on_hover_text("recorded from the next step");
                    }
                };
                for f in Family::ALL {
                    ui.label(f.name());
                    ui.monospace(format!("{:.4}", p.violation[f]));
                    correction(ui, p.dx[f]);
                    correction(ui, p.dtheta[f]);
                    ui.end_row();
                }
            });
    }

    /// Sends the tuning if it validates (`Tuning::validate`), else restores
    /// the last good one and shows why.
    fn commit(&mut self, session: &Session, before: Tuning) {
        if self.tuning == before {
            return;
        }
        match self.tuning.validate() {
            Ok(()) => {
                session.send(Command::Tune(self.tuning));
                self.message = None;
            }
            Err(e) => {
                self.say(false, e.to_string());
                self.tuning = before;
            }
        }
    }

    fn solver_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Solver").strong());
        let before = self.tuning;
        // Every field, by name: a new parameter without a control here does
        // not compile.
        let Params {
            damping,
            weights,
            phi,
            h,
            iterations,
            dt,
            substeps,
        } = &mut self.tuning.solver;
        let free = SliderClamping::Never;
        ui.add(slider(damping, 0.0..=1.0).clamping(free).text("k damping"));
        for f in Family::ALL {
            ui.add(
                slider(&mut weights[f], 0.0..=1.0)
                    .clamping(free)
                    .text(format!("λ {}", f.name())),
            );
        }
        ui.add(
            slider(phi, 0.0..=std::f32::consts::PI)
                .clamping(free)
                .text("Φ cap (rad)"),
        );
        ui.horizontal(|ui| {
            let mut auto = *h == Width::Auto;
            if ui.checkbox(&mut auto, "h auto").changed() {
                *h = if auto {
                    Width::Auto
                } else {
                    Width::Fixed(0.001)
                };
            }
            if let Width::Fixed(h) = h {
                ui.add(
                    slider(h, 0.0..=0.1)
                        .logarithmic(true)
                        .clamping(free)
                        .text("h"),
                );
            }
        });
        ui.add(slider(iterations, 1..=50).clamping(free).text("iterations"));
        ui.add(slider(dt, 0.001..=0.05).clamping(free).text("Δt (s)"));
        ui.add(slider(substeps, 1..=32).clamping(free).text("substeps"));
        self.commit(session, before);
    }

    fn wind_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Wind").strong());
        let before = self.tuning;
        let WindSection {
            velocity,
            gust,
            gust_period,
            sway,
        } = &mut self.tuning.wind;
        ui.horizontal(|ui| {
            ui.label("velocity");
            for (v, axis) in [
                (&mut velocity.x, "x "),
                (&mut velocity.y, "y "),
                (&mut velocity.z, "z "),
            ] {
                ui.add(drag(v).speed(0.1).prefix(axis));
            }
        });
        ui.add(slider(gust, 0.0..=20.0).text("gust (m/s)"));
        ui.add(slider(gust_period, 0.0..=10.0).text("gust period (s)"));
        ui.add(slider(sway, 0.0..=90.0).text("sway (°)"));
        self.commit(session, before);
    }

    fn telemetry_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Telemetry").strong());
        let before = self.telemetry;
        let TelemetrySettings {
            level,
            log_every,
            arrow_threshold,
            arrow_scale,
            color_by,
            corrections,
        } = &mut self.telemetry;
        egui::ComboBox::from_label("level")
            .selected_text(format!("{level:?}").to_lowercase())
            .show_ui(ui, |ui| {
                for l in [Level::Off, Level::Summary, Level::Full] {
                    ui.selectable_value(level, l, format!("{l:?}").to_lowercase());
                }
            });
        egui::ComboBox::from_label("colour by")
            .selected_text(color_by.name().into_owned())
            .show_ui(ui, |ui| {
                for c in ColorBy::all() {
                    ui.selectable_value(color_by, c, c.name().into_owned());
                }
            });
        ui.add(
            drag(log_every)
                .range(1..=1000)
                .prefix("log every ")
                .suffix(" frames"),
        );
        if ui
            .checkbox(&mut self.arrows, "correction arrows")
            .on_hover_text(
                "Draw each family's δx and δθ (level full), of the families ticked below",
            )
            .changed()
        {
            session.send(Command::Arrows(self.arrows));
        }
        ui.horizontal_wrapped(|ui| {
            ui.label("corrections:");
            for f in Family::ALL {
                ui.checkbox(&mut corrections[f], f.name());
            }
        });
        ui.add(
            slider(arrow_scale, 0.1..=500.0)
                .logarithmic(true)
                .text("arrow scale"),
        );
        ui.add(slider(arrow_threshold, 0.0..=0.01).text("arrow threshold"));
        if self.telemetry != before {
            session.send(Command::Telemetry(self.telemetry));
        }
    }

    fn set_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Set any field").strong())
            .on_hover_text("key=value, as with --set; scene fields restart the scene");
        let mut apply = false;
        ui.horizontal(|ui| {
            let edit = ui.add(
                egui::TextEdit::singleline(&mut self.set_text)
                    .hint_text("solver.weights.normality=0.3")
                    .desired_width(170.0),
            );
            apply = ui.button("Apply").clicked()
                || (edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)));
        });
        if apply {
            self.apply_set(session, status);
        }
    }

    fn apply_set(&mut self, session: &Session, status: &Status) {
        let o: Override = match self.set_text.parse() {
            Ok(o) => o,
            Err(e) => return self.say(false, e.to_string()),
        };
        let Some(current) = &status.preset else {
            return;
        };
        match load::with_overrides(current, std::slice::from_ref(&o)) {
            Err(e) => self.say(false, error_text(&e)),
            Ok(loaded) => {
                let live = Tuning::is_live(&o.key) || o.key.starts_with("telemetry.");
                self.sync(&loaded.preset);
                if live {
                    session.send(Command::Tune(self.tuning));
                    session.send(Command::Telemetry(self.telemetry));
                    self.say(true, format!("set {}", o.key));
                } else {
                    session.send(Command::Load(Box::new(loaded), status.preset_name.clone()));
                    self.say(true, format!("set {}; the scene restarted", o.key));
                }
            }
        }
    }

    fn files_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Files").strong());
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path).desired_width(150.0));
            if ui.button("Save preset").clicked() {
                self.save(status);
            }
        });
        ui.checkbox(&mut self.save_diff, "save as a diff")
            .on_hover_text(format!(
                "extend = \"{}\" and only the changed keys; off: the whole preset",
                status.preset_name
            ));
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.record_path).desired_width(150.0));
            if status.recording.is_some() {
                if ui.button("Stop recording").clicked() {
                    session.send(Command::StopRecording);
                    self.say(true, format!("recorded to {}", self.record_path));
                }
            } else if ui.button("Record").clicked() {
                session.send(Command::StartRecording(PathBuf::from(&self.record_path)));
            }
        });
    }

    /// Writes the current preset (with the tuning) and checks it loads
    /// back identically: as `extend = "<base>"` plus the changed keys when
    /// "save as a diff" is on and the base loads, else whole.
    fn save(&mut self, status: &Status) {
        let Some(preset) = &status.preset else { return };
        let path = self.save_path.clone();
        let comment = format!(
            "Saved by weft from {} at frame {}.",
            status.preset_name, status.frame
        );
        let diff = match load::load(&status.preset_name, &[]) {
            Ok(base) if self.save_diff => preset_diff::as_extension(
                &comment,
                &status.preset_name,
                &base.preset,
                preset,
                Path::new(&path),
            ),
            _ => None,
        };
        let text = diff.unwrap_or_else(|| format!("# {comment}\n{}", load::to_toml(preset)));
        if let Err(e) = std::fs::write(&path, text) {
            return self.say(false, format!("cannot save to {path}: {e}"));
        }
        match load::load(&path, &[]) {
            Ok(l) if &l.preset == preset => self.say(true, format!("saved {path}")),
            Ok(_) => self.say(
                false,
                format!("saved {path}, but it loads back differently"),
            ),
            Err(e) => self.say(false, format!("saved {path}, but it does not load: {e}")),
        }
    }
}

/// A slider whose value, typed, is taken on Enter or when the field loses
/// focus (dragging still applies as it moves).
fn slider<Num: egui::emath::Numeric>(
    value: &mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> Slider<'_> {
    Slider::new(value, range).update_while_editing(false)
}

/// A number field whose value, typed, is taken on Enter or when it loses
/// focus.
fn drag<Num: egui::emath::Numeric>(value: &mut Num) -> egui::DragValue<'_> {
    egui::DragValue::new(value).update_while_editing(false)
}

/// A figure as a person reads it: four decimals in the usual range,
/// scientific notation only for the very small or large.
fn figure(v: f64) -> String {
    if v == 0.0 || (1e-3..1e4).contains(&v.abs()) {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}
