//! The simulation's keyboard shortcuts: which keys, how the panel names
//! them, and what they do.

use egui::Key;

use super::Panel;
use crate::app::session::{Command, Session, Status};

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

/// A shortcut's keys as the panel names them: `F6 or Space`.
pub(super) fn keys_of(f: Key) -> String {
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

impl Panel {
    /// F6 or Space play/pause, F7 or Right arrow step, F8 branch, F9 or Backspace
    /// reset (see [`SHORTCUTS`]); the plain keys only while no text field is
    /// being typed in.
    pub(super) fn shortcuts(&mut self, ctx: &egui::Context, session: &Session, status: &Status) {
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
}
