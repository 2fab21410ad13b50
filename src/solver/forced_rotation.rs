//! The forced rotation of §3.4: how far one correction may turn an element.
//!
//! A constraint asks for a full corrective rotation of angle `θ*` (the
//! inertia-weighted projection of its violation). The paper shapes the angle
//! actually applied with its adjustment function, Eq. 3:
//!
//! ```text
//! θ = min(θ*, Φ · exp(−h / θ*))
//! ```
//!
//! The envelope `Φ · exp(−h / ζ)` is the paper's; weft reads its garbled
//! argument as the dimensionless violation `ζ = θ*` (radians), and never turns
//! past the full correction. So:
//! - `h = 0` gives the Φ-capped full correction `min(θ*, Φ)`;
//! - a larger `h` suppresses small corrections (the envelope goes to 0 as
//!   `θ* → 0`) while large ones still approach `Φ`;
//! - no forced rotation ever exceeds `Φ`.
//!
//! The default width comes from mass, inertia and the substep (the paper's
//! `h = 2m / (I Δt²)`), made dimensionless with standard gravity `g₀` and the
//! rest spacing `L`: `h_auto = g₀ / (h_paper · L³) = (I / (m L²)) · (g₀ Δt² / 2L)`,
//! the tilt that gravity alone gives an edge in one substep, scaled by the
//! element's inertia ratio. See `docs/method.md` for the reasoning.

/// Standard gravity, used only to make the default width dimensionless.
pub const STANDARD_GRAVITY: f32 = 9.806_65;

/// Eq. 3 with its two parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForcedRotation {
    /// Cap on one forced rotation, `Φ ∈ [0, π]`.
    pub phi: f32,
    /// Width of the envelope, `h ≥ 0`.
    pub h: f32,
}

impl ForcedRotation {
    /// The angle actually applied for a full corrective angle `full ≥ 0`.
    #[inline]
    pub fn angle(&self, full: f32) -> f32 {
        if full <= 0.0 {
            return 0.0;
        }
        let ratio = self.h / full;
        // exp(−r) ≥ 1 − r: when even that lower bound of the envelope is
        // above the full correction, the min is the full correction (exact,
        // and by far the common case).
        if full <= self.phi * (1.0 - ratio) {
            return full;
        }
        let envelope = if ratio <= 0.0 {
            self.phi
        } else if ratio >= 80.0 {
            // exp(−80) ≈ 2e-35: nothing is left of the correction.
            return 0.0;
        } else {
            self.phi * (-ratio).exp()
        };
        full.min(envelope)
    }

    /// The default width `h` for a particle of `mass` and in-plane `inertia`,
    /// a substep `dt` and a rest spacing `spacing`.
    pub fn auto_width(mass: f32, inertia: f32, dt: f32, spacing: f32) -> f32 {
        let h_paper = 2.0 * mass / (inertia * dt * dt);
        STANDARD_GRAVITY / (h_paper * spacing * spacing * spacing)
    }
}
