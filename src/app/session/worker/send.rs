//! A frame's drawing sent to the viewer whole, and, while the session
//! moves the viewer's time cursor, the cursor sent after it
//! ([`crate::app::session::follow`]).

use super::Worker;
use crate::app::session::follow::WholeFrame;

impl Worker {
    /// Sends what is logged of the current frame (its drawing, the ghost
    /// with it) at once; while the session moves the viewer's cursor, waits
    /// until it has all gone to the viewer, then has the cursor put on the
    /// frame.
    pub(super) fn send_drawing(&mut self) {
        let follows = self.shown.lock().expect("not poisoned").follow.is_on();
        if !follows {
            self.run.telemetry.send();
            return;
        }
        if let Err(e) = self.run.telemetry.flush() {
            return self.set_error(Some(format!("sending a frame to the viewer: {e}")));
        }
        let Some(store_id) = self.rec.store_info().map(|i| i.store_id) else {
            return;
        };
        let scene = &self.run.scene;
        let frame = WholeFrame {
            store_id,
            recording_id: self.info.recording_id.clone(),
            frame: scene.frame(),
            sim_time_ns: WholeFrame::nanos(scene.time()),
        };
        let hook = self.shown.lock().expect("not poisoned").follow.send(&frame);
        if let Some(hook) = hook {
            hook(&frame);
        }
    }

    /// The session moves the viewer's cursor from now on (Play, Step).
    pub(super) fn take_cursor(&self) {
        self.shown.lock().expect("not poisoned").follow.take();
    }
}
