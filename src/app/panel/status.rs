//! The status line at the top of the panel, and how a preset error reads
//! there.

use egui::Color32;

use super::Panel;
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
    /// session's error (a solver failure, a refused branch, a file
    /// problem), and the answer to the panel's last edit or action (a
    /// rejected value in red).
    pub(super) fn status_line(&self, ui: &mut egui::Ui, status: &Status) {
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
}
