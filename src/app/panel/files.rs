//! Files: saving the running preset (whole, or as `extend` plus the changed
//! keys) and recording a session to an `.rrd`.

use std::path::{Path, PathBuf};

use egui::RichText;

use super::{Panel, Place};
use crate::app::preset_diff;
use crate::app::session::{Command, Session, Status};
use crate::scene::load;

impl Panel {
    pub(super) fn files_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Files").strong());
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path).desired_width(150.0));
            if ui.button("Save preset").clicked() {
                self.save(status);
            }
        });
        self.message_ui(ui, Place::Save);
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
                    let path = status.recording.as_ref().map(|p| p.display().to_string());
                    let path = path.unwrap_or_else(|| self.record_path.clone());
                    self.say(Place::Record, true, format!("recorded to {path}"));
                }
            } else if ui.button("Record").clicked() {
                session.send(Command::StartRecording(PathBuf::from(&self.record_path)));
                self.valid_input();
            }
        });
        if let Some(path) = &status.recording {
            ui.weak(format!("recording to {} (from frame 0)", path.display()));
        }
        self.message_ui(ui, Place::Record);
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
            return self.say(Place::Save, false, format!("cannot save to {path}: {e}"));
        }
        match load::load(&path, &[]) {
            Ok(l) if &l.preset == preset => self.say(Place::Save, true, format!("saved {path}")),
            Ok(_) => self.say(
                Place::Save,
                false,
                format!("saved {path}, but it loads back differently"),
            ),
            Err(e) => self.say(
                Place::Save,
                false,
                format!("saved {path}, but it does not load: {e}"),
            ),
        }
    }
}
