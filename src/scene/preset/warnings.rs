//! What is valid but probably not meant: [`Preset::warnings`], such as a
//! grid so large that every frame, the first one included, takes seconds to
//! minutes. `load` returns them with the preset; the command line prints
//! them to standard error.

use super::Preset;

/// Rough cost of one particle through one substep's update, or through one
/// sweep of every family, in seconds: measured at 512 × 512 (`weft record
/// hanging_sheet --set cloth.weft=512 --set cloth.warp=512`, this machine's
/// 2 cores, dev profile), rounded up.
const SECONDS_PER_PARTICLE_PASS: f64 = 5e-7;
/// A frame estimated to take longer than this gets a warning, in seconds
/// (the shipped presets take milliseconds).
const SLOW_FRAME: f64 = 0.5;

impl Preset {
    /// What is valid but probably not meant: a grid so large that each frame
    /// takes seconds, with an estimate of the cost.
    pub fn warnings(&self) -> Vec<String> {
        let (c, s) = (&self.cloth, &self.solver);
        let particles = c.weft as f64 * c.warp as f64;
        let passes = s.substeps as f64 * (1.0 + s.iterations as f64);
        let frame = particles * passes * SECONDS_PER_PARTICLE_PASS;
        if frame < SLOW_FRAME {
            return Vec::new();
        }
        let frames = (self.duration as f64 / s.dt as f64).ceil();
        vec![format!(
            "a {} × {} cloth ({particles} particles) with {} substeps × {} iterations is far larger than the shipped presets (at most 32 × 32): expect roughly {} per frame, the first one included, and {} for the {} s duration",
            c.weft,
            c.warp,
            s.substeps,
            s.iterations,
            seconds(frame),
            seconds(frame * frames),
            self.duration,
        )]
    }
}

/// A duration for a person: `0.8 s`, `40 s`, `12 min`, `3.5 h`.
fn seconds(t: f64) -> String {
    if t < 10.0 {
        format!("{t:.1} s")
    } else if t < 120.0 {
        format!("{t:.0} s")
    } else if t < 7200.0 {
        format!("{:.0} min", t / 60.0)
    } else {
        format!("{:.1} h", t / 3600.0)
    }
}
