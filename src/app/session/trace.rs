//! A run's cloth, frame by frame: its world positions, kept so that a
//! branch can draw its parent as a ghost beside its own cloth
//! ([`crate::telemetry::ghost`]).
//!
//! Memory stays bounded, as the checkpoints' does: a trace keeps at most
//! [`BUDGET`] bytes of positions; past that, every other frame is dropped
//! and the interval between kept frames doubles, so the trace still covers
//! the whole run. `flag_on_car` (384 particles, 4.6 kB a frame) keeps every
//! frame for its first 7000 frames (about two minutes simulated).

use glam::Vec3;

/// The most bytes of positions a trace keeps.
pub const BUDGET: usize = 32 << 20;

/// A run's world positions at every `every`-th frame.
#[derive(Clone, Debug)]
pub struct Trace {
    /// Frame, simulated time and world positions, by ascending frame.
    frames: Vec<(u64, f64, Vec<Vec3>)>,
    /// The interval between kept frames.
    every: u64,
    /// Bytes of positions kept.
    bytes: usize,
}

impl Default for Trace {
    fn default() -> Self {
        Self {
            frames: Vec::new(),
            every: 1,
            bytes: 0,
        }
    }
}

impl Trace {
    /// Keeps the positions at `frame` (simulated time `time`), if the
    /// interval keeps that frame; a frame at or before the last kept one
    /// (a run starts over only as a new trace) is ignored.
    pub fn push(&mut self, frame: u64, time: f64, positions: &[Vec3]) {
        if !frame.is_multiple_of(self.every)
            || self.frames.last().is_some_and(|(f, _, _)| *f >= frame)
        {
            return;
        }
        self.bytes += std::mem::size_of_val(positions);
        self.frames.push((frame, time, positions.to_vec()));
        while self.bytes > BUDGET && self.frames.len() > 1 {
            self.every *= 2;
            let every = self.every;
            self.frames.retain(|(f, _, _)| f.is_multiple_of(every));
            self.bytes = self
                .frames
                .iter()
                .map(|(_, _, x)| std::mem::size_of_val(&x[..]))
                .sum();
        }
    }

    /// The positions shown at `frame`: those of the last kept frame at or
    /// before it, if that is less than one interval before it (else the
    /// run never reached `frame`).
    pub fn at(&self, frame: u64) -> Option<&[Vec3]> {
        let k = self.frames.partition_point(|(f, _, _)| *f <= frame);
        let (f, _, x) = self.frames.get(k.checked_sub(1)?)?;
        (frame - f < self.every).then_some(&x[..])
    }

    /// Drops the frames after `frame` (a branch keeps its parent's up to
    /// the frame it starts from).
    pub fn truncate_after(&mut self, frame: u64) {
        let k = self.frames.partition_point(|(f, _, _)| *f <= frame);
        for (_, _, x) in self.frames.drain(k..) {
            self.bytes -= std::mem::size_of_val(&x[..]);
        }
    }

    /// Frames kept, and the interval between them.
    pub fn kept(&self) -> (usize, u64) {
        (self.frames.len(), self.every)
    }

    /// The last frame kept.
    pub fn last_frame(&self) -> Option<u64> {
        self.frames.last().map(|(f, _, _)| *f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloth(n: usize, v: f32) -> Vec<Vec3> {
        vec![Vec3::splat(v); n]
    }

    #[test]
    fn a_frame_reads_back_until_the_next_is_due() {
        let mut t = Trace::default();
        for f in 0..5 {
            t.push(f, f as f64 * 0.1, &cloth(3, f as f32));
        }
        assert_eq!(t.at(3), Some(&cloth(3, 3.0)[..]));
        assert_eq!(t.at(4), Some(&cloth(3, 4.0)[..]));
        // Never reached.
        assert_eq!(t.at(5), None);
        // Pushed again, or out of order: ignored.
        t.push(2, 0.2, &cloth(3, 9.0));
        assert_eq!(t.at(2), Some(&cloth(3, 2.0)[..]));
    }

    #[test]
    fn over_budget_every_other_frame_goes_and_the_run_stays_covered() {
        // A cloth of a quarter of the budget: five frames do not fit.
        let n = BUDGET / 4 / std::mem::size_of::<Vec3>();
        let mut t = Trace::default();
        for f in 0..5 {
            t.push(f, 0.0, &cloth(n, f as f32));
        }
        assert_eq!(t.kept(), (3, 2), "frames 0, 2 and 4 kept");
        assert_eq!(t.at(1).map(|x| x[0].x), Some(0.0), "frame 0 shown at 1");
        assert_eq!(t.at(4).map(|x| x[0].x), Some(4.0));
        assert_eq!(t.at(6), None);
        // An odd frame is not kept any more.
        t.push(5, 0.0, &cloth(n, 5.0));
        assert_eq!(t.kept(), (3, 2));
    }

    #[test]
    fn a_branch_keeps_its_parent_s_frames_up_to_its_own() {
        let mut t = Trace::default();
        for f in 0..10 {
            t.push(f, 0.0, &cloth(2, f as f32));
        }
        let parent = t.clone();
        t.truncate_after(6);
        assert_eq!(t.last_frame(), Some(6));
        assert_eq!(t.at(7), None);
        t.push(7, 0.0, &cloth(2, -7.0));
        assert_eq!(t.at(7), Some(&cloth(2, -7.0)[..]));
        assert_eq!(parent.at(7), Some(&cloth(2, 7.0)[..]));
        assert_eq!(t.bytes, 8 * 2 * 12);
    }
}
