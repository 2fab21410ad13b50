//! What is valid but probably not meant: [`Preset::warnings`], such as a
//! grid so large that every frame, the first one included, takes seconds to
//! minutes. `load` returns them with the preset; the command line prints
//! them to standard error.

use super::Preset;
use crate::solver::Family;

/// Self-collision keeps layers a thickness apart: over half the grid's
/// spacing it holds folds open wider than the grid can bend.
const MAX_THICKNESS_PER_SPACING: f32 = 0.5;
/// Under 1 % of the spacing the layers lie within rounding of each other.
const MIN_THICKNESS_PER_SPACING: f32 = 0.01;

/// Rough cost of one particle through one substep's update, or through one
/// sweep of every family, in seconds: measured at 512 × 512 (`weft record
/// hanging_sheet --set cloth.weft=512 --set cloth.warp=512`, this machine's
/// 2 cores, dev profile), rounded up.
const SECONDS_PER_PARTICLE_PASS: f64 = 5e-7;
/// Rough cost of self-collision (the path check, its list, the contacts and
/// their measures) per particle and substep, in seconds, with a thickness
/// the grid can fold: measured at 128 × 128 and 256 × 256 (`weft record
/// hanging_sheet --set cloth.weft=256 --set cloth.warp=256 --set
/// cloth.thickness=0.001`, with `solver.weights.self` 1 and 0, 2 cores, dev
/// profile: 1.0 and 1.7 µs), rounded up.
const SELF_SECONDS_PER_PARTICLE_SUBSTEP: f64 = 2e-6;
/// A frame estimated to take longer than this gets a warning, in seconds
/// (the shipped presets take milliseconds).
const SLOW_FRAME: f64 = 0.5;

impl Preset {
    /// What is valid but probably not meant: a grid so large that each frame
    /// takes seconds, with an estimate of the cost; a thickness that
    /// self-collision cannot keep at the grid's spacing, with one it can.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        out.extend(self.slow_frame());
        out.extend(self.unfit_thickness());
        out
    }

    /// A thickness self-collision cannot keep at this grid's spacing.
    fn unfit_thickness(&self) -> Option<String> {
        let c = &self.cloth;
        if self.solver.weights[Family::SelfCollision] == 0.0 {
            return None;
        }
        let spacing = c.spec().spacing();
        let spacing = spacing.0.min(spacing.1);
        let (lo, hi) = (
            MIN_THICKNESS_PER_SPACING * spacing,
            MAX_THICKNESS_PER_SPACING * spacing,
        );
        if c.thickness > hi {
            Some(format!(
                "cloth.thickness = {} m is more than half the grid's spacing ({spacing:.4} m): self-collision then holds every fold at least that far open, wider than the grid can bend, so the cloth folds as if stiff, and keeps every particle in contact with its neighbours' triangles, which makes each step many times dearer; use a thickness up to {hi:.4} m, or a finer grid",
                c.thickness
            ))
        } else if c.thickness < lo {
            Some(format!(
                "cloth.thickness = {} m is under 1 % of the grid's spacing ({spacing:.4} m): self-collision would keep the layers closer than a substep's rounding can tell apart, and a particle left on the other layer's face has no side to keep; use a thickness of at least {lo:.5} m, or turn self-collision off (solver.weights.self = 0)",
                c.thickness
            ))
        } else {
            None
        }
    }

    /// A grid so large that each frame takes seconds.
    fn slow_frame(&self) -> Option<String> {
        let (c, s) = (&self.cloth, &self.solver);
        let particles = c.weft as f64 * c.warp as f64;
        let passes = s.substeps as f64 * (1.0 + s.iterations as f64);
        let self_on = s.weights[Family::SelfCollision] > 0.0;
        let contacts = if self_on {
            particles * s.substeps as f64 * SELF_SECONDS_PER_PARTICLE_SUBSTEP
        } else {
            0.0
        };
        let frame = particles * passes * SECONDS_PER_PARTICLE_PASS + contacts;
        if frame < SLOW_FRAME {
            return None;
        }
        let frames = (self.duration as f64 / s.dt as f64).ceil();
        let advice = if self_on {
            format!(
                "; self-collision is {} of that (solver.weights.self = 0 turns it off where the layers never meet)",
                seconds(contacts)
            )
        } else {
            String::new()
        };
        Some(format!(
            "a {} × {} cloth ({particles} particles) with {} substeps × {} iterations is far larger than the shipped presets (at most 32 × 32): expect roughly {} per frame, the first one included, and {} for the {} s duration{advice}",
            c.weft,
            c.warp,
            s.substeps,
            s.iterations,
            seconds(frame),
            seconds(frame * frames),
            self.duration,
        ))
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
