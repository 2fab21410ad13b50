//! The update phase of §3.2: every particle moves on its own.
//!
//! Störmer integration with damping `k`, velocity approximated by the last
//! displacement:
//!
//! ```text
//! Δx(t+Δt) = k · (x(t) − x(t−Δt)) + a(t) · Δt²,   x_update = x(t) + Δx(t+Δt)
//! ```
//!
//! Orientation is advanced the same way: the last rotation
//! `q(t) q(t−Δt)⁻¹`, as a rotation vector scaled by `k`, is applied again.
//!
//! The acceleration is gravity plus wind acting on the oriented element. With
//! relative wind `u = v_air − v` and normal `n`, the pressure on the element is
//! `½ ρ_air C_n (u·n)|u·n|` along `n`, plus a small skin friction
//! `½ ρ_air C_t |u_t| u_t` along the tangential part `u_t`; divided by the areal
//! density `ρ_A` this is an acceleration. A flag edge-on to the wind (`u·n = 0`)
//! feels only skin friction. The change of velocity the wind gives in one
//! substep is capped at the relative velocity itself, so a light element is
//! carried along by the wind instead of overshooting it.

use glam::Vec3;

use super::cloth::{ClothState, normal_of, rotate};

/// What acts on the cloth from outside, constant over one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    /// Gravity, in m/s².
    pub gravity: Vec3,
    /// Air velocity (wind), in m/s.
    pub wind: Vec3,
    /// Air density `ρ_air`, in kg/m³.
    pub air_density: f32,
    /// Pressure coefficient `C_n` on the element's face.
    pub drag_normal: f32,
    /// Skin-friction coefficient `C_t` along the element.
    pub drag_tangent: f32,
}

impl Default for Environment {
    fn default() -> Self {
        Self {
            gravity: Vec3::new(0.0, 0.0, -9.81),
            wind: Vec3::ZERO,
            air_density: 1.2,
            drag_normal: 1.0,
            drag_tangent: 0.02,
        }
    }
}

/// The acceleration the wind gives an element with normal `n` moving at `v`.
#[inline]
pub fn wind_acceleration(env: &Environment, areal_density: f32, n: Vec3, v: Vec3, dt: f32) -> Vec3 {
    let u = env.wind - v;
    let un = u.dot(n);
    let ut = u - n * un;
    let k = 0.5 * env.air_density / areal_density;
    let normal = n * (k * env.drag_normal * un * un.abs());
    let tangent = ut * (k * env.drag_tangent * ut.length());
    // An explicit drag larger than the relative velocity would overshoot it.
    let cap = |acc: Vec3, rel: f32| {
        let dv = acc.length() * dt;
        if dv > rel && dv > 0.0 {
            acc * (rel / dv)
        } else {
            acc
        }
    };
    cap(normal, un.abs()) + cap(tangent, ut.length())
}

/// Advances every free particle by one substep of length `dt`; pinned
/// particles (no mass, free orientation) only turn.
pub(crate) fn integrate(
    state: &mut ClothState,
    inv_mass: &[f32],
    inv_inertia: &[f32],
    env: &Environment,
    areal_density: f32,
    damping: f32,
    dt: f32,
) {
    let dt2 = dt * dt;
    let with_wind = env.air_density > 0.0 && (env.drag_normal > 0.0 || env.drag_tangent > 0.0);
    for i in 0..state.len() {
        let q = state.orientation[i];
        if inv_mass[i] > 0.0 {
            let x = state.position[i];
            let disp = x - state.prev_position[i];
            let mut acc = env.gravity;
            if with_wind {
                acc += wind_acceleration(env, areal_density, normal_of(q), disp / dt, dt);
            }
            state.prev_position[i] = x;
            state.position[i] = x + disp * damping + acc * dt2;
        }
        if inv_inertia[i] > 0.0 {
            let mut turn = q * state.prev_orientation[i].conjugate();
            if turn.w < 0.0 {
                turn = -turn;
            }
            state.prev_orientation[i] = q;
            state.orientation[i] = rotate(q, rotation_vector(turn) * damping);
        }
    }
}

/// The rotation vector (axis × angle) of a unit quaternion with `w ≥ 0`.
/// Unlike glam's, it never asserts: a NaN stays a NaN for the step to report.
#[inline]
fn rotation_vector(q: glam::Quat) -> Vec3 {
    let v = Vec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s.is_nan() || s <= 1e-9 {
        return v * 2.0;
    }
    v * (2.0 * s.atan2(q.w) / s)
}
