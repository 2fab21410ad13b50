//! The adjust phase of one substep (§3.3–3.4): `iterations` sweeps over the
//! constraint families in [`Family::ALL`] order (each as many
//! [`passes`](Family::passes) as it asks for), each sweep followed by the
//! colliders, all in one parallel region ([`super::team`]).
//!
//! Every thread of the crew walks the same sequence: for each family, each
//! of its constraint sets, each colour batch, it projects the blocks of the
//! batch it claims as it comes free and waits at a barrier; then it pushes its share of the particles
//! out of the colliders (each particle on its own, colliders in index
//! order) and waits again. Because no two constraints of a colour share a
//! free particle, and a particle's collider pass reads only that particle,
//! the state after the phase is the same bit for bit for any number of
//! threads, and the same as one thread walking the sequence alone.
//!
//! Thread 0 times the families and the colliders for the diagnostics: the
//! time from the end of one section to the end of the next, barriers
//! included, which is the wall time the section costs the step.
//!
//! With self-contacts, friction between layers runs once, before the last
//! sweep (after the only one), on thread 0 while the others wait: the
//! contacts' pushes so far bound it, and the sweep after it mends what
//! holding a particle back does to its edges ([`LayerFriction`]).
//!
//! In the step's last phase, with corrections asked for, every thread also
//! credits each family's sweep (stretch's consecutive passes once, after
//! the last) with what it did to the thread's share of the particles
//! ([`Tracking`]), and waits for the crew before the next.

use std::time::{Duration, Instant};

use glam::Vec3;

use super::collision::{self, Collider, Contact, Pose};
use super::diagnostics::{CorrectionTrack, Diagnostics, LargestTurn, Tracking};
use super::families::{Family, PerFamily, SharedMultipliers, Sweep};
use super::kernels::{NoRecord, Recorder, Shared};
use super::self_collision::{self, SelfContact};
use super::team::{self, Crew};

/// Everything one adjust phase reads and writes.
pub(crate) struct Adjust<'a> {
    /// The constraints, the state, the compliances and Eq. 3.
    pub sweep: Sweep<'a>,
    /// Every constraint's multiplier over the substep.
    pub mu: SharedMultipliers<'a>,
    /// Sweeps in the phase.
    pub iterations: u32,
    /// The colliders, if there are any.
    pub colliders: Option<Colliders<'a>>,
    /// Friction between layers, if it is on and there are self-contacts.
    pub friction: Option<LayerFriction<'a>>,
}

/// Friction between layers (`self_collision::apply_friction`): the
/// self-contacts, each particle at the substep's start, and `μ`.
pub(crate) struct LayerFriction<'a> {
    pub contacts: &'a [SelfContact],
    pub start: &'a [Vec3],
    pub friction: f32,
}

/// The colliders at the substep's end, and each particle's deepest contact.
pub(crate) struct Colliders<'a> {
    pub shapes: &'a [Collider],
    pub poses: &'a [Pose],
    /// Distance kept from a collider's surface.
    pub margin: f32,
    pub contacts: Shared<'a, Contact>,
}

/// Wall time of each part of the phase, as thread 0 saw it.
#[derive(Debug, Default)]
struct Times {
    families: PerFamily<Duration>,
    collisions: Duration,
}

impl Adjust<'_> {
    /// Runs the phase on up to `threads` threads, with `diagnostics` when
    /// they are on: every family's time and the colliders', the largest
    /// forced rotations if corrections are asked for, and, given a `track`
    /// (the step's last phase), each particle's corrections.
    pub(crate) fn run(
        &self,
        threads: usize,
        diagnostics: Option<&mut Diagnostics>,
        track: Option<&mut CorrectionTrack>,
    ) {
        let Some(d) = diagnostics else {
            self.run_recorded(threads, &mut PerFamily::splat(NoRecord), false, None);
            return;
        };
        let times = if d.corrections {
            let mut recs = PerFamily::splat(LargestTurn::default());
            let times = {
                let tracking = track.map(|t| t.begin(self.sweep.p, &mut d.families));
                self.run_recorded(threads, &mut recs, true, tracking.as_ref())
            };
            for (fd, rec) in d.families.iter_mut().zip(recs) {
                fd.max_rotation = fd.max_rotation.max(rec.radians());
            }
            times
        } else {
            self.run_recorded(threads, &mut PerFamily::splat(NoRecord), true, None)
        };
        for (fd, t) in d.families.iter_mut().zip(times.families) {
            fd.time += t;
        }
        d.timings.collisions += times.collisions;
    }

    /// Runs the phase on up to `threads` threads. Each thread records into a
    /// fork of `recorders` (one per family), which are joined back, and
    /// credits its share of the particles' corrections to `tracking`; with
    /// `timed`, thread 0 returns the [`Times`].
    fn run_recorded<R: Recorder>(
        &self,
        threads: usize,
        recorders: &mut PerFamily<R>,
        timed: bool,
        tracking: Option<&Tracking>,
    ) -> Times {
        let p = self.sweep.p;
        let forks = team::run(threads, |crew| {
            let mut recs = recorders.map(|_, r| r.fork());
            let mut clock = (timed && crew.index() == 0).then(Clock::new);
            for sweep in 0..self.iterations {
                if self.iterations > 1 && sweep + 1 == self.iterations {
                    self.hold_layers(crew, tracking, clock.as_mut());
                }
                for family in Family::ALL {
                    // Families with weight 0 are skipped.
                    if self.sweep.weights[family] == 0.0 {
                        continue;
                    }
                    for _ in 0..family.passes() {
                        self.sweep
                            .project(crew, family, &self.mu, &mut recs[family]);
                    }
                    // A family's passes are credited once, after the last.
                    if let Some(t) = tracking {
                        t.credit(crew, family, p);
                    }
                    if let Some(c) = clock.as_mut() {
                        let t = c.lap();
                        c.times.families[family] += t;
                    }
                }
                if let Some(colliders) = &self.colliders {
                    self.collide(crew, colliders, tracking);
                    if let Some(c) = clock.as_mut() {
                        let t = c.lap();
                        c.times.collisions += t;
                    }
                }
            }
            if self.iterations == 1 {
                self.hold_layers(crew, tracking, clock.as_mut());
            }
            if let Some(t) = tracking {
                t.finish(crew);
            }
            (recs, clock.map(|c| c.times))
        });
        let mut times = Times::default();
        for (recs, t) in forks {
            for (mine, theirs) in recorders.iter_mut().zip(recs) {
                mine.join(theirs);
            }
            if let Some(t) = t {
                times = t;
            }
        }
        times
    }

    /// Friction between layers, on thread 0 in contact order while the
    /// others wait (a move `tracking` credits to no family; `clock` times
    /// it with self-collision).
    fn hold_layers(&self, crew: &Crew, tracking: Option<&Tracking>, clock: Option<&mut Clock>) {
        let Some(f) = &self.friction else {
            return;
        };
        let p = self.sweep.p;
        if crew.index() == 0 {
            let mu = self.mu.self_contacts();
            // SAFETY: the other threads wait at the barrier below, touching
            // neither the positions nor the multipliers until then.
            let (x, mu) = unsafe { (p.x.slice(0..p.inv_mass.len()), mu.slice(0..mu.len())) };
            self_collision::apply_friction(x, f.start, p.inv_mass, f.contacts, mu, f.friction);
        }
        crew.barrier();
        if let Some(t) = tracking {
            t.skip(crew, p);
        }
        crew.barrier();
        if let Some(c) = clock {
            let t = c.lap();
            c.times.families[Family::SelfCollision] += t;
        }
    }

    /// Pushes this thread's share of the particles out of every collider
    /// (a move `tracking` credits to no family).
    fn collide(&self, crew: &Crew, c: &Colliders, tracking: Option<&Tracking>) {
        let p = self.sweep.p;
        let mine = crew.share(p.inv_mass.len());
        // SAFETY: shares are disjoint, and a particle's collider pass reads
        // and writes only that particle's position and contact.
        let (x, contacts) = unsafe { (p.x.slice(mine.clone()), c.contacts.slice(mine.clone())) };
        collision::project(x, &p.inv_mass[mine], c.shapes, c.poses, c.margin, contacts);
        if let Some(t) = tracking {
            t.skip(crew, p);
        }
        crew.barrier();
    }
}

/// Thread 0's stopwatch.
struct Clock {
    last: Instant,
    times: Times,
}

impl Clock {
    fn new() -> Self {
        Self {
            last: Instant::now(),
            times: Times::default(),
        }
    }

    /// Time since the last lap.
    fn lap(&mut self) -> Duration {
        let now = Instant::now();
        let t = now - self.last;
        self.last = now;
        t
    }
}
