//! A run's life: starting one (from frame 0, or as a branch of the current
//! run at a frame), and ending it (its summary and result properties, and
//! the recording file closed).

use rerun::sink::FileSink;

use super::Worker;
use crate::app::session::runs::{Start, open};
use crate::app::session::trace::Trace;
use crate::app::session::{BranchAt, RunInfo, SessionError, verdict_text};
use crate::record::verdict;
use crate::scene::{Loaded, load};

impl Worker {
    /// The loaded preset with the current tuning and telemetry settings.
    pub(super) fn current_loaded(&self) -> Loaded {
        let tuning = self.run.scene.tuning();
        let mut loaded = self.loaded.clone();
        tuning.apply_to(&mut loaded.preset);
        loaded.preset.telemetry = *self.run.telemetry.settings();
        loaded.resolved = load::to_toml(&loaded.preset);
        loaded
    }

    pub(super) fn branch(&mut self, at: BranchAt) {
        let last = self.history.last_frame();
        let frame = match at {
            BranchAt::Frame(f) => f,
            BranchAt::Time(t) => self.history.frame_at(t),
        };
        if frame > last {
            return self.set_error(Some(format!(
                "cannot branch at frame {frame}: run #{} has reached frame {last}",
                self.info.number
            )));
        }
        let tuning = self.run.scene.tuning();
        match self.history.state_at(frame) {
            Ok(snapshot) => {
                let history = self.history.branch(frame, tuning);
                let parent_series = self.series.clone();
                let parent_trace = self.trace.clone();
                self.playing = false;
                if self.begin(
                    Start::Branch {
                        snapshot: Box::new(snapshot),
                        history: Box::new(history),
                        tuning,
                        parent_series,
                    },
                    None,
                ) {
                    // The two runs are the same up to the branch frame.
                    self.series.retain(|(f, _, _)| *f <= frame);
                    self.trace.truncate_after(frame);
                    self.start_ghost(parent_trace);
                }
            }
            Err(e) => self.set_error(Some(format!("cannot branch at frame {frame}: {e}"))),
        }
    }

    /// Ends the current run and starts a new one; false if it could not.
    pub(super) fn begin(&mut self, start: Start, file: Option<FileSink>) -> bool {
        let number = self.runs.len() as u32 + 1;
        let parent = match &start {
            Start::Branch { snapshot, .. } => Some((
                self.info.number,
                self.info.recording_id.clone(),
                snapshot.scene.frame(),
            )),
            Start::Fresh(_) => None,
        };
        let info = RunInfo {
            number,
            parent,
            ..RunInfo::default()
        };
        let settings = *self.run.telemetry.settings();
        let arrows = self.run.telemetry.arrows();
        // The base a run's name is described against: the preset as named.
        let base = load::load(&self.name, &[]).ok().map(|l| l.preset);
        match open(&self.forward, start, &self.name, info, settings, base, file) {
            Ok(opened) => {
                // A new run starts with a clean status; what goes wrong in
                // closing the old one still shows.
                self.set_error(None);
                self.finish();
                self.stop_recording();
                if opened.info.parent.is_none() {
                    self.series.clear();
                    self.trace = Trace::default();
                }
                self.ghost = None;
                self.tee = opened.tee;
                // The speed readouts are the new run's.
                self.recent.clear();
                self.status.lock().expect("not poisoned").step_ms = 0.0;
                let old = std::mem::replace(&mut self.rec, opened.rec);
                let flushed = old.flush_blocking();
                self.run = opened.run;
                self.run.telemetry.set_arrows(arrows);
                self.diagnose();
                self.history = opened.history;
                self.trail.clear();
                self.info = opened.info.clone();
                self.runs.push(opened.info);
                self.keep_frame();
                if let Err(e) = flushed {
                    self.set_error(Some(format!("the previous run: {e}")));
                }
                true
            }
            Err(e) => {
                self.set_error(Some(e.to_string()));
                false
            }
        }
    }

    /// Logs the run's summary and its result properties, and flushes; a
    /// failure shows in the status.
    pub(super) fn finish(&mut self) {
        if let Err(e) = self.end_run() {
            self.set_error(Some(format!("ending the run: {e}")));
        }
    }

    pub(super) fn end_run(&mut self) -> Result<(), SessionError> {
        let figures = self.run.log_summary()?;
        let checks = verdict(self.run.scene.preset().expect.as_ref(), &figures);
        self.rec.send_property(
            "result",
            &rerun::AnyValues::default()
                .with_component::<rerun::components::Text>("frames", [figures.frames.to_string()])
                .with_component::<rerun::components::Text>(
                    "final_state",
                    [figures.final_state.clone()],
                )
                .with_component::<rerun::components::Text>("verdict", [verdict_text(&checks)]),
        )?;
        Ok(self.rec.flush_blocking()?)
    }

    /// Closes the recording file, if there is one.
    pub(super) fn stop_recording(&mut self) {
        if let Err(e) = self.tee.stop() {
            self.set_error(Some(e.to_string()));
        }
        self.recording = None;
    }
}
