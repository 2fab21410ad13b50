//! A branch's parent as a ghost: the parent's cloth, kept frame by frame
//! in its [`Trace`], drawn faint in the branch's 3D view at each frame the
//! branch logs ([`crate::telemetry::ghost`]), so that what the branch's
//! change does is seen beside the cloth, not only in the plots.

use super::Worker;
use crate::app::session::trace::Trace;
use crate::telemetry::ghost;

/// The ghost of a branch's parent.
pub(in crate::app::session) struct Ghost {
    /// The parent's cloth, frame by frame.
    parent: Trace,
    /// Whether the viewer shows it now (so that turning it off, or the
    /// parent's last frame passing, clears it once).
    drawn: bool,
}

impl Worker {
    /// Keeps the current frame's world positions in the run's trace.
    pub(super) fn keep_frame(&mut self) {
        let scene = &self.run.scene;
        self.trace
            .push(scene.frame(), scene.time(), &scene.world_positions());
    }

    /// Starts drawing `parent` beside a branch just begun: its triangles
    /// and colour, then the parent at the branch's frame.
    pub(super) fn start_ghost(&mut self, parent: Trace) {
        let triangles = &self.run.scene.solver().topology().triangles;
        if let Err(e) = ghost::log_static(&self.rec, triangles) {
            return self.set_error(Some(format!("drawing the parent: {e}")));
        }
        self.ghost = Some(Ghost {
            parent,
            drawn: false,
        });
        self.draw_ghost(true);
        self.send_drawing();
    }

    /// Draws the parent at the current frame, if the run draws this frame
    /// (or `now`: the ghost was just turned on or off); clears it once when
    /// it is turned off or the parent never reached the frame.
    pub(super) fn draw_ghost(&mut self, now: bool) {
        let scene = &self.run.scene;
        let (frame, time) = (scene.frame(), scene.time());
        let Some(g) = self.ghost.as_mut() else {
            return;
        };
        if !now && !self.run.telemetry.draws_frame(frame) {
            return;
        }
        let positions = g.parent.at(frame).filter(|_| self.show_ghost);
        if positions.is_none() && !g.drawn {
            return;
        }
        let triangles = &scene.solver().topology().triangles;
        let logged = ghost::log(&self.rec, frame, time, positions, triangles);
        g.drawn = positions.is_some();
        if let Err(e) = logged {
            self.set_error(Some(format!("drawing the parent: {e}")));
        }
    }
}
