//! The run controls: Play / Pause, Step, Reset, Branch at a frame (the
//! viewer's time cursor, or a typed frame), for a branch whether its
//! parent is drawn as a ghost, and the speed.

use egui::Key;

use super::Panel;
use super::keys::keys_of;
use super::tuning::slider;
use crate::app::session::{BranchAt, Command, Session, Status};

impl Panel {
    pub(super) fn branch(&mut self, session: &Session, status: &Status) {
        let at = self.branch_at.unwrap_or(BranchAt::Frame(status.frame));
        session.send(Command::Branch(at));
        self.branch_at = None;
        self.branch_typed = false;
    }

    pub(super) fn transport_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
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
        if let Some(e) = status
            .error
            .as_deref()
            .filter(|e| super::status::is_branch_error(e))
        {
            ui.add(egui::Label::new(egui::RichText::new(e).color(super::status::RED)).wrap());
        }
        if let Some((parent, _, frame)) = &status.run.parent
            && ui
                .checkbox(&mut self.ghost, "parent as a ghost")
                .on_hover_text(format!(
                    "Draw run #{parent}'s cloth, faint, in the 3D view beside this one's \
                     (from frame {frame}, where they part)"
                ))
                .changed()
        {
            session.send(Command::Ghost(self.ghost));
        }
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
}
