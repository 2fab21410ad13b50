//! Stretch: the length limit on weft, warp and shear edges.
//!
//! The linear part of the paper's spring, `−k (x_a − x_b)`, "limits the
//! spring's length" (§2). As a position constraint: `C = |s| − L` with
//! `s = x_b − x_a`, projected along `ŝ = s / |s|` in proportion to inverse
//! mass: `δx_a = +w_a Δ ŝ`, `δx_b = −w_b Δ ŝ`, `Δ = λ C / (w_a + w_b)`.
//! No rotation. The violation reported is the strain `|C| / L`.
//!
//! The length *limit* also holds at long range: every free particle is
//! tethered to its nearest driven particle, and may not be farther from it
//! than at rest (`C = |x_i − x_p| − D ≤ 0`, one-sided, only `x_i` moves). A
//! long run of Gauss–Seidel edges passes a jerk on slowly; the tether passes
//! it in one projection, so a cloth dragged or stopped abruptly by its
//! attachment does not overstretch.

use glam::Vec3;

use super::{Particles, Recorder, shift};
use crate::solver::topology::Pair;

/// Projects one edge.
#[inline]
pub(crate) fn project<R: Recorder>(p: &Particles, pair: Pair, weight: f32, rec: &mut R) {
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
    let c = len - pair.rest;
    let dir = s / len;
    let delta = weight * c / w;
    if wa > 0.0 {
        shift(p, a, dir * (wa * delta), rec);
    }
    if wb > 0.0 {
        shift(p, b, dir * (-wb * delta), rec);
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
}

/// Projects one tether: pulls the particle back if it is too far.
#[inline]
pub(crate) fn project_tether<R: Recorder>(p: &Particles, t: Tether, weight: f32, rec: &mut R) {
    let (i, a) = (t.particle as usize, t.anchor as usize);
    let s = p.x(a) - p.x(i);
    let len = s.length();
    if len <= t.rest || len <= 1e-9 {
        return;
    }
    shift(p, i, s * (weight * (len - t.rest) / len), rec);
}

/// For every free particle, a tether to the driven particle nearest at rest.
pub fn tethers(rest: &[Vec3], driven: &[usize]) -> Vec<Tether> {
    if driven.is_empty() {
        return Vec::new();
    }
    let mut is_driven = vec![false; rest.len()];
    for &d in driven {
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
            Tether {
                particle: i as u32,
                anchor: anchor as u32,
                rest: d2.sqrt(),
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
