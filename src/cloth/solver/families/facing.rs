//! Facing: each element's normal follows the surface its neighbours make,
//! facing the same way (weft's own family, on by default at `λ = 0.99`).
//!
//! Planarity ties a normal to the edges around it only up to its sign, and
//! softly; a flag flaps faster than that tie holds, and its elements lag and
//! turn over (`docs/method.md`, section 7). Facing measures
//! each element against the normal of its patch,
//!
//! ```text
//! g = (x(i+1, j) − x(i−1, j)) × (x(i, j+1) − x(i, j−1))
//! ```
//!
//! (one-sided at the border; [`Patch::surface_normal`]), which faces the way
//! every element faced at rest. The violation is the angle
//! `C = ∠(n, g) ∈ [0, π]`, with rotational gradient `−(n × g) / |n × g|`:
//! unlike planarity it tells `n` from `−n`, so an element that has turned
//! over is turned back, the long way round. A normal exactly opposite `g`
//! turns about `n × (the weft chord)`, by the full angle `π`.
//!
//! The surface leads and the element follows: positions do not move (the
//! gradient in position is left out, as if the neighbours were fixed for
//! this family). So a patch writes only its own element's orientation, and
//! every patch of a sweep is independent of the others: one colour. Each
//! turn is shaped by Eq. 3. The violation reported is the angle, in
//! radians: the same measure as the debugger's normals against the surface
//! ([`normal_offsets`](crate::solver::diagnostics::normal_offsets)).

use glam::Vec3;

use super::measure::{tally, wanted};
use crate::solver::kernels::lanes::{self, Chunk, Lane};
use crate::solver::kernels::{Particles, Recorder};
use crate::solver::{forced_rotation::ForcedRotation, topology::Patch};
use super::{ConstraintFamily, Measure, Sets, Sweep, zero};
use super::violation::Violation;
use crate::solver::kernels::{Shared, kernel, project_batches};
use crate::solver::team::Crew;

/// The facing family.
pub struct Facing;

impl ConstraintFamily for Facing {
    const NAME: &'static str = "facing";
    const COLOR: [u8; 3] = [240, 120, 160];
    const DEFAULT_WEIGHT: f32 = 0.99;
    const TURNS: bool = true;
    /// The reference compliance `α_ref` (at `λ = ½`) of facing angles,
    /// 1/(N·m): the inverse of the rigidity with which each element turns to
    /// face the way its surface does (1e-5 N·m at `λ = ½`; per element,
    /// whatever the resolution).
    const REFERENCE_COMPLIANCE: f32 = 1e5;
    /// Its measure is the debugger's normals against the surface, taken
    /// while facing is on.
    const MEASURED_ONLY_WHILE_ON: bool = true;

    type Multipliers = Vec<f32>;
    type Shared<'a> = Shared<'a, f32>;

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(mu, sets.topology.patches.len());
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
        let set = &sweep.sets.topology.patches;
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
        // Already measured as the normals against the surface: tallied
        // from those on this thread.
        if let Some(offsets) = m.offsets {
            return tally(1, offsets, |a| a);
        }
        let (x, normal) = (&m.state.position, |i| m.state.normal(i));
        tally(m.threads, &m.topology.patches.items, |p| {
            violation(x, normal, p)
        })
    }

    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        let (x, normal) = (&m.state.position, |i| m.state.normal(i));
        for &p in m.topology.patches.items.iter().filter(|p| wanted(only, &[p.at])) {
            put(p.at, violation(x, normal, p));
        }
    }
}

/// `|n × g|` at or below which an element is taken as facing along or
/// against its surface ([`super::axis_angle`]); `g` is not normalised
/// (about the square of the grid's spacing).
const TINY: f32 = 1e-12;

/// Turns the elements of up to `F::N` patches toward their surface
/// normals, side by side, with compliance `alpha_t` (`α / Δt²`).
#[inline(always)]
pub(crate) fn project<F: Lane, R: Recorder>(
    p: &Particles,
    patches: &F::Array<Patch>,
    mu: &mut F::Array<f32>,
    live: usize,
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let at = Chunk::<F>::of(patches, |c| c.at);
    let beta = at.inv_inertia(p);
    let mut on = lanes::live::<F>(live) & beta.simd_gt(0.0);
    if on.none() {
        return;
    }
    let chord = |a: fn(Patch) -> u32, b: fn(Patch) -> u32| {
        Chunk::<F>::of(patches, b).x(p) - Chunk::<F>::of(patches, a).x(p)
    };
    let along_weft = chord(|c| c.left, |c| c.right);
    let g = along_weft.cross(chord(|c| c.down, |c| c.up));
    let q = at.q(p);
    let n = q.normal();
    let (axis, angle) = crate::solver::kernels::angles::axis_angle_lanes(n, g, TINY, &mut on, |k| along_weft.lane(k));
    let mut m = lanes::load::<F>(mu);
    let d = lanes::delta_mu(angle, beta, F::splat(alpha_t), m);
    let d = lanes::forced(rot, angle, d, beta, on);
    m = on.select(m + d, m);
    lanes::store(m, mu);
    at.turn(p, q, axis * (-beta * d), on, rec);
}

/// The angle between the element's normal and its surface's, in radians
/// (0 where the surface normal vanishes).
#[inline]
pub fn violation(x: &[Vec3], normal: impl Fn(usize) -> Vec3, patch: Patch) -> f32 {
    let g = patch.surface_normal(x);
    if g == Vec3::ZERO {
        return 0.0;
    }
    let n = normal(patch.at as usize);
    crate::solver::kernels::angles::atan2(n.cross(g).length(), n.dot(g))
}
