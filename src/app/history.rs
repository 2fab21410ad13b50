//! What the debugger keeps of a run so that it can branch from any frame:
//! checkpoints, the tuning changes, and the simulated time of every frame.
//!
//! The solver is deterministic, so the state at frame `F` is the state of
//! the nearest checkpoint at or before `F`, stepped forward with the tuning
//! changes the run made in between. A checkpoint is a [`Snapshot`] (the
//! scene with its solver state, and the run's figures) taken every
//! [`EVERY`] frames. Memory is bounded: when more than [`MAX`] are kept,
//! every other one is dropped and the interval doubles, so the checkpoints
//! always cover the whole run with at most `MAX` copies of the scene, and
//! reaching any frame costs at most one interval of silent steps.
//!
//! A branch inherits its parent's history up to the branch frame: the two
//! runs are the same up to there.

use crate::app::session::SessionError;
use crate::record::Snapshot;
use crate::scene::Tuning;

/// Frames between checkpoints at the start of a run (half a second at 60 Hz).
pub const EVERY: u64 = 30;
/// Most checkpoints kept per run.
pub const MAX: usize = 64;

/// A run's checkpoints, tuning changes and frame times.
#[derive(Clone, Debug)]
pub struct History {
    every: u64,
    checkpoints: Vec<(u64, Snapshot)>,
    /// `(frame, tuning)`: the tuning the step producing `frame` first used.
    tunings: Vec<(u64, Tuning)>,
    /// Simulated time of each frame, from frame 0.
    times: Vec<f64>,
}

impl History {
    /// The history of a run that starts at `snapshot`'s frame with `tuning`.
    pub fn new(snapshot: Snapshot, tuning: Tuning) -> Self {
        let frame = snapshot.scene.frame();
        Self {
            every: EVERY,
            times: vec![snapshot.scene.time()],
            checkpoints: vec![(frame, snapshot)],
            tunings: vec![(frame, tuning)],
        }
    }

    /// Notes that the step producing `frame` uses `tuning` (a change is kept).
    pub fn tuning(&mut self, frame: u64, tuning: Tuning) {
        if self.tunings.last().map(|(_, t)| t) != Some(&tuning) {
            self.tunings.push((frame, tuning));
        }
    }

    /// Notes a frame stepped; `snapshot` is called when a checkpoint is due.
    pub fn stepped(&mut self, frame: u64, time: f64, snapshot: impl FnOnce() -> Snapshot) {
        if frame as usize == self.times.len() {
            self.times.push(time);
        }
        if frame.is_multiple_of(self.every) {
            self.checkpoints.push((frame, snapshot()));
            if self.checkpoints.len() > MAX {
                self.every *= 2;
                let every = self.every;
                let first = self.checkpoints[0].0;
                self.checkpoints
                    .retain(|(f, _)| *f == first || f.is_multiple_of(every));
            }
        }
    }

    /// The last frame known.
    pub fn last_frame(&self) -> u64 {
        self.times.len() as u64 - 1
    }

    /// The frame at simulated time `t` (the latest frame not after it).
    pub fn frame_at(&self, t: f64) -> u64 {
        let k = self.times.partition_point(|&x| x <= t + 1e-9);
        k.saturating_sub(1) as u64
    }

    /// How many checkpoints are kept, and their interval now.
    pub fn checkpoints(&self) -> (usize, u64) {
        (self.checkpoints.len(), self.every)
    }

    /// The run's state at `frame` (at most [`History::last_frame`]): the
    /// nearest checkpoint before it, stepped silently with the tuning
    /// changes of the run. Bit-identical to the run at that frame.
    pub fn state_at(&self, frame: u64) -> Result<Snapshot, SessionError> {
        let frame = frame.min(self.last_frame());
        let (start, snapshot) = self
            .checkpoints
            .iter()
            .rev()
            .find(|(f, _)| *f <= frame)
            .ok_or(SessionError::BeforeRun(frame))?;
        let mut s = snapshot.clone();
        for f in start + 1..=frame {
            for (_, t) in self.tunings.iter().filter(|(at, _)| *at == f) {
                s.scene
                    .set_tuning(t)
                    .map_err(|source| SessionError::Tuning { frame: f, source })?;
            }
            s.advance()
                .map_err(|source| SessionError::Step { frame: f, source })?;
        }
        Ok(s)
    }

    /// The history of a branch at `frame` (the part of this one up to it),
    /// continuing with `tuning`.
    pub fn branch(&self, frame: u64, tuning: Tuning) -> Self {
        let mut h = Self {
            every: self.every,
            checkpoints: self
                .checkpoints
                .iter()
                .filter(|(f, _)| *f <= frame)
                .cloned()
                .collect(),
            tunings: self
                .tunings
                .iter()
                .filter(|(f, _)| *f <= frame)
                .copied()
                .collect(),
            times: self.times[..=frame as usize].to_vec(),
        };
        h.tuning(frame + 1, tuning);
        h
    }
}
