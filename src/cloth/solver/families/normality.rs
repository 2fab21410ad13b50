//! Normality: the normals of neighbours agree (co-normality), and the cloth
//! resists in-plane shear.
//!
//! The paper prints `δθ = λ (n_a × n_b)`: turn each normal about
//! `n_a × n_b` toward the other. The violation is the angle
//! `C = ∠(n_a, n_b)` on every weft and warp edge, with rotational gradients
//! `∓ (n_a × n_b) / |n_a × n_b|`; positions do not move. Each turn is shaped
//! by Eq. 3. The violation reported is the angle, in radians.
//!
//! The paper pairs normality with shear ("normality & shear"), and so does
//! weft: the same weight sets the stiffness of the cell diagonals, soft
//! distance constraints (`stretch::project`) that let the weave
//! shear the way cloth does instead of holding it square like a board.
//!
//! Two normals pointing exactly apart have `n_a × n_b = 0`, which would make
//! a flipped element a fixed point; there the turn is about the axis
//! `n_a × ŝ` (any axis across `n_a` flips it back), by the full angle `π`.

use glam::Vec3;

use super::{ConstraintFamily, Measure, Sets, Sweep, each_pair, measure::tally, stretch, zero};
use super::violation::Violation;
use crate::solver::kernels::lanes::{self, Chunk, Lane};
use crate::solver::kernels::{Particles, Recorder, Shared, kernel, project_batches};
use crate::solver::team::Crew;
use crate::solver::{forced_rotation::ForcedRotation, topology::Pair};

/// The normality family: neighbouring normals agree, and the cells resist
/// shear.
pub struct Normality;

/// The reference compliance of the cell diagonals (shear), m/N: the
/// inverse of the in-plane shear stiffness `G·t` (2 N/m at `λ = ½`).
pub const SHEAR_REFERENCE_COMPLIANCE: f32 = 0.5;

impl ConstraintFamily for Normality {
    const NAME: &'static str = "normality";
    const COLOR: [u8; 3] = [120, 200, 90];
    const DEFAULT_WEIGHT: f32 = 0.2;
    const TURNS: bool = true;
    /// The reference compliance `α_ref` (at `λ = ½`, for a square cell) of
    /// normality angles, 1/(N·m): the inverse of the rigidity with which
    /// neighbouring normals agree (1e-5 N·m at `λ = ½`).
    const REFERENCE_COMPLIANCE: f32 = 1e5;

    /// The edges', then the diagonals'.
    type Multipliers = [Vec<f32>; 2];
    type Shared<'a> = [Shared<'a, f32>; 2];

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(&mut mu[0], sets.topology.structural.len());
        zero(&mut mu[1], sets.topology.shear.len());
    }

    fn share(mu: &mut Self::Multipliers) -> Self::Shared<'_> {
        let [edges, diagonals] = mu;
        [Shared::new(edges), Shared::new(diagonals)]
    }

    fn project<R: Recorder>(
        sweep: &Sweep,
        crew: &Crew,
        weight: f32,
        mu: &Self::Shared<'_>,
        rec: &mut R,
    ) {
        let (p, rot, topology) = (sweep.p, sweep.rot, sweep.sets.topology);
        let k = sweep.compliance(Self::REFERENCE_COMPLIANCE, weight);
        let edges = &topology.structural;
        project_batches(
            crew,
            &edges.items,
            &mu[0],
            &edges.batches,
            rec,
            kernel!(|c, m, n, r| project::<F, _>(p, c, m, n, k, rot, r)),
        );
        let k = sweep.compliance(SHEAR_REFERENCE_COMPLIANCE, weight);
        let diagonals = &topology.shear;
        project_batches(
            crew,
            &diagonals.items,
            &mu[1],
            &diagonals.batches,
            rec,
            kernel!(|c, m, n, _| stretch::project::<F>(p, c, m, n, k)),
        );
    }

    fn violation(m: &Measure) -> Violation {
        let normal = |i| m.state.normal(i);
        tally(m.threads, &m.topology.structural.items, |p| {
            violation(normal, p)
        })
    }

    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        let normal = |i| m.state.normal(i);
        each_pair(&m.topology.structural, only, |p| violation(normal, p), put);
    }
}

/// `|n_a × n_b|` at or below which two normals are taken as parallel or
/// opposite ([`super::axis_angle`]).
const TINY: f32 = 1e-9;

/// Projects the normals of up to `F::N` edges of one
/// colour toward each other, side by side, with compliance `alpha_t`
/// (`α / Δt²`, for a square cell).
#[inline(always)]
pub(crate) fn project<F: Lane, R: Recorder>(
    p: &Particles,
    pairs: &F::Array<Pair>,
    mu: &mut F::Array<f32>,
    live: usize,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, b) = (
        Chunk::<F>::of(pairs, |c| c.a),
        Chunk::<F>::of(pairs, |c| c.b),
    );
    let (ba, bb) = (a.inv_inertia(p), b.inv_inertia(p));
    let w = ba + bb;
    let mut on = lanes::live::<F>(live) & !w.simd_le(0.0);
    if on.none() {
        return;
    }
    let (qa, qb) = (a.q(p), b.q(p));
    let (na, nb) = (qa.normal(), qb.normal());
    let (axis, angle) =
        crate::solver::kernels::angles::axis_angle_lanes(na, nb, TINY, &mut on, |k| p.x(b.at(k)) - p.x(a.at(k)));
    let mut m = lanes::load::<F>(mu);
    let d = lanes::delta_mu(
        angle,
        w,
        F::splat(alpha_t) / lanes::field::<F, _>(pairs, |c| c.aspect),
        m,
    );
    // Gradients: −axis at a, +axis at b; the larger turn is Eq. 3's to shape.
    let d = lanes::forced(rot, angle, d, ba.max(bb), on);
    m = on.select(m + d, m);
    lanes::store(m, mu);
    a.turn(p, qa, axis * (-ba * d), on & ba.simd_gt(0.0), rec);
    b.turn(p, qb, axis * (bb * d), on & bb.simd_gt(0.0), rec);
}

/// The angle between the two normals, in radians.
#[inline]
pub fn violation(normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (na, nb) = (normal(pair.a as usize), normal(pair.b as usize));
    crate::solver::kernels::angles::atan2(na.cross(nb).length(), na.dot(nb))
}
