//! The status line at the top of the panel, and how a preset error reads
//! there.

use egui::Color32;

use super::{Panel, Place};
use crate::app::session::Status;
use crate::scene::PresetError;

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

impl Panel {
    /// The status line, at the top of the panel whatever is scrolled: the
    /// session's error (a solver failure, a file problem), or the keys.
    /// A refused branch shows beside Branch, and the answer to an edit or
    /// action beside its control ([`Self::message_ui`]).
    pub(super) fn status_line(&self, ui: &mut egui::Ui, status: &Status) {
        match status.error.as_deref() {
            Some(e) if !is_branch_error(e) => {
                ui.colored_label(RED, e);
            }
            _ => {
                ui.weak("Space play/pause · Right arrow step · Backspace reset · F8 branch");
            }
        }
    }

    /// The answer to the last edit or action, if it was made at `place`.
    pub(super) fn message_ui(&self, ui: &mut egui::Ui, place: Place) {
        if let Some(m) = self.message.as_ref().filter(|m| m.place == place) {
            let colour = if m.ok { GREEN } else { RED };
            ui.add(egui::Label::new(egui::RichText::new(&m.text).color(colour)).wrap());
        }
    }

    /// Clears the answer to an earlier input: a valid one was made.
    pub(super) fn valid_input(&mut self) {
        self.message = None;
    }
}

/// Whether the session's error is a refused branch (shown beside Branch).
pub(super) fn is_branch_error(e: &str) -> bool {
    e.starts_with("cannot branch")
}

/// A refusal's colour.
pub(super) const RED: Color32 = Color32::from_rgb(230, 80, 70);
/// An answer's colour.
const GREEN: Color32 = Color32::from_rgb(110, 190, 110);
