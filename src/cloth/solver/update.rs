//! The update phase of §3.2: every particle moves on its own.
//!
//! Störmer integration with damping `k`, velocity approximated by the last
//! displacement, damped relative to the reference motion `r` of what the
//! particle hangs from (Müller et al. 2007 §3.5 damp only what is not
//! carried along):
//!
//! ```text
//! Δx(t+Δt) = r + k · (x(t) − x(t−Δt) − r) + a(t) · Δt²,   x_update = x(t) + Δx(t+Δt)
//! ```
//!
//! Orientation is advanced the same way: the last rotation
//! `q(t) q(t−Δt)⁻¹`, relative to the reference body's own turn, as a
//! rotation vector scaled by `k`, is applied again on top of that turn.
//!
//! Positions are measured from the solver's floating origin
//! ([`super::frame`]): the update adds the frame's kick `D_prev − D` (the
//! fictitious force of an accelerating origin), and air drag sees the world
//! velocity, the particle's motion plus the origin's.
//!
//! The acceleration is gravity plus wind acting on the oriented element. With
//! relative wind `u = v_air − v` and normal `n`, the pressure on the element is
//! `½ ρ_air C_n (u·n)|u·n|` along `n`, plus a small skin friction
//! `½ ρ_air C_t |u_t| u_t` along the tangential part `u_t`; divided by the areal
//! density `ρ_A` this is an acceleration. A flag edge-on to the wind (`u·n = 0`)
//! feels only skin friction. The change of velocity the wind gives in one
//! substep is capped at the relative velocity itself, so a light element is
//! carried along by the wind instead of overshooting it.

use glam::{Quat, Vec3};

use super::{
    cloth::ClothState,
    collision::Pose,
    kernels::Shared,
    rotation::{normal_of, rotate},
    team,
};

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
///
/// The drag's two parts are `n · k C_n u_n |u_n|` and `u_t · k C_t |u_t|`, so
/// their magnitudes are `k C_n u_n²` and `k C_t |u_t|²` (`|n| = 1`): the cap
/// takes them from the speeds, not from the lengths of the acceleration
/// vectors. Squaring those vectors' components, which for a slowly moving
/// element are tiny, made subnormal numbers, and a settled sheet in still
/// air spent half its update phase in their slow arithmetic (BENCHMARKS.md,
/// "Measured design choices").
#[inline]
pub fn wind_acceleration(env: &Environment, areal_density: f32, n: Vec3, v: Vec3, dt: f32) -> Vec3 {
    let u = env.wind - v;
    let un = u.dot(n);
    let ut = u - n * un;
    let ut_len = ut.length();
    let k = 0.5 * env.air_density / areal_density;
    let normal = k * env.drag_normal * un * un.abs();
    let tangent = k * env.drag_tangent * ut_len;
    // An explicit drag larger than the relative velocity would overshoot it:
    // the factor that caps an acceleration of magnitude `acc` at `rel / dt`.
    let cap = |acc: f32, rel: f32| {
        let dv = acc * dt;
        if dv > rel && dv > 0.0 { rel / dv } else { 1.0 }
    };
    n * (normal * cap(normal.abs(), un.abs())) + ut * (tangent * cap(tangent * ut_len, ut_len))
}

/// What damping measures velocities against: for each particle, the body
/// whose motion it follows (its tether's anchor's body), or the cloth's own
/// mean motion for a cloth that hangs from nothing.
pub(crate) struct Reference<'a> {
    /// Per particle, the index of its reference body; [`FREE`] for none.
    pub body_of: &'a [u32],
    /// Each body's pose at the start and at the end of the last substep.
    pub from: &'a [Pose],
    /// See `from`.
    pub to: &'a [Pose],
}

/// How the floating origin moves, as one substep's update sees it
/// ([`super::frame`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FrameMotion {
    /// The origin's motion over the substep before (added to a particle's
    /// own motion for its world velocity, which air drag sees).
    pub before: Vec3,
    /// The frame's kick: `D_prev − D`, the fictitious force of an
    /// accelerating origin, as a displacement.
    pub kick: Vec3,
}

/// [`Reference::body_of`] for a particle that follows no body.
pub(crate) const FREE: u32 = u32::MAX;

/// Advances every free particle by one substep of length `dt`; pinned
/// particles (no mass, free orientation) only turn. Each particle moves on
/// its own, so `threads` threads each take a contiguous share and the
/// result is the same for any number of them.
///
/// Damping keeps a fraction `damping` of each particle's velocity *relative
/// to its reference motion*: the rigid motion of the body it hangs from
/// (over the last substep), or the mass-weighted mean motion of the cloth.
/// Uniform motion, and the motion of whatever carries the cloth, are left
/// alone, so the result does not depend on the frame of reference; only the
/// air drag sees world velocity.
#[allow(clippy::too_many_arguments)] // the update's inputs, each a distinct slice or scalar
pub(crate) fn integrate(
    state: &mut ClothState,
    inv_mass: &[f32],
    inv_inertia: &[f32],
    reference: &Reference,
    frame: FrameMotion,
    env: &Environment,
    areal_density: f32,
    damping: f32,
    dt: f32,
    threads: usize,
) {
    let mean = mean_displacement(state, inv_mass, reference.body_of);
    // Each body's rigid motion over the last substep, `to ∘ from⁻¹`, once.
    let motions: Vec<Pose> = reference
        .from
        .iter()
        .zip(reference.to)
        .map(|(from, to)| {
            let rotation = (to.rotation * from.rotation.conjugate()).normalize();
            Pose::new(to.translation - rotation * from.translation, rotation)
        })
        .collect();
    let step = Step {
        env,
        with_wind: env.air_density > 0.0 && (env.drag_normal > 0.0 || env.drag_tangent > 0.0),
        areal_density,
        damping,
        dt,
        mean,
        motions: &motions,
        frame,
    };
    let n = state.len();
    let (x, prev_x) = (
        Shared::new(&mut state.position),
        Shared::new(&mut state.prev_position),
    );
    let (q, prev_q) = (
        Shared::new(&mut state.orientation),
        Shared::new(&mut state.prev_orientation),
    );
    team::run(threads, |crew| {
        let mine = crew.share(n);
        // SAFETY: the shares are disjoint, and a particle's update reads and
        // writes only that particle.
        let (x, prev_x, q, prev_q) = unsafe {
            (
                x.slice(mine.clone()),
                prev_x.slice(mine.clone()),
                q.slice(mine.clone()),
                prev_q.slice(mine.clone()),
            )
        };
        for (k, i) in mine.enumerate() {
            let carrier = step.motions.get(reference.body_of[i] as usize);
            if inv_mass[i] > 0.0 {
                step.translate(carrier, q[k], &mut x[k], &mut prev_x[k]);
            }
            if inv_inertia[i] > 0.0 {
                step.rotate(carrier, &mut q[k], &mut prev_q[k]);
            }
        }
    });
}

/// What every particle's update reads.
struct Step<'a> {
    env: &'a Environment,
    with_wind: bool,
    areal_density: f32,
    damping: f32,
    dt: f32,
    /// The cloth's mean displacement, for particles that follow no body.
    mean: Vec3,
    /// Each body's rigid motion over the last substep.
    motions: &'a [Pose],
    /// How the origin moves (a zero motion or kick is not added: the bits
    /// stay those of a frame at rest).
    frame: FrameMotion,
}

impl Step<'_> {
    /// Moves a free particle with orientation `q`, carried by `carrier`.
    #[inline]
    fn translate(&self, carrier: Option<&Pose>, q: Quat, x: &mut Vec3, prev: &mut Vec3) {
        let (now, before) = (*x, *prev);
        let disp = now - before;
        let carried = carrier.map_or(self.mean, |m| m.transform_point(before) - before);
        let mut acc = self.env.gravity;
        if self.with_wind {
            let world = if self.frame.before != Vec3::ZERO {
                disp + self.frame.before
            } else {
                disp
            };
            let v = world / self.dt;
            acc += wind_acceleration(self.env, self.areal_density, normal_of(q), v, self.dt);
        }
        *prev = now;
        let next = now + carried + (disp - carried) * self.damping + acc * (self.dt * self.dt);
        *x = if self.frame.kick != Vec3::ZERO {
            next + self.frame.kick
        } else {
            next
        };
    }

    /// Turns a particle with inertia, carried by `carrier`.
    #[inline]
    fn rotate(&self, carrier: Option<&Pose>, q: &mut Quat, prev: &mut Quat) {
        let now = *q;
        let carried = carrier.map_or(Quat::IDENTITY, |m| m.rotation);
        let mut relative = now * prev.conjugate() * carried.conjugate();
        if relative.w < 0.0 {
            relative = -relative;
        }
        *prev = now;
        *q = rotate(carried * now, rotation_vector(relative) * self.damping);
    }
}

/// The mass-weighted mean displacement over the last substep of the free
/// particles that follow no body (zero if there are none).
fn mean_displacement(state: &ClothState, inv_mass: &[f32], body_of: &[u32]) -> Vec3 {
    let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0f64);
    for i in 0..state.len() {
        if inv_mass[i] > 0.0 && body_of[i] == FREE {
            let m = 1.0 / inv_mass[i] as f64;
            sum += (state.position[i] - state.prev_position[i]).as_dvec3() * m;
            weight += m;
        }
    }
    if weight > 0.0 {
        (sum / weight).as_vec3()
    } else {
        Vec3::ZERO
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
    v * (2.0 * super::portable::atan2(s, q.w) / s)
}
