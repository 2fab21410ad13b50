//! The viewer's time cursor while the simulation plays: moved by the
//! session, to each frame once all its drawing has reached the viewer.
//!
//! The viewer takes in what it is sent a few milliseconds at a time, and
//! draws between two such turns: left to follow the stream on its own, its
//! cursor would stand at the newest time it holds, where part of a frame's
//! drawing may still be on its way (the mesh of one frame beside the
//! particles of the next). So while it plays, the session sends, after the
//! last message of each frame it draws, a command to put the cursor on
//! that frame ([`WholeFrame`], through the hook the window sets); the
//! viewer handles it in order, after the frame's drawing, so the view only
//! ever shows whole frames.
//!
//! The cursor is the user's again once they move it back (scrubbing, a
//! click in a plot): until the next Play, Step or run, the session sends no
//! more cursor commands.

use std::collections::VecDeque;
use std::sync::Arc;

use super::BranchAt;

/// A frame all of whose drawing has been sent: where to put the viewer's
/// time cursor.
#[derive(Clone, Debug, PartialEq)]
pub struct WholeFrame {
    /// The run's recording.
    pub store_id: rerun::StoreId,
    /// Its recording id.
    pub recording_id: String,
    /// The frame, on the `frame` timeline.
    pub frame: u64,
    /// Its simulated time on the `sim_time` timeline, in nanoseconds (as
    /// Rerun stores the time logged in seconds).
    pub sim_time_ns: i64,
}

impl WholeFrame {
    /// The time of `frame` logged at `time` seconds, as Rerun stores it.
    pub fn nanos(time: f64) -> i64 {
        std::time::Duration::try_from_secs_f64(time).map_or(0, |d| d.as_nanos() as i64)
    }

    /// Whether the cursor reported at `at` is at this frame.
    fn is_at(&self, at: BranchAt) -> bool {
        match at {
            BranchAt::Frame(f) => f == self.frame,
            BranchAt::Time(t) => (t * 1e9 - self.sim_time_ns as f64).abs() < 2.0,
        }
    }
}

/// What the window does with a [`WholeFrame`]: send the viewer a command,
/// in the same channel as the data, to put its cursor there.
pub type FrameHook = Arc<dyn Fn(&WholeFrame) + Send + Sync>;

/// The frames whose cursor commands are on their way, newest last: the
/// viewer reports each as the cursor gets there.
const IN_FLIGHT: usize = 256;

/// Whether the session moves the viewer's cursor, and where it put it.
#[derive(Default)]
pub(crate) struct Follow {
    /// The window's hook (none without a window).
    pub(crate) hook: Option<FrameHook>,
    /// Whether the cursor is the session's (from Play, Step or a new run
    /// until the user moves it back).
    on: bool,
    /// The frames sent lately.
    sent: VecDeque<WholeFrame>,
}

impl Follow {
    /// The session takes the cursor (Play, Step, a new run).
    pub(crate) fn take(&mut self) {
        self.on = true;
    }

    /// Notes `frame` as sent, if the cursor is the session's, and returns
    /// the hook to send it with (called by the caller once it has let go
    /// of the lock on this: the hook may wait for the viewer).
    pub(crate) fn send(&mut self, frame: &WholeFrame) -> Option<FrameHook> {
        let hook = self.hook.clone().filter(|_| self.on)?;
        if self.sent.len() == IN_FLIGHT {
            self.sent.pop_front();
        }
        self.sent.push_back(frame.clone());
        Some(hook)
    }

    /// The viewer reports its cursor at `at` on `recording`, `back` from
    /// where it last reported it there: a cursor moved back, to none of
    /// the frames sent, was moved by the user, who then has it. (The
    /// session's commands, and the viewer following the stream on its own
    /// before the first of them lands, only move it forward.)
    pub(crate) fn reported(&mut self, recording: &str, at: BranchAt, back: bool) {
        let ours = self
            .sent
            .iter()
            .any(|f| f.recording_id == recording && f.is_at(at));
        if back && !ours {
            self.on = false;
            self.sent.clear();
        }
    }

    /// Whether the session moves the cursor.
    pub(crate) fn is_on(&self) -> bool {
        self.on && self.hook.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    fn frame(f: u64) -> WholeFrame {
        WholeFrame {
            store_id: rerun::StoreId::random(rerun::StoreKind::Recording, "weft"),
            recording_id: "r".into(),
            frame: f,
            sim_time_ns: WholeFrame::nanos(f as f64 / 60.0),
        }
    }

    #[test]
    fn the_cursor_is_the_user_s_once_moved_back() {
        let shown = Arc::new(Mutex::new(Vec::new()));
        let s = shown.clone();
        let mut follow = Follow {
            hook: Some(Arc::new(move |f: &WholeFrame| {
                s.lock().unwrap().push(f.frame)
            })),
            ..Follow::default()
        };
        let show = |follow: &mut Follow, f: u64| {
            if let Some(hook) = follow.send(&frame(f)) {
                hook(&frame(f));
            }
        };
        show(&mut follow, 1);
        assert!(shown.lock().unwrap().is_empty(), "not taken yet");
        follow.take();
        for f in 2..6 {
            show(&mut follow, f);
        }
        // The viewer following on its own before the commands land, then
        // catching up, back to a frame sent: still the session's.
        follow.reported("r", BranchAt::Frame(1), false);
        follow.reported("r", BranchAt::Time(3.0 / 60.0), false);
        follow.reported("r", BranchAt::Frame(7), false);
        follow.reported("r", BranchAt::Frame(4), true);
        follow.reported("other", BranchAt::Frame(0), false);
        assert!(follow.is_on());
        // Scrubbed back between frames: the user's.
        follow.reported("r", BranchAt::Time(2.5 / 60.0), true);
        assert!(!follow.is_on());
        show(&mut follow, 6);
        assert_eq!(*shown.lock().unwrap(), vec![2, 3, 4, 5]);
        follow.take();
        show(&mut follow, 7);
        assert_eq!(shown.lock().unwrap().last(), Some(&7));
    }
}
