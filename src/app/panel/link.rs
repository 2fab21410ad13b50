//! What the embedded viewer reports (its time cursor, the particle
//! selected or the point clicked in the 3D view), and how the panel
//! follows it.

use super::Panel;
use crate::app::session::{BranchAt, Command, Session, Status};

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

impl Panel {
    /// Takes the viewer's time cursor (on the current run) as the branch
    /// point, and a particle selected in the 3D view as the inspected one.
    pub(super) fn follow_viewer(&mut self, session: &Session, status: &Status) {
        if status.run.recording_id != self.run_seen {
            // A new run: the branch field follows its frame, not a time
            // cursor or a frame of the run before.
            self.run_seen = status.run.recording_id.clone();
            self.branch_at = None;
            self.branch_typed = false;
        }
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
}
