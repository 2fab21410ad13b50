//! The tuning panel: immediate-mode egui beside the viewer.
//!
//! Every edit is validated like a preset value before it reaches the
//! session; a rejected value leaves the parameter as it was and shows the
//! message. The panel holds only edit buffers; the session owns the scene.

use std::path::PathBuf;

use egui::{Color32, RichText, Slider, SliderClamping};

use super::session::{Command, Session, Status};
use crate::scene::{
    Override, Tuning, load,
    preset::{ColorBy, Level, Preset, TelemetrySettings},
    shipped,
};
use crate::solver::{Family, Width};

/// The panel's state between frames.
pub struct Panel {
    tuning: Tuning,
    telemetry: TelemetrySettings,
    speed: f32,
    open: String,
    save_path: String,
    record_path: String,
    set_text: String,
    message: Option<(bool, String)>,
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
            speed: 1.0,
            open: status.preset_name.clone(),
            save_path: format!("{stem}_tuned.toml"),
            record_path: format!("{stem}_session.rrd"),
            set_text: String::new(),
            message: None,
        };
        p.sync(&preset);
        p
    }

    /// Sets where "Save preset" writes.
    pub fn set_save_path(&mut self, path: impl Into<String>) {
        self.save_path = path.into();
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
        egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .show(ui, |ui| {
                ui.heading("weft");
                self.preset_ui(ui, session, &status);
                ui.separator();
                self.transport_ui(ui, session, &status);
                ui.separator();
                self.readouts_ui(ui, &status);
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
                if let Some(e) = &status.error {
                    ui.colored_label(Color32::from_rgb(230, 80, 70), e);
                }
                if let Some((ok, text)) = &self.message {
                    let colour = if *ok {
                        Color32::from_rgb(110, 190, 110)
                    } else {
                        Color32::from_rgb(230, 80, 70)
                    };
                    ui.colored_label(colour, text);
                }
            });
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
            Err(e) => self.say(false, e.to_string()),
        }
    }

    fn transport_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.horizontal(|ui| {
            if status.playing {
                if ui.button("Pause").clicked() {
                    session.send(Command::Pause);
                }
            } else if ui.button("Play").clicked() {
                session.send(Command::Play);
            }
            if ui.button("Step").clicked() {
                session.send(Command::Step);
            }
            if ui.button("Reset").clicked() {
                session.send(Command::Reset);
            }
        });
        if ui
            .add(
                Slider::new(&mut self.speed, 0.05..=4.0)
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
        let p = &mut self.tuning.solver;
        let free = SliderClamping::Never;
        ui.add(
            Slider::new(&mut p.damping, 0.0..=1.0)
                .clamping(free)
                .text("k damping"),
        );
        for f in Family::BY_INDEX {
            ui.add(
                Slider::new(&mut p.weights[f], 0.0..=1.0)
                    .clamping(free)
                    .text(format!("λ {}", f.name())),
            );
        }
        ui.add(
            Slider::new(&mut p.phi, 0.0..=std::f32::consts::PI)
                .clamping(free)
                .text("Φ cap (rad)"),
        );
        ui.horizontal(|ui| {
            let mut auto = p.h == Width::Auto;
            if ui.checkbox(&mut auto, "h auto").changed() {
                p.h = if auto {
                    Width::Auto
                } else {
                    Width::Fixed(0.001)
                };
            }
            if let Width::Fixed(h) = &mut p.h {
                ui.add(
                    Slider::new(h, 0.0..=0.1)
                        .logarithmic(true)
                        .clamping(free)
                        .text("h"),
                );
            }
        });
        ui.add(
            Slider::new(&mut p.iterations, 1..=50)
                .clamping(free)
                .text("iterations"),
        );
        ui.add(
            Slider::new(&mut p.dt, 0.001..=0.05)
                .clamping(free)
                .text("Δt (s)"),
        );
        ui.add(
            Slider::new(&mut p.substeps, 1..=32)
                .clamping(free)
                .text("substeps"),
        );
        self.commit(session, before);
    }

    fn wind_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Wind").strong());
        let before = self.tuning;
        let w = &mut self.tuning.wind;
        ui.horizontal(|ui| {
            ui.label("velocity");
            ui.add(
                egui::DragValue::new(&mut w.velocity.x)
                    .speed(0.1)
                    .prefix("x "),
            );
            ui.add(
                egui::DragValue::new(&mut w.velocity.y)
                    .speed(0.1)
                    .prefix("y "),
            );
            ui.add(
                egui::DragValue::new(&mut w.velocity.z)
                    .speed(0.1)
                    .prefix("z "),
            );
        });
        ui.add(Slider::new(&mut w.gust, 0.0..=20.0).text("gust (m/s)"));
        ui.add(Slider::new(&mut w.gust_period, 0.0..=10.0).text("gust period (s)"));
        ui.add(Slider::new(&mut w.sway, 0.0..=90.0).text("sway (°)"));
        self.commit(session, before);
    }

    fn telemetry_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Telemetry").strong());
        let before = self.telemetry;
        let t = &mut self.telemetry;
        egui::ComboBox::from_label("level")
            .selected_text(format!("{:?}", t.level).to_lowercase())
            .show_ui(ui, |ui| {
                for l in [Level::Off, Level::Summary, Level::Full] {
                    ui.selectable_value(&mut t.level, l, format!("{l:?}").to_lowercase());
                }
            });
        egui::ComboBox::from_label("colour by")
            .selected_text(format!("{:?}", t.color_by).to_lowercase())
            .show_ui(ui, |ui| {
                for c in [
                    ColorBy::Strain,
                    ColorBy::Speed,
                    ColorBy::Correction,
                    ColorBy::None,
                ] {
                    ui.selectable_value(&mut t.color_by, c, format!("{c:?}").to_lowercase());
                }
            });
        ui.horizontal_wrapped(|ui| {
            ui.label("corrections:");
            for f in Family::BY_INDEX {
                ui.checkbox(&mut t.corrections[f], f.name());
            }
        });
        ui.add(
            Slider::new(&mut t.arrow_scale, 0.1..=500.0)
                .logarithmic(true)
                .text("arrow scale"),
        );
        ui.add(Slider::new(&mut t.arrow_threshold, 0.0..=0.01).text("arrow threshold"));
        if *t != before {
            session.send(Command::Telemetry(*t));
        }
    }

    fn set_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Set any field").strong())
            .on_hover_text("key=value, as with --set; scene fields restart the scene");
        let mut apply = false;
        ui.horizontal(|ui| {
            let edit = ui.add(
                egui::TextEdit::singleline(&mut self.set_text)
                    .hint_text("solver.weights.curvature=0.3")
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
            Err(e) => return self.say(false, e),
        };
        let Some(current) = &status.preset else {
            return;
        };
        match load::with_overrides(current, std::slice::from_ref(&o)) {
            Err(e) => self.say(false, e.to_string()),
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

    /// Writes the current preset (with the tuning) and checks it loads back identically.
    fn save(&mut self, status: &Status) {
        let Some(preset) = &status.preset else { return };
        let text = format!(
            "# Saved by weft from {} at frame {}.\n{}",
            status.preset_name,
            status.frame,
            load::to_toml(preset)
        );
        let path = self.save_path.clone();
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
