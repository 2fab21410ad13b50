//! Self-collision: the cloth's two sides stay apart at its thickness.
//!
//! The contacts, their search and the crossings measure live in
//! [`solver::self_collision`](crate::solver::self_collision), which
//! explains the constraint; this family projects this substep's contacts
//! like every other constraint set, colour batch by colour batch, and
//! measures the penetration of the pairs closer than the thickness.

use super::{ConstraintFamily, Measure, Sets, Sweep, zero};
use super::violation::Violation;
use crate::solver::kernels::{Recorder, Shared, kernel, project_batches};
use crate::solver::self_collision::{self, for_each_close};
use crate::solver::team::Crew;

/// The self-collision family.
pub struct SelfCollision;

impl ConstraintFamily for SelfCollision {
    const NAME: &'static str = "self";
    const COLOR: [u8; 3] = [200, 90, 220];
    /// On: a cloth that passes through itself is what a person notices
    /// first, though the path check and the contacts are the dearest part
    /// of a step (see docs/method.md, §11b, "Limits, and the default").
    const DEFAULT_WEIGHT: f32 = 1.0;
    const TURNS: bool = false;
    /// The reference compliance `α_ref` (at `λ = ½`) of self-contacts, m/N:
    /// how far a pressed layer gives into the thickness (1 mm per newton at
    /// `λ = ½`; at `λ = 1`, nothing).
    const REFERENCE_COMPLIANCE: f32 = 1e-3;
    /// Its measure is a contact search.
    const MEASURED_ONLY_WHILE_ON: bool = true;

    type Multipliers = Vec<f32>;
    type Shared<'a> = Shared<'a, f32>;

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(mu, sets.contacts.len());
    }

    fn share(mu: &mut Self::Multipliers) -> Self::Shared<'_> {
        Shared::new(mu)
    }

    fn project<R: Recorder>(
        sweep: &Sweep,
        crew: &Crew,
        weight: f32,
        mu: &Self::Shared<'_>,
        rec: &mut R,
    ) {
        let (p, thickness) = (sweep.p, sweep.thickness);
        let k = sweep.compliance(Self::REFERENCE_COMPLIANCE, weight);
        let contacts = sweep.sets.contacts;
        project_batches(
            crew,
            &contacts.items,
            mu,
            &contacts.batches,
            rec,
            kernel!(|cs, ms, n, _| {
                for (&c, m) in cs.iter().zip(ms).take(n) {
                    self_collision::project(p, c, m, thickness, k);
                }
            }),
        );
    }

    fn violation(m: &Measure) -> Violation {
        let mut depths = Vec::new();
        for_each_close(&m.state.position, m.topology, m.spec, |_, _, d| {
            depths.push(d)
        });
        Violation::of(depths.into_iter())
    }

    fn each_violation(m: &Measure, _only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        // The contact search runs over the whole cloth whatever `only`.
        for_each_close(&m.state.position, m.topology, m.spec, |p, tri, d| {
            for i in [p, tri[0], tri[1], tri[2]] {
                put(i, d);
            }
        });
    }
}
