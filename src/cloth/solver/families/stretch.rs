//! Stretch: the length limit on weft and warp edges, and the tethers.
//!
//! The linear part of the paper's spring, `−k (x_a − x_b)`, "limits the
//! spring's length" (§2). As a position constraint: `C = |s| − L` with
//! `s = x_b − x_a`, gradient `∓ ŝ`, projected in proportion to inverse mass.
//! At the default `λ = 1` it is rigid: real cloth hardly stretches. No
//! rotation. The violation reported is the strain `|C| / L`.
//!
//! The same distance constraint, soft, resists in-plane shear on the cell
//! diagonals; it runs under the normality weight, as the paper pairs shear
//! with normality ([`super::normality`]).
//!
//! The length *limit* also holds at long range: every free particle is
//! tethered to its nearest driven particle, and may not be farther from it
//! than at rest (`C = |x_i − x_p| − D ≤ 0`, one-sided, only `x_i` moves). A
//! long run of Gauss–Seidel edges passes a jerk on slowly; the tether passes
//! it in one projection, so a cloth dragged or stopped abruptly by its
//! attachment does not overstretch. A tether only ever pulls, so it never
//! stops a cloth from draping or folding.

use glam::Vec3;

use super::{ConstraintFamily, Measure, Sets, Sweep, each_pair, measure::tally, zero};
use super::violation::Violation;
use crate::solver::kernels::lanes::{self, Chunk, Lane};
use crate::solver::kernels::{Particles, Recorder, Shared, kernel, project_batches};
use crate::solver::team::Crew;
use crate::solver::topology::Pair;

/// The stretch family: weft and warp edges, and the tethers.
pub struct Stretch;

impl ConstraintFamily for Stretch {
    const NAME: &'static str = "stretch";
    const COLOR: [u8; 3] = [230, 80, 70];
    const DEFAULT_WEIGHT: f32 = 1.0;
    const TURNS: bool = false;
    /// The reference compliance `α_ref` (at `λ = ½`, for a square cell) of weft
    /// and warp edges and tethers, m/N: the inverse of the cloth's stretch
    /// stiffness `E·t` (1000 N/m at `λ = ½`).
    const REFERENCE_COMPLIANCE: f32 = 1e-3;
    /// Stretch is the firm limit and the cheapest family (no angles, no
    /// turns), and the only rigid one at the default weights: a rigid
    /// constraint needs more Gauss–Seidel passes than a soft one, which
    /// XPBD settles in about one. Three passes per sweep bought a flag on a
    /// braking car from 0.20 to 0.085 peak strain at 8 substeps × 2
    /// iterations, for 7 % more time per sweep. (Running the passes'
    /// colours in alternating orders, symmetric Gauss–Seidel, was measured
    /// and raised peak strain on every preset.)
    const PASSES: usize = 3;

    /// The edges', then the tethers'.
    type Multipliers = [Vec<f32>; 2];
    type Shared<'a> = [Shared<'a, f32>; 2];

    fn reset(mu: &mut Self::Multipliers, sets: &Sets) {
        zero(&mut mu[0], sets.topology.structural.len());
        zero(&mut mu[1], sets.tethers.items.len());
    }

    fn share(mu: &mut Self::Multipliers) -> Self::Shared<'_> {
        let [edges, tethers] = mu;
        [Shared::new(edges), Shared::new(tethers)]
    }

    fn project<R: Recorder>(
        sweep: &Sweep,
        crew: &Crew,
        weight: f32,
        mu: &Self::Shared<'_>,
        rec: &mut R,
    ) {
        let (p, k) = (sweep.p, sweep.compliance(Self::REFERENCE_COMPLIANCE, weight));
        let edges = &sweep.sets.topology.structural;
        project_batches(
            crew,
            &edges.items,
            &mu[0],
            &edges.batches,
            rec,
            kernel!(|c, m, n, _| project::<F>(p, c, m, n, k)),
        );
        // Each particle appears once per tether batch.
        let tethers = sweep.sets.tethers;
        project_batches(
            crew,
            &tethers.items,
            &mu[1],
            &tethers.batches,
            rec,
            kernel!(|t, m, n, _| project_tethers::<F>(p, t, m, n, k)),
        );
    }

    fn violation(m: &Measure) -> Violation {
        let x = &m.state.position;
        tally(m.threads, &m.topology.structural.items, |p| violation(x, p))
    }

    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32)) {
        let x = &m.state.position;
        each_pair(&m.topology.structural, only, |p| violation(x, p), put);
    }
}

/// Projects up to `F::N` distance constraints of one colour
/// side by side, with compliance `alpha_t` (`α / Δt²` for a square cell;
/// divided by each pair's aspect).
#[inline(always)]
pub(crate) fn project<F: Lane>(
    p: &Particles,
    pairs: &F::Array<Pair>,
    mu: &mut F::Array<f32>,
    live: usize,
    alpha_t: f32,
) {
    let (a, b) = (
        Chunk::<F>::of(pairs, |c| c.a),
        Chunk::<F>::of(pairs, |c| c.b),
    );
    let (wa, wb) = (a.inv_mass(p), b.inv_mass(p));
    let w = wa + wb;
    let s = b.x(p) - a.x(p);
    let len = s.length();
    let on = lanes::live::<F>(live) & !w.simd_eq(0.0) & !len.simd_le(1e-9);
    if on.none() {
        return;
    }
    let rest = lanes::field::<F, _>(pairs, |c| c.rest);
    let alpha_t = F::splat(alpha_t) / lanes::field::<F, _>(pairs, |c| c.aspect);
    let m = lanes::load::<F>(mu);
    let d = lanes::delta_mu(len - rest, w, alpha_t, m);
    lanes::store(on.select(m + d, m), mu);
    let dir = s * (d * (F::ONE / len));
    a.shift(p, dir * -wa, on & wa.simd_gt(0.0));
    b.shift(p, dir * wb, on & wb.simd_gt(0.0));
}

/// One free particle's limit on its distance from a driven particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tether {
    /// The free particle.
    pub particle: u32,
    /// The driven particle it hangs from.
    pub anchor: u32,
    /// Their distance at rest, in metres.
    pub rest: f32,
    /// How many rest spacings the tether spans: it is as compliant as that
    /// many edges in a row.
    pub span: f32,
}

/// Projects up to `F::N` tethers of one batch side by
/// side: pulls each particle back if it is too far.
#[inline(always)]
pub(crate) fn project_tethers<F: Lane>(
    p: &Particles,
    tethers: &F::Array<Tether>,
    mu: &mut F::Array<f32>,
    live: usize,
    alpha_t: f32,
) {
    let (i, anchor) = (
        Chunk::<F>::of(tethers, |t| t.particle),
        Chunk::<F>::of(tethers, |t| t.anchor),
    );
    let s = i.x(p) - anchor.x(p);
    let len = s.length();
    let on = lanes::live::<F>(live) & !len.simd_le(1e-9);
    if on.none() {
        return;
    }
    let w = i.inv_mass(p);
    let rest = lanes::field::<F, _>(tethers, |t| t.rest);
    let alpha_t = F::splat(alpha_t) * lanes::field::<F, _>(tethers, |t| t.span);
    let m = lanes::load::<F>(mu);
    // One-sided: the multiplier may only pull (μ ≤ 0).
    let next = (m + lanes::delta_mu(len - rest, w, alpha_t, m)).min(F::ZERO);
    let d = next - m;
    lanes::store(on.select(next, m), mu);
    i.shift(p, s * (w * d / len), on & !d.simd_eq(0.0));
}

/// Tethers in two batches: every free particle's tether to its nearest
/// driven particle, then its tether to the nearest driven particle of
/// another group of attachments, if there is one. Within a batch each
/// particle appears once, so a batch may be projected in any order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tethers {
    /// The tethers, first batch then second.
    pub items: Vec<Tether>,
    /// The two batches' ranges in `items`.
    pub batches: Vec<std::ops::Range<usize>>,
}

/// Builds the [`Tethers`] of a cloth at rest in `rest` with the particles
/// `driven` attached. Attachments form a group when they are within 1.5
/// rest `spacing`s of each other (a flag's pole is one group, a sheet's two
/// pinned corners are two).
///
/// One anchor bounds each particle's distance from its own side only: a
/// sheet hung by two corners could then sag between them in a shallow V,
/// with all the stretch in the middle edges. A tether to the nearest anchor
/// of the other group rules the V out. (Any tether is a true limit of an
/// inextensible cloth: no two material points can be farther apart than
/// their distance across the flat cloth.)
pub fn tethers(rest: &[Vec3], driven: &[usize], spacing: f32) -> Tethers {
    let mut is_driven = vec![false; rest.len()];
    for &d in driven {
        debug_assert!(d < rest.len());
        is_driven[d] = true;
    }
    let group = groups(rest, driven, 1.5 * spacing);
    let tether = |particle: usize, anchor: usize| {
        let rest = rest[anchor].distance(rest[particle]);
        Tether {
            particle: particle as u32,
            anchor: anchor as u32,
            rest,
            span: (rest / spacing).max(1.0),
        }
    };
    // The nearest driven particle (by index into `driven`) passing `keep`.
    let nearest = |i: usize, keep: &dyn Fn(usize) -> bool| {
        (0..driven.len())
            .filter(|&k| keep(k))
            .map(|k| (k, rest[driven[k]].distance_squared(rest[i])))
            .fold(None, |best: Option<(usize, f32)>, c| match best {
                Some(b) if b.1 <= c.1 => Some(b),
                _ => Some(c),
            })
            .map(|(k, _)| k)
    };
    let (mut first, mut second) = (Vec::new(), Vec::new());
    for i in (0..rest.len()).filter(|&i| !is_driven[i]) {
        let Some(a) = nearest(i, &|_| true) else {
            continue;
        };
        first.push(tether(i, driven[a]));
        if let Some(b) = nearest(i, &|k| group[k] != group[a]) {
            second.push(tether(i, driven[b]));
        }
    }
    let split = first.len();
    first.append(&mut second);
    Tethers {
        batches: vec![0..split, split..first.len()],
        items: first,
    }
}

/// The group of each driven particle: two are in one group when a chain of
/// driven particles, each within `reach` of the next, joins them.
fn groups(rest: &[Vec3], driven: &[usize], reach: f32) -> Vec<usize> {
    let mut group: Vec<usize> = (0..driven.len()).collect();
    fn root(group: &mut [usize], mut k: usize) -> usize {
        while group[k] != k {
            group[k] = group[group[k]];
            k = group[k];
        }
        k
    }
    for a in 0..driven.len() {
        for b in a + 1..driven.len() {
            if rest[driven[a]].distance_squared(rest[driven[b]]) <= reach * reach {
                let (ra, rb) = (root(&mut group, a), root(&mut group, b));
                group[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    (0..driven.len()).map(|k| root(&mut group, k)).collect()
}

/// The strain of one edge, `| |s| − L | / L`.
#[inline]
pub fn violation(x: &[Vec3], pair: Pair) -> f32 {
    let len = x[pair.b as usize].distance(x[pair.a as usize]);
    (len - pair.rest).abs() / pair.rest
}
