//! Self-collision: the cloth's two sides stay apart at its thickness, and no
//! edge passes through a triangle of its own cloth. docs/method.md §11b has
//! the argument; this is the part as the solver runs it, in one type,
//! `SelfCollision`, which owns all of its state.
//!
//! **The guarantee.** A cloth free of crossings at a substep's start (no
//! grid edge through a triangle it shares no particle with) is free of them
//! at its end. **Contacts** (`contact.rs`: a particle kept on its side of a
//! triangle at the thickness, projected with the other families in every
//! sweep) keep the layers apart but cannot promise it alone; the **path
//! check** does (`path/`): no pair of primitives sharing no particle may
//! close more than most of its distance along the substep's straight path,
//! so none reaches distance 0 on the way. A pair that would is parted, and
//! where that does not do, every particle is held within a fraction of its
//! distance to the nearest such primitive (the offset bounds).
//!
//! **The exceptions**, each where the code lets the cloth go unchecked
//! (the next step's start then looks for crossings, and any it finds are
//! tangles, left out until they come apart):
//! - *a driven or pulled particle beyond its bound*: it goes where its body
//!   or its pull takes it (`PathCheck::clamp`);
//! - *a layer squeezed by a collider*: the colliders have the last word
//!   (`SelfCollision::end_substep`);
//! - *the steps after a jerk*: a body that teleports its particles drags
//!   the cloth through itself; for `JERK_UNBOUNDED` steps nothing is
//!   bounded, and for `JERK_WATCH` steps, and then as long as any is
//!   found, tangles are left out (`SelfCollision::start_step`);
//! - *tangled particles*: left out of the contacts, the path check and the
//!   bounds, and moved so that the tangle shrinks (`untangle.rs`).
//!
//! **The stages**, in the order a step runs them (the solver calls them
//! from `step.rs` while the family's weight is above 0):
//!
//! | when | stage | what it does |
//! |---|---|---|
//! | step's start | `start_step` | watches for jerks, and for crossings unless the cloth is known free of them |
//! | substep's start | `start_substep` | moves tangled particles apart; starts the path check (near pairs, close edge pairs) |
//! | after the update | `after_update` | the path from the start checked; else bounded |
//! | before the sweeps | `find_contacts` | the substep's particle–triangle contacts, coloured |
//! | the sweeps | `families::self_collision` | the contacts projected, friction between layers |
//! | substep's end | `end_substep` | close edges pushed apart, the path checked again (bounded in rounds), the colliders' push checked |
//! | step's end | `tangles` | the crossings now (the diagnostics' count), which are the tangles |
//!
//! Files: `contact.rs` the contact and friction; `pick.rs` the contact
//! search (`SelfContacts`); `broad_phase.rs` the contacts' near pairs and
//! the crossing count's spatial hash; `prune.rs` boxes sorted along an
//! axis; `path/` the path check and the bounds (`PathCheck`); `tangles.rs`
//! the measures (penetration depths, crossings) and the tangles;
//! `untangle.rs` their pull apart. Every stage's result depends on the
//! positions alone, never on the threads.

pub(crate) mod broad_phase;
mod contact;
mod path;
mod pick;
mod prune;
mod tangles;
mod untangle;

use std::time::{Duration, Instant};

use glam::Vec3;

use crate::solver::cloth::ClothSpec;
use crate::solver::topology::Topology;
use contact::{Foot, Triangle, bounds, least};
use path::{EDGE_GAP, PathCheck};
use pick::{Layers, SelfContacts};
use untangle::{STEP, untangle};

pub use contact::SelfContact;
pub(crate) use contact::{apply_friction, project};
pub use tangles::{ON_PLANE, crossing_points, crossings, for_each_close};

/// What the stages read of the cloth that a step does not change.
#[derive(Clone, Copy)]
pub(crate) struct Grid<'a> {
    /// The grid's triangles and constraint sets.
    pub topology: &'a Topology,
    /// The cloth: its thickness and spacing.
    pub spec: &'a ClothSpec,
    /// Per particle: 0 for a driven one.
    pub inv_mass: &'a [f32],
}

impl Grid<'_> {
    fn triangles(&self) -> &[[u32; 3]] {
        &self.topology.triangles
    }

    /// The shorter rest spacing.
    fn spacing(&self) -> f32 {
        let (dx, dy) = self.spec.spacing();
        dx.min(dy)
    }
}

/// Self-collision: all of its state, and its stages (the module's table).
#[derive(Clone, Debug, Default)]
pub(crate) struct SelfCollision {
    /// This substep's contacts, and the tangles left alone.
    contacts: SelfContacts,
    /// The path check and its bounds.
    path: PathCheck,
    /// Substeps left that a jerk leaves unbounded.
    unbounded: u32,
    /// Scratch of the substep's end: where the sweeps took the particles,
    /// or the state the path was cleared to.
    target: Vec<Vec3>,
    /// Time spent in each stage since [`SelfCollision::take_time`], when
    /// timed.
    time: Option<StageTimes>,
}

/// Wall time spent in each of self-collision's stages (the module's
/// table), for the diagnostics: where its cost goes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Watching for jerks and crossings at a step's start.
    pub step_start: Duration,
    /// Untangling and the path check's start, at each substep's start.
    pub substep_start: Duration,
    /// The path checked (or bounded) after the update.
    pub after_update: Duration,
    /// The substep's contacts found.
    pub contacts: Duration,
    /// Edges pushed apart and the path checked again at the substep's end
    /// (the colliders' push not included).
    pub substep_end: Duration,
    /// The crossings (tangles) counted at a step's end.
    pub tangles: Duration,
}

impl StageTimes {
    /// Every stage with its lower-case name, in the order they run.
    pub fn iter(&self) -> [(&'static str, Duration); 6] {
        [
            ("step_start", self.step_start),
            ("substep_start", self.substep_start),
            ("after_update", self.after_update),
            ("contacts", self.contacts),
            ("substep_end", self.substep_end),
            ("tangles", self.tangles),
        ]
    }

    /// The time of every stage together.
    pub fn total(&self) -> Duration {
        self.iter().into_iter().map(|(_, t)| t).sum()
    }
}

impl SelfCollision {
    /// The contacts the sweeps project.
    pub(crate) fn contacts(&self) -> &crate::solver::topology::Batched<SelfContact> {
        &self.contacts.set
    }

    /// Off (the family's weight is 0): no contacts, and nothing known about
    /// crossings.
    pub(crate) fn off(&mut self) {
        self.contacts.clear();
        self.path.clear();
    }

    /// Times the stages from now on (`true`), or not.
    pub(crate) fn time_stages(&mut self, on: bool) {
        self.time = on.then(StageTimes::default);
    }

    /// The time spent in each stage since the last call.
    pub(crate) fn take_time(&mut self) -> StageTimes {
        self.time.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// Runs `f` on `self`, its time added to `stage`'s if the stages are
    /// timed.
    fn timed<T>(
        &mut self,
        stage: fn(&mut StageTimes) -> &mut Duration,
        f: impl FnOnce(&mut Self) -> T,
    ) -> T {
        let start = self.time.is_some().then(Instant::now);
        let out = f(self);
        if let (Some(time), Some(start)) = (self.time.as_mut(), start) {
            *stage(time) += start.elapsed();
        }
        out
    }

    /// **Step's start.** A jerk (an attachment's motion over this step
    /// differs from the last step's by more than [`JERK`] rest spacings,
    /// `motion_changes` being each attachment's difference: a teleport, not
    /// a car that brakes, whose motion changes by millimetres a step) leaves
    /// tangles alone for this step and the next [`JERK_WATCH`], and the
    /// particles unbounded for [`JERK_UNBOUNDED`]: the cloth it drags
    /// through itself comes apart instead of being held tangled. Otherwise
    /// crossings are looked for unless the cloth is known free of them, and
    /// any found are tangles, left alone until they come apart.
    pub(crate) fn start_step(
        &mut self,
        grid: Grid,
        x: &[Vec3],
        motion_changes: impl IntoIterator<Item = f64>,
        substeps: u32,
    ) {
        let limit = JERK as f64 * grid.spacing() as f64;
        if motion_changes.into_iter().any(|d| !d.le(&limit)) {
            self.contacts.watch_for_tangles((JERK_WATCH + 1) * substeps);
            self.unbounded = JERK_UNBOUNDED * substeps;
        }
        if self.contacts.watching() {
            // Tangled particles move freely: look again once they are apart.
            self.path.checked = false;
            return;
        }
        if self.path.checked {
            return;
        }
        let found = self.timed(
            |t| &mut t.step_start,
            |s| s.contacts.find_tangles(x, grid.triangles(), grid.spec),
        );
        let tangled = !found.is_empty();
        self.path.checked = !tangled;
        if tangled {
            self.contacts.watch_for_tangles(substeps);
        }
    }

    /// **Substep's start**, at `x`: the tangles left alone are moved apart
    /// (`untangle.rs`), then the path check starts (`PathCheck::begin`),
    /// unless a jerk leaves this substep unbounded.
    pub(crate) fn start_substep(&mut self, grid: Grid, x: &mut [Vec3]) {
        let start: fn(&mut StageTimes) -> &mut Duration = |t| &mut t.substep_start;
        if self.contacts.leave_tangles_this_substep() {
            self.timed(start, |s| {
                s.contacts.find_tangles(x, grid.triangles(), grid.spec);
                let step = STEP * grid.spacing();
                untangle(
                    x,
                    grid.inv_mass,
                    grid.triangles(),
                    &s.contacts.crossed,
                    step,
                );
            });
        }
        if self.unbounded > 0 {
            self.unbounded -= 1;
            self.path.clear();
            return;
        }
        self.timed(start, |s| {
            s.path
                .begin(x, grid.triangles(), grid.spec, s.contacts.tangled())
        });
    }

    /// **After the update**: the particles stay where the update took them
    /// if the path there forms no crossing; else they are bounded
    /// ([`SelfCollision::clamp_to_bounds`], one round). `pulled` is the
    /// particle a pull holds, if any.
    pub(crate) fn after_update(&mut self, grid: Grid, x: &mut [Vec3], pulled: Option<usize>) {
        self.timed(
            |t| &mut t.after_update,
            |s| s.clamp_to_bounds(grid, x, pulled, 1),
        );
    }

    /// **Before the sweeps**: this substep's contacts over the predicted
    /// positions `x` (`start` the substep's), within the thickness and
    /// [`SELF_CONTACT_SLACK`] rest spacings.
    pub(crate) fn find_contacts(&mut self, grid: Grid, x: &[Vec3], start: &[Vec3], threads: usize) {
        self.timed(
            |t| &mut t.contacts,
            |s| {
                let layers = Layers {
                    now: x,
                    start,
                    inv_mass: grid.inv_mass,
                };
                let reach = grid.spec.thickness + SELF_CONTACT_SLACK * grid.spacing();
                s.contacts
                    .build(&layers, grid.topology, grid.spec, reach, threads);
            },
        );
    }

    /// **Substep's end**, after the sweeps: the edge pairs found nearer
    /// than a fraction of the thickness at the substep's start are pushed
    /// apart; the path from the start is checked again, bounded in up to
    /// [`CLAMP_ROUNDS`] rounds ([`SelfCollision::clamp_to_bounds`]); then
    /// the colliders have the last word (`push` projects them, and says
    /// whether it moved a particle). Their push is a move the path check has
    /// not seen, so the path is checked again for the pairs of the particles
    /// it moved (`PathCheck::path_clear_after`), and while that parts
    /// particles the colliders push again, up to [`COLLIDER_ROUNDS`] times.
    /// A path still not clear after them (a layer squeezed between a
    /// collider and another layer) leaves the cloth unchecked.
    pub(crate) fn end_substep(
        &mut self,
        grid: Grid,
        x: &mut [Vec3],
        pulled: Option<usize>,
        mut push: impl FnMut(&mut [Vec3]) -> bool,
    ) {
        self.timed(
            |t| &mut t.substep_end,
            |s| {
                let gap = EDGE_GAP * grid.spec.thickness;
                s.path
                    .keep_edges_apart(x, grid.inv_mass, gap, s.contacts.tangled());
                s.clamp_to_bounds(grid, x, pulled, CLAMP_ROUNDS);
            },
        );
        let mut cleared = std::mem::take(&mut self.target);
        cleared.clear();
        cleared.extend_from_slice(x);
        if push(x) && !self.check_colliders_push(grid, x, &cleared, &mut push) {
            self.path.checked = false;
        }
        self.target = cleared;
    }

    /// **Step's end**, for the diagnostics: which particles
    /// are tangled at `x`, and where each (edge, triangle) pair crosses.
    pub(crate) fn tangles(&mut self, grid: Grid, x: &[Vec3]) -> Vec<Vec3> {
        self.timed(
            |t| &mut t.tangles,
            |s| s.contacts.find_tangles(x, grid.triangles(), grid.spec),
        )
    }

    /// Leaves the particles at `x` if the path there from the substep's
    /// start forms no crossing, parting the pairs that approach too fast
    /// (`PathCheck::path_clear`); else bounds every particle at the start and
    /// brings each within its bound. Where that moved a particle, the
    /// bounds are found again at the clamped state (free of crossings like
    /// the start) and the particles go on from there towards `x`, up to
    /// `rounds` times: a particle held back by a near layer catches up with
    /// the rest instead of stretching its edges. A pulled particle is parted
    /// by its mass like any other, but left where its pull took it.
    fn clamp_to_bounds(&mut self, grid: Grid, x: &mut [Vec3], pulled: Option<usize>, rounds: u32) {
        let (triangles, exempt) = (grid.triangles(), self.contacts.tangled());
        if self
            .path
            .path_clear(x, grid.inv_mass, triangles, grid.spec, exempt)
        {
            return;
        }
        self.path.find_at_start(triangles, grid.spec, exempt);
        if rounds > 1 {
            self.target.clear();
            self.target.extend_from_slice(x);
        }
        for round in 1..=rounds {
            let moved = self.path.clamp(x, grid.inv_mass, pulled);
            if moved == 0 || round == rounds {
                break;
            }
            let exempt = self.contacts.tangled();
            self.path.find(x, triangles, grid.spec, exempt);
            x.copy_from_slice(&self.target);
        }
    }

    /// [`SelfCollision::end_substep`]'s rounds after the colliders pushed a
    /// particle away from `cleared`: whether the path ends clear.
    fn check_colliders_push(
        &mut self,
        grid: Grid,
        x: &mut [Vec3],
        cleared: &[Vec3],
        push: &mut impl FnMut(&mut [Vec3]) -> bool,
    ) -> bool {
        for _ in 0..COLLIDER_ROUNDS {
            let clear = self.timed(
                |t| &mut t.substep_end,
                |s| {
                    let exempt = s.contacts.tangled();
                    s.path.path_clear_after(
                        x,
                        cleared,
                        grid.inv_mass,
                        grid.triangles(),
                        grid.spec,
                        exempt,
                    )
                },
            );
            // Nothing parted: the colliders' push is where it was left.
            if clear && !self.path.parted {
                return true;
            }
            if !push(x) {
                return clear;
            }
        }
        false
    }
}

/// How much farther than the thickness, in rest spacings, a particle and a
/// triangle may be at the predicted positions to be a self-contact of the
/// substep: room for the adjust phase's own corrections to bring them
/// together.
const SELF_CONTACT_SLACK: f32 = 0.25;

/// How much, in rest spacings, an attachment's motion may change from one
/// step to the next before self-collision leaves tangles alone
/// ([`SelfCollision::start_step`]).
const JERK: f32 = 2.0;

/// How many times a substep's end may be clamped to the bounds, finding
/// them again in between ([`SelfCollision::end_substep`]).
const CLAMP_ROUNDS: u32 = 6;

/// How many times a substep's end checks the path again after the
/// colliders pushed a particle ([`SelfCollision::end_substep`]).
const COLLIDER_ROUNDS: u32 = 3;

/// How many steps after a jerk self-collision leaves tangles alone.
const JERK_WATCH: u32 = 60;

/// How many steps, the jerk's included, the path check and its bounds are
/// lifted for: the free particles follow the jerked ones, and are checked
/// again (but for the tangled ones) while the tangles are undone.
const JERK_UNBOUNDED: u32 = 5;
