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

use super::{Particles, Recorder, delta_mu, shift, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Triple};

/// Projects one bend triple with compliance `alpha_t` (`α / Δt²`, for a
/// square cell); `mu` holds the sagitta's and the bend angle's multipliers.
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    t: Triple,
    mu: &mut [f32; 2],
    alpha_t: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, m, b) = (t.a as usize, t.mid as usize, t.b as usize);
    let (na, nb) = (normal_of(p.q(a)), normal_of(p.q(b)));
    let (xa, xm, xb) = (p.x(a), p.x(m), p.x(b));
    let Some((c, across, chord)) = sagitta(xa, xm, xb, t.rest) else {
        return; // straight: nothing to bend back
    };
    let alpha_t = alpha_t / t.aspect;

    // Translation: the middle onto the chord, along the mean normal made
    // perpendicular to the chord (so the run bends, not stretches).
    // Gradients 2n̂/L at the middle and −n̂/L at each end (L = rest / 2).
    let (wa, wm, wb) = (p.inv_mass[a], p.inv_mass[m], p.inv_mass[b]);
    let inv_half = 2.0 / t.rest;
    let w = (4.0 * wm + wa + wb) * inv_half * inv_half;
    if w > 0.0 {
        let d = delta_mu(c, w, alpha_t, mu[0]);
        mu[0] += d;
        let step = across * (d * inv_half);
        if wm > 0.0 {
            shift(p, m, step * (2.0 * wm), rec);
        }
        if wa > 0.0 {
            shift(p, a, step * -wa, rec);
        }
        if wb > 0.0 {
            shift(p, b, step * -wb, rec);
        }
    }

    // Rotation: the ends' normals toward each other about the bending axis
    // e = n̂ × chord; the bend angle β from n_a to n_b about e has gradients
    // −e at a and +e at b. Over a run of two edges it counts four times
    // less than the sagitta angle, so its compliance is four times larger.
    let (ba, bb) = (p.inv_inertia[a], p.inv_inertia[b]);
    let e = across.cross(chord);
    let e_len = e.length();
    if ba + bb <= 0.0 || e_len <= 1e-9 {
        return;
    }
    let e = e * e_len.recip();
    let bend = super::atan2(na.cross(nb).dot(e), na.dot(nb));
    let mut d = delta_mu(bend, ba + bb, 4.0 * alpha_t, mu[1]);
    d *= rot.scale(bend.abs(), ba.max(bb) * d.abs());
    mu[1] += d;
    if ba > 0.0 {
        turn(p, a, e * (-ba * d), rec);
    }
    if bb > 0.0 {
        turn(p, b, e * (bb * d), rec);
    }
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
