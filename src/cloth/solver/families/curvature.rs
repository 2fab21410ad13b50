//! Curvature: runs of three particles resist bending, so the cloth bends smoothly.
//!
//! The paper: "when two connected particles form a curved surface, their
//! normals must keep equal angles, so each rotation is adjusted by the
//! difference between the normals' sum and its own normal", printed as
//! `δθ = λ (n_a + n_b) × s_ab` and `δx = v (n_a + n_b)`, `v ∝ (n_a + n_b) · s_ab`.
//! weft applies it to bend triples `a – m – b` (ends two apart):
//!
//! - **rotation**: about the bending axis `e = (n_a + n_b) × s / |…|`
//!   (the printed `δθ` direction), the ends' normals are turned toward their
//!   sum, i.e. toward each other, by the bend angle
//!   `β = atan2((n_a × n_b) · e, n_a · n_b)`, shared by inverse inertia and
//!   shaped by Eq. 3;
//! - **translation**: along the normalised sum `n̂ = (n_a + n_b) / |…|` (the
//!   printed `δx` direction, made perpendicular to the chord so the run bends
//!   rather than stretches), the middle is brought onto the chord. The
//!   sagitta `C = n̂ · (x_m − ½(x_a + x_b))` is the difference of the printed
//!   co-circularity products `(n_a + n_b) · s` over the two halves, halved;
//!   it is projected with gradients `n̂` at the middle and `−½ n̂` at each end,
//!   which keeps the centre of mass.
//!
//! Both vanish exactly when the run is straight (the rest state), so `λ`
//! sets how easily the cloth bends. Twist about the run is left to
//! normality. As constraints both are angles: the sagitta angle
//! `C = 2 n̂ · (x_m − ½(x_a + x_b)) / L` (`L` one edge's rest length; about
//! the run's turn angle) and the bend angle `β`, whose compliances come from
//! the bending rigidity the weight stands for (see `docs/method.md`). The
//! violation reported is `|C|`, exactly what the projection removes.

use glam::Vec3;

use super::{each_triple, measure::tally};
use crate::solver::kernels::lanes::{self, Chunk, Lane, V3};
use crate::solver::kernels::{Particles, Recorder};
use crate::solver::{forced_rotation::ForcedRotation, topology::Triple};
use super::{ConstraintFamily, Measure, Sets, Sweep, zero};
use super::violation::Violation;
use crate::solver::kernels::{Shared, kernel, project_batches};
use crate::solver::team::Crew;

/// The curvature family.
pub struct Curvature;

impl ConstraintFamily for Curvature {
    const NAME: &'static str = "curvature";
    const COLOR: [u8; 3] = [230, 170, 50];
    const DEFAULT_WEIGHT: f32 = 0.1;
    const TURNS: bool = true;
    /// The reference compliance `α_ref` (at `λ = ½`, for a square cell) of
    /// curvature angles, 1/(N·m): the inverse of the bending rigidity `B`
    /// (1e-5 N·m at `λ = ½`, a light cotton).
    const REFERENCE_COMPLIANCE: f32 = 1e5;

    type Multipliers = Vec<[f32; 2]>;
    type Shared<'a> = Shared<'a, [f32; 2]>;

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(mu, sets.topology.bend.len());
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
        let (p, rot) = (sweep.p, sweep.rot);
        let k = sweep.compliance(Self::REFERENCE_COMPLIANCE, weight);
        let set = &sweep.sets.topology.bend;
        project_batches(
            crew,
            &set.items,
            mu,
            &set.batches,
            rec,
            kernel!(|c, m, n, r| project::<F, _>(p, c, m, n, k, rot, r)),
        );
    }

    fn violation(m: &Measure) -> Violation {
        let x = &m.state.position;
        tally(m.threads, &m.topology.bend.items, |t| violation(x, t))
    }

    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        let x = &m.state.position;
        each_triple(&m.topology.bend, only, |t| violation(x, t), put);
    }
}

/// Projects up to `F::N` bend triples of one colour side by
/// side, with compliance `alpha_t` (`α / Δt²`, for a square cell); `mu`
/// holds each triple's sagitta and bend angle multipliers.
#[inline(always)]
pub(crate) fn project<F: Lane, R: Recorder>(
    p: &Particles,
    triples: &F::Array<Triple>,
    mu: &mut F::Array<[f32; 2]>,
    live: usize,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let a = Chunk::<F>::of(triples, |t| t.a);
    let m = Chunk::<F>::of(triples, |t| t.mid);
    let b = Chunk::<F>::of(triples, |t| t.b);
    let (qa, qb) = (a.q(p), b.q(p));
    let (na, nb) = (qa.normal(), qb.normal());
    let (xa, xm, xb) = (a.x(p), m.x(p), b.x(p));
    let rest = lanes::field::<F, _>(triples, |t| t.rest);
    // `sagitta`, in lanes; a straight run has nothing to bend back.
    let chord = xb - xa;
    let offset = xm - (xa + xb) * F::splat(0.5);
    let across = offset - chord * (offset.dot(chord) / chord.length_squared().max(F::splat(1e-18)));
    let len = across.length();
    let bent = lanes::live::<F>(live) & !(len.is_nan() | len.simd_le(1e-9));
    if bent.none() {
        return;
    }
    let c = F::splat(4.0) * len / rest;
    let across = across * (F::ONE / len);
    let alpha_t = F::splat(alpha_t) / lanes::field::<F, _>(triples, |t| t.aspect);
    let mut mus = lanes::load_pairs::<F>(mu);

    // Translation: the middle onto the chord, along the mean normal made
    // perpendicular to the chord (so the run bends, not stretches).
    // Gradients 2n̂/L at the middle and −n̂/L at each end (L = rest / 2).
    let (wa, wm, wb) = (a.inv_mass(p), m.inv_mass(p), b.inv_mass(p));
    let inv_half = F::splat(2.0) / rest;
    let w = (F::splat(4.0) * wm + wa + wb) * inv_half * inv_half;
    let on = bent & w.simd_gt(0.0);
    if on.any() {
        let d = lanes::delta_mu(c, w, alpha_t, mus[0]);
        mus[0] = on.select(mus[0] + d, mus[0]);
        let step = across * (d * inv_half);
        m.shift(p, step * (F::splat(2.0) * wm), on & wm.simd_gt(0.0));
        a.shift(p, step * -wa, on & wa.simd_gt(0.0));
        b.shift(p, step * -wb, on & wb.simd_gt(0.0));
    }

    // Rotation: the ends' normals toward each other about the bending axis
    // e = n̂ × chord; the bend angle β from n_a to n_b about e has gradients
    // −e at a and +e at b. Over a run of two edges it counts four times
    // less than the sagitta angle, so its compliance is four times larger.
    let (ba, bb) = (a.inv_inertia(p), b.inv_inertia(p));
    let e = across.cross(chord);
    let e_len = e.length();
    let on = bent & !((ba + bb).simd_le(0.0) | e_len.simd_le(1e-9));
    if on.any() {
        let e: V3<F> = e * (F::ONE / e_len);
        let bend = lanes::atan2(na.cross(nb).dot(e), na.dot(nb));
        let d = lanes::delta_mu(bend, ba + bb, F::splat(4.0) * alpha_t, mus[1]);
        let d = lanes::forced(rot, bend.abs(), d, ba.max(bb), on);
        mus[1] = on.select(mus[1] + d, mus[1]);
        a.turn(p, qa, e * (-ba * d), on & ba.simd_gt(0.0), rec);
        b.turn(p, qb, e * (bb * d), on & bb.simd_gt(0.0), rec);
    }
    lanes::store_pairs(mus, mu);
}

/// The sagitta angle `C = 2 |d⊥| / L` of a run (`L` half the run's rest
/// length), where `d⊥` is the middle's offset from the chord's midpoint made
/// perpendicular to the chord, with the unit direction `d⊥ / |d⊥|` and the
/// chord. The direction is the run's own, so the constraint stays well posed
/// whatever the normals do; for a run bent the way its normals say, it is
/// their mean made perpendicular to the chord (the paper's `n_a + n_b`).
/// `None` when the run is straight (nothing to correct) or degenerate.
#[inline]
fn sagitta(xa: Vec3, xm: Vec3, xb: Vec3, rest: f32) -> Option<(f32, Vec3, Vec3)> {
    let chord = xb - xa;
    let offset = xm - 0.5 * (xa + xb);
    let across = offset - chord * (offset.dot(chord) / chord.length_squared().max(1e-18));
    let len = across.length();
    if len.is_nan() || len <= 1e-9 {
        return None;
    }
    Some((4.0 * len / rest, across * len.recip(), chord))
}

/// The sagitta angle `|C|` that the projection removes, in radians.
#[inline]
pub fn violation(x: &[Vec3], t: Triple) -> f32 {
    sagitta(x[t.a as usize], x[t.mid as usize], x[t.b as usize], t.rest).map_or(0.0, |v| v.0)
}
