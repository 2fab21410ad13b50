//! Solver parameters: one plain struct, validated before use.
//!
//! Every parameter has a documented [`Range`]; [`Params::validate`] rejects
//! an out-of-range or non-finite value with a [`RangeError`] that names the
//! parameter and its allowed range.

use serde::{Deserialize, Serialize};
use std::fmt;

#[cfg(doc)]
use super::families::ConstraintFamily;
#[cfg(doc)]
use super::families::compliance_factor;
use super::families::{Family, PerFamily};
use super::range::{Range, RangeError};

/// The per-family constraint weights `λ`, each in `[0, 1]`.
///
/// A weight sets how stiff its family is, independently of iterations,
/// substeps and resolution: `λ = 0` turns the family off, `λ = 1` makes it
/// rigid, and in between its compliance (inverse stiffness, XPBD's `α`) is
/// [`compliance_factor`]`(λ)` times the family's reference compliance
/// (`ConstraintFamily::REFERENCE_COMPLIANCE`): `((1 − λ) / λ)²`, so `λ = ½` is the
/// reference material and each step of 0.1 around it is about a factor of
/// two in stiffness. See `docs/method.md` ("Weights").
/// The defaults are [`PerFamily::default_weights`].
pub type Weights = PerFamily<f32>;

/// Reads `[solver.weights]` over the default weights.
fn weights_over_defaults<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Weights, D::Error> {
    Weights::deserialize_over(Weights::default_weights(), d)
}

/// The width `h` of the forced-rotation envelope (Eq. 3).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Width {
    /// The default, [`DEFAULT_WIDTH`](super::forced_rotation::DEFAULT_WIDTH):
    /// one angle for every resolution and substep (see `docs/method.md`, Eq. 3).
    #[default]
    Auto,
    /// A fixed, dimensionless width `h ≥ 0`, in radians.
    Fixed(f32),
}

impl Serialize for Width {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Width::Auto => s.serialize_str("auto"),
            Width::Fixed(h) => s.serialize_f32(*h),
        }
    }
}

impl<'de> Deserialize<'de> for Width {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Width;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("\"auto\" or a number h ≥ 0")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Width, E> {
                if v == "auto" {
                    Ok(Width::Auto)
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Width, E> {
                Ok(Width::Fixed(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Width, E> {
                Ok(Width::Fixed(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Width, E> {
                Ok(Width::Fixed(v as f32))
            }
        }
        d.deserialize_any(V)
    }
}

/// Everything the solver is tuned with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Damping `k ∈ [0, 1]` of the Störmer update, for position and orientation:
    /// the fraction of velocity *relative to what the cloth hangs from* kept
    /// over one `Δt` (1 keeps all, 0 none), applied as `k^(1/substeps)` per
    /// substep. Uniform motion is never damped (see [`update`](super::update)).
    pub damping: f32,
    /// Constraint weights `λ` per family.
    #[serde(deserialize_with = "weights_over_defaults")]
    pub weights: Weights,
    /// Cap `Φ ∈ [0, π]` on one forced rotation, in radians (Eq. 3).
    pub phi: f32,
    /// Width `h` of the forced-rotation envelope (Eq. 3).
    pub h: Width,
    /// Adjust iterations per substep, in `[1, 200]`.
    pub iterations: u32,
    /// Frame time step `Δt` in seconds, in `(0, 0.1]`.
    pub dt: f32,
    /// Substeps per frame step, in `[1, 64]`; each substep is `Δt / substeps`.
    pub substeps: u32,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            damping: 0.99,
            weights: Weights::default_weights(),
            phi: std::f32::consts::FRAC_PI_4,
            h: Width::Auto,
            iterations: 4,
            dt: 1.0 / 60.0,
            substeps: 8,
        }
    }
}

impl Params {
    /// Checks every parameter against its range; the first violation is returned.
    pub fn validate(&self) -> Result<(), RangeError> {
        Range::new(0.0, 1.0)
            .of("k")
            .check("damping", self.damping)?;
        for f in Family::ALL {
            let weight = Range::new(0.0, 1.0).of("λ");
            weight.check(format!("weights.{}", f.name()), self.weights[f])?;
        }
        let phi = Range::new(0.0, std::f32::consts::PI).of("Φ").unit(" rad");
        phi.check("phi", self.phi)?;
        if let Width::Fixed(h) = self.h {
            Range::at_least(0.0)
                .unit(" rad (or \"auto\")")
                .check("h", h)?;
        }
        Range::new(1.0, 200.0).check_count("iterations", self.iterations)?;
        Range::above(0.0, 0.1)
            .of("Δt")
            .unit(" s")
            .check("dt", self.dt)?;
        Range::new(1.0, 64.0).check_count("substeps", self.substeps)?;
        Ok(())
    }

    /// The damping applied per substep, `k^(1 / substeps)`: `k` is what is
    /// kept of the velocity over a whole `Δt`, whatever the substeps.
    pub fn substep_damping(&self) -> f32 {
        super::portable::powf(self.damping, 1.0 / self.substeps as f32)
    }

    /// The width `h` of Eq. 3 in force.
    pub fn width(&self) -> f32 {
        match self.h {
            Width::Auto => super::forced_rotation::DEFAULT_WIDTH,
            Width::Fixed(h) => h,
        }
    }

    /// The substep length `Δt / substeps`, in seconds.
    pub fn substep_dt(&self) -> f32 {
        self.dt / self.substeps as f32
    }
}
