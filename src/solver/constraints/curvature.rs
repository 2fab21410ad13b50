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
//! normality. The violation reported is the sagitta (along `n̂`) in
//! half-lengths of the run, `2|C| / L`: `sin(φ/2)` for a run that turns by
//! `φ`, about half the turn.

use glam::Vec3;

use super::{Particles, Recorder, shift, turn};
use crate::solver::{cloth::normal_of, forced_rotation::ForcedRotation, topology::Triple};

/// Projects one bend triple.
#[inline]
pub(crate) fn project<R: Recorder>(
    p: &Particles,
    t: Triple,
    weight: f32,
    rot: &ForcedRotation,
    rec: &mut R,
) {
    let (a, m, b) = (t.a as usize, t.mid as usize, t.b as usize);
    let (na, nb) = (normal_of(p.q(a)), normal_of(p.q(b)));
    let sum = na + nb;
    let len = sum.length();
    if len <= 1e-6 {
        return; // folded flat on itself: no mean normal to bend about
    }
    let n = sum / len;

    // Translation: the middle onto the chord, along the mean normal made
    // perpendicular to the chord (so the run bends, not stretches).
    let chord = p.x(b) - p.x(a);
    let across =
        (n - chord * (n.dot(chord) / chord.length_squared().max(1e-18))).normalize_or_zero();
    let (wa, wm, wb) = (p.inv_mass[a], p.inv_mass[m], p.inv_mass[b]);
    let w = wm + 0.25 * (wa + wb);
    if w > 0.0 && across != Vec3::ZERO {
        let n = across;
        let c = n.dot(p.x(m) - 0.5 * (p.x(a) + p.x(b)));
        let delta = -weight * c / w;
        if wm > 0.0 {
            shift(p, m, n * (wm * delta), rec);
        }
        if wa > 0.0 {
            shift(p, a, n * (-0.5 * wa * delta), rec);
        }
        if wb > 0.0 {
            shift(p, b, n * (-0.5 * wb * delta), rec);
        }
    }

    // Rotation: the ends' normals toward each other about the bending axis.
    let (ba, bb) = (p.inv_inertia[a], p.inv_inertia[b]);
    let total = ba + bb;
    let e = n.cross(chord);
    let e_len = e.length();
    if total <= 0.0 || e_len <= 1e-9 {
        return;
    }
    let e = e / e_len;
    let bend = super::atan2(na.cross(nb).dot(e), na.dot(nb));
    let full = weight * bend / total;
    if ba > 0.0 {
        turn(p, a, e * (full * ba), rot, rec);
    }
    if bb > 0.0 {
        turn(p, b, e * (-full * bb), rot, rec);
    }
}

/// The sagitta of the middle in half-lengths of the run, `2|C| / L`.
#[inline]
pub fn violation(x: &[Vec3], normal: impl Fn(usize) -> Vec3, t: Triple) -> f32 {
    let (a, m, b) = (t.a as usize, t.mid as usize, t.b as usize);
    let n = (normal(a) + normal(b)).normalize_or_zero();
    2.0 * n.dot(x[m] - 0.5 * (x[a] + x[b])).abs() / t.rest
}
