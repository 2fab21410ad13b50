//! Planarity: neighbours share a tangent plane (co-planarity).
//!
//! The paper prints `δx_a = v·n_a`, `δx_b = −v·n_b`, `v = n_a × s_ab`. Read as
//! the gradients of the co-planarity violation `n_a · s` (the distance of `b`
//! from `a`'s tangent plane): moving `b` along `n_a`, `a` against it, and
//! turning `a` about `v = n_a × s` all reduce it. weft projects the same
//! condition as an angle (see `one_side`) so that it stays well posed for
//! large violations. Each edge is projected from both ends, `b` into `a`'s
//! plane and `a` into `b`'s. The violation reported is that angle, in
//! radians (the larger of the two ends).
//!
//! Planarity ties each normal to the surface around it; together with
//! normality (neighbouring normals agree) this resists bending too, on top
//! of curvature: with both rigid, a cloth could not bend at all. Their
//! default weights are soft enough that curvature's weight sets the drape
//! (`docs/method.md` has the ablation).

use glam::Vec3;

use super::{each_pair, measure::tally};
use crate::solver::kernels::lanes::{self, Chunk, Lane};
use crate::solver::kernels::{Particles, Recorder};
use crate::solver::{forced_rotation::ForcedRotation, topology::Pair};
use super::{ConstraintFamily, Measure, Sets, Sweep, zero};
use super::violation::Violation;
use crate::solver::kernels::{Shared, kernel, project_batches};
use crate::solver::team::Crew;

/// The planarity family.
pub struct Planarity;

impl ConstraintFamily for Planarity {
    const NAME: &'static str = "planarity";
    const COLOR: [u8; 3] = [70, 170, 230];
    const DEFAULT_WEIGHT: f32 = 0.5;
    const TURNS: bool = true;
    /// The reference compliance `α_ref` (at `λ = ½`, for a square cell) of
    /// planarity angles, 1/(N·m): the inverse of the rigidity tying each normal
    /// to the surface around it (1e-5 N·m at `λ = ½`).
    const REFERENCE_COMPLIANCE: f32 = 1e5;

    type Multipliers = Vec<[f32; 2]>;
    type Shared<'a> = Shared<'a, [f32; 2]>;

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(mu, sets.topology.structural.len());
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
        let set = &sweep.sets.topology.structural;
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
        let (x, normal) = (&m.state.position, |i| m.state.normal(i));
        tally(m.threads, &m.topology.structural.items, |p| {
            violation(x, normal, p)
        })
    }

    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        let (x, normal) = (&m.state.position, |i| m.state.normal(i));
        each_pair(&m.topology.structural, only, |p| violation(x, normal, p), put);
    }
}

/// Projects up to `F::N` edges of one colour side by side,
/// each from both ends, with compliance `alpha_t` (`α / Δt²`, for a square
/// cell); `mu` holds each edge's two sides' multipliers.
#[inline(always)]
pub(crate) fn project<F: Lane, R: Recorder>(
    p: &Particles,
    pairs: &F::Array<Pair>,
    mu: &mut F::Array<[f32; 2]>,
    live: usize,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, b) = (
        Chunk::<F>::of(pairs, |c| c.a),
        Chunk::<F>::of(pairs, |c| c.b),
    );
    let alpha_t = F::splat(alpha_t) / lanes::field::<F, _>(pairs, |c| c.aspect);
    let mut m = lanes::load_pairs::<F>(mu);
    let live = lanes::live::<F>(live);
    // Both sides move both ends: the positions stay in lanes between them
    // and are written once.
    let (mut ea, mut eb) = (End::of(p, &a), End::of(p, &b));
    one_side(p, (&mut ea, &mut eb), &mut m[0], live, alpha_t, rot, rec);
    one_side(p, (&mut eb, &mut ea), &mut m[1], live, alpha_t, rot, rec);
    lanes::store_pairs(m, mu);
    ea.pos.put(p, &a);
    eb.pos.put(p, &b);
}

/// One end of a chunk's edges: its particles, positions (held in lanes),
/// inverse masses and inverse inertias.
struct End<'c, F: Lane> {
    chunk: &'c Chunk<F>,
    pos: lanes::Held<F>,
    w: F,
    beta: F,
}

impl<'c, F: Lane> End<'c, F> {
    #[inline(always)]
    fn of(p: &Particles, chunk: &'c Chunk<F>) -> Self {
        Self {
            chunk,
            pos: lanes::Held::of(p, chunk),
            w: chunk.inv_mass(p),
            beta: chunk.inv_inertia(p),
        }
    }
}

/// The angle `α = asin(n · ŝ)` of the edge `e → o` out of `e`'s tangent
/// plane, with the unit rotation axis `n × ŝ / |n × ŝ|` and the unit
/// direction `n⊥` of the normal across the edge. `None` when the edge is
/// degenerate or the normal lies along it (an unstable balance the other
/// families break).
#[inline(always)]
fn out_of_plane(n: Vec3, s: Vec3) -> Option<(f32, Vec3, Vec3, f32)> {
    let len = s.length();
    if len <= 1e-9 {
        return None;
    }
    let dir = s * len.recip();
    let sin = n.dot(dir).clamp(-1.0, 1.0);
    let axis = n.cross(dir);
    let cos = axis.length();
    if cos <= 1e-6 {
        return None;
    }
    let inv_cos = cos.recip();
    Some((
        crate::solver::kernels::angles::atan(sin * inv_cos),
        axis * inv_cos,
        (n - dir * sin) * inv_cos,
        len,
    ))
}

/// Brings each lane's `o` into the tangent plane of its `e`.
///
/// The constraint is the angle `α = asin(n · ŝ)` of the edge out of the plane
/// (the same zero set as `n · s`; [`out_of_plane`], lane by lane). Its
/// gradients stay useful even when the normal lies along the edge: in
/// rotation, the unit axis `n × ŝ / |n × ŝ|`; in position, `n⊥ / |s|` with
/// `n⊥` the normal made perpendicular to the edge, so the edge turns instead
/// of shortening and never fights the length limit.
#[inline(always)]
fn one_side<F: Lane, R: Recorder>(
    p: &Particles,
    (e, o): (&mut End<F>, &mut End<F>),
    mu: &mut F,
    live: F,
    alpha_t: F,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let q = e.chunk.q(p);
    let n = q.normal();
    let s = o.pos.x - e.pos.x;
    let len = s.length();
    let inv_len = F::ONE / len;
    let dir = s * inv_len;
    let sin = lanes::clamp_unit(n.dot(dir));
    let axis = n.cross(dir);
    let cos = axis.length();
    let inv_cos = F::ONE / cos;
    let (we, wo, be) = (e.w, o.w, e.beta);
    let w = (we + wo) * inv_len * inv_len + be;
    let on = live & !len.simd_le(1e-9) & !cos.simd_le(1e-6) & !w.simd_le(0.0);
    if on.none() {
        return;
    }
    let alpha = lanes::atan(sin * inv_cos);
    let axis = axis * inv_cos;
    let across = (n - dir * sin) * inv_cos;
    let d = lanes::delta_mu(alpha, w, alpha_t, *mu);
    let d = lanes::forced(rot, alpha.abs(), d, be, on);
    *mu = on.select(*mu + d, *mu);
    let step = across * (d * inv_len);
    o.pos.shift(step * wo, on & wo.simd_gt(0.0));
    e.pos.shift(step * -we, on & we.simd_gt(0.0));
    e.chunk
        .turn(p, q, axis * (be * d), on & be.simd_gt(0.0), rec);
}

/// The larger of the two one-sided angles `|α|` that the projection removes,
/// in radians.
#[inline]
pub fn violation(x: &[Vec3], normal: impl Fn(usize) -> Vec3, pair: Pair) -> f32 {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let side = |e: usize, o: usize| out_of_plane(normal(e), x[o] - x[e]).map_or(0.0, |v| v.0.abs());
    side(a, b).max(side(b, a))
}
