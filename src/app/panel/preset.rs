//! The preset box (the shipped presets, a file, Load) and "Set any field"
//! (`key=value`, as with `--set`).

use egui::RichText;

use super::{Panel, Place, error_text};
use crate::app::session::{Command, Session, Status};
use crate::scene::{Override, Tuning, load, shipped};

impl Panel {
    pub(super) fn preset_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
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
        self.message_ui(ui, Place::Preset);
    }

    fn load(&mut self, session: &Session, name: String) {
        match load::load(&name, &[]) {
            Ok(loaded) => {
                self.sync(&loaded.preset);
                self.open = name.clone();
                session.send(Command::Load(Box::new(loaded), name.clone()));
                self.say(Place::Preset, true, format!("loaded {name}"));
            }
            Err(e) => self.say(Place::Preset, false, error_text(&e)),
        }
    }

    pub(super) fn set_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
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
        self.message_ui(ui, Place::Set);
    }

    fn apply_set(&mut self, session: &Session, status: &Status) {
        let o: Override = match self.set_text.parse() {
            Ok(o) => o,
            Err(e) => return self.say(Place::Set, false, e.to_string()),
        };
        let Some(current) = &status.preset else {
            return;
        };
        match load::with_overrides(current, std::slice::from_ref(&o)) {
            Err(e) => self.say(Place::Set, false, error_text(&e)),
            Ok(loaded) => {
                let live = Tuning::is_live(&o.key) || o.key.starts_with("telemetry.");
                self.sync(&loaded.preset);
                if live {
                    session.send(Command::Tune(self.tuning));
                    session.send(Command::Telemetry(self.telemetry));
                    self.say(Place::Set, true, format!("set {}", o.key));
                } else {
                    session.send(Command::Load(Box::new(loaded), status.preset_name.clone()));
                    self.say(
                        Place::Set,
                        true,
                        format!("set {}; the scene restarted", o.key),
                    );
                }
            }
        }
    }
}
