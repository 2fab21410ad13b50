//! What the simulation thread tells the window: the [`Status`] it
//! publishes after every command and step (under one lock, so that a
//! reader never sees a new run with an old frame), and the waker that has
//! the window redraw.

use crate::record::{Check, verdict};
use crate::scene::Scene;
use crate::solver::{Family, PerFamily};

use super::Worker;
use crate::app::pull::Pulled;
use crate::app::session::{ParticleReadout, Status};

impl Worker {
    pub(super) fn set_error(&self, e: Option<String>) {
        self.status.lock().expect("not poisoned").error = e;
        self.wake();
    }

    /// Tells the window that the status changed.
    pub(super) fn wake(&self) {
        let waker = self.waker.lock().expect("not poisoned").clone();
        if let Some(waker) = waker {
            waker();
        }
    }

    /// Publishes everything, the preset included (after a command).
    pub(super) fn publish(&self) {
        let mut preset = self.run.scene.preset().clone();
        preset.telemetry = *self.run.telemetry.settings();
        let progress = self.progress();
        // One lock, so a reader never sees a new run with an old frame.
        let mut s = self.status.lock().expect("not poisoned");
        s.preset_name = self.name.clone();
        s.preset = Some(preset);
        s.run = self.info.clone();
        s.runs = self.runs.clone();
        s.recording = self.recording.clone();
        s.picked = self.picked;
        progress.write(&mut s);
        drop(s);
        self.wake();
    }

    /// Publishes what a step changes (the preset does not change on a step).
    pub(super) fn publish_progress(&self) {
        let progress = self.progress();
        progress.write(&mut self.status.lock().expect("not poisoned"));
        self.wake();
    }

    fn progress(&self) -> Progress {
        let scene = &self.run.scene;
        let figures = self.run.figures();
        let checks = verdict(scene.preset().expect.as_ref(), &figures);
        Progress {
            frame: scene.frame(),
            time: scene.time(),
            playing: self.playing,
            speed: self.speed,
            steps_per_second: self.recent.len() as f32,
            violations: scene.solver().diagnostics().map(|d| {
                let crossings = d.self_crossings.unwrap_or(0);
                (
                    d.families.map(|_, f| f.violation.max),
                    d.max_strain,
                    crossings,
                )
            }),
            digest: figures.final_state,
            checks,
            checkpoints: self.history.checkpoints(),
            particle: self.inspect.map(|i| readout(scene, i)),
            pull: Pulled::of(scene),
        }
    }
}

/// What a step changes in the [`Status`], gathered before taking its lock.
struct Progress {
    frame: u64,
    time: f64,
    playing: bool,
    speed: f32,
    steps_per_second: f32,
    violations: Option<(PerFamily<f32>, f32, usize)>,
    digest: String,
    checks: Vec<Check>,
    checkpoints: (usize, u64),
    particle: Option<ParticleReadout>,
    pull: Option<Pulled>,
}

impl Progress {
    fn write(self, s: &mut Status) {
        s.frame = self.frame;
        s.time = self.time;
        s.playing = self.playing;
        s.speed = self.speed;
        s.steps_per_second = self.steps_per_second;
        if let Some((max_violation, max_strain, crossings)) = self.violations {
            s.max_violation = max_violation;
            s.max_strain = max_strain;
            s.crossings = crossings;
        }
        s.digest = self.digest;
        s.checks = self.checks;
        s.checkpoints = self.checkpoints;
        s.particle = self.particle;
        s.pull = self.pull;
    }
}

/// What the inspector shows of particle `i`.
fn readout(scene: &Scene, i: usize) -> ParticleReadout {
    let solver = scene.solver();
    let mut r = ParticleReadout {
        index: i,
        cell: solver.spec().cell(i),
        strain: solver.particle_strain_at(i),
        normal_offset: solver.normal_offset_at(i),
        ..ParticleReadout::default()
    };
    let corrections = solver.diagnostics().filter(|d| d.corrections);
    r.corrections = corrections.is_some();
    for f in Family::ALL {
        r.violation[f] = solver.particle_violation_at(f, i);
        if let Some(d) = corrections {
            r.dx[f] = d.family(f).dx[i];
            r.dtheta[f] = d.family(f).dtheta[i];
        }
    }
    r
}
