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

use super::{Particles, Recorder, delta_mu, shift};
use crate::solver::topology::Pair;

/// Projects one distance constraint with compliance `alpha_t` (`α / Δt²`
/// for a square cell; divided by the pair's aspect).
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    pair: Pair,
    mu: &mut f32,
    alpha_t: f32,
    rec: &mut R,
) {
    let (a, b) = (pair.a as usize, pair.b as usize);
    let (wa, wb) = (p.inv_mass[a], p.inv_mass[b]);
    let w = wa + wb;
    if w == 0.0 {
        return;
    }
    let s = p.x(b) - p.x(a);
    let len = s.length();
    if len <= 1e-9 {
        return;
    }
    let d = delta_mu(len - pair.rest, w, alpha_t / pair.aspect, *mu);
    *mu += d;
    let dir = s * (d * len.recip());
    if wa > 0.0 {
        shift(p, a, dir * -wa, rec);
    }
    if wb > 0.0 {
        shift(p, b, dir * wb, rec);
    }
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

/// Projects one tether: pulls the particle back if it is too far.
#[inline]
pub(crate) fn project_tether<R: Recorder>(
    p: &Particles,
    t: Tether,
    mu: &mut f32,
    alpha_t: f32,
    rec: &mut R,
) {
    let (i, a) = (t.particle as usize, t.anchor as usize);
    let s = p.x(i) - p.x(a);
    let len = s.length();
    if len <= 1e-9 {
        return;
    }
    let w = p.inv_mass[i];
    // One-sided: the multiplier may only pull (μ ≤ 0).
    let next = (*mu + delta_mu(len - t.rest, w, alpha_t * t.span, *mu)).min(0.0);
    let d = next - *mu;
    *mu = next;
    if d != 0.0 {
        shift(p, i, s * (w * d / len), rec);
    }
}

/// For every free particle, a tether to the driven particle nearest at rest.
///
/// Linear in the number of particles for the usual case of attachments along
/// the cloth's border: the candidates are scanned once per free particle,
/// but only the driven particles are candidates.
pub fn tethers(rest: &[Vec3], driven: &[usize], spacing: f32) -> Vec<Tether> {
    if driven.is_empty() {
        return Vec::new();
    }
    let mut is_driven = vec![false; rest.len()];
    for &d in driven {
        debug_assert!(d < rest.len());
        is_driven[d] = true;
    }
    (0..rest.len())
        .filter(|&i| !is_driven[i])
        .map(|i| {
            let (anchor, d2) = driven
                .iter()
                .map(|&d| (d, rest[d].distance_squared(rest[i])))
                .fold((driven[0], f32::INFINITY), |best, c| {
                    if c.1 < best.1 { c } else { best }
                });
            let rest = d2.sqrt();
            Tether {
                particle: i as u32,
                anchor: anchor as u32,
                rest,
                span: (rest / spacing).max(1.0),
            }
        })
        .collect()
}

/// The strain of one edge, `| |s| − L | / L`.
#[inline]
pub fn violation(x: &[Vec3], pair: Pair) -> f32 {
    let len = x[pair.b as usize].distance(x[pair.a as usize]);
    (len - pair.rest).abs() / pair.rest
}
