//! Solver parameters: one plain struct, validated before use.
//!
//! Every parameter has a documented range; [`Params::validate`] rejects an
//! out-of-range or non-finite value with a [`ParamError`] that names the
//! parameter and its range, so a slider, a preset and the command line all get
//! the same message.

use serde::{Deserialize, Serialize};
use std::fmt;

use super::Family;

/// The per-family constraint weights `λ`, each in `[0, 1]`.
///
/// A weight sets how stiff its family is, independently of iterations,
/// substeps and resolution: `λ = 0` turns the family off, `λ = 1` makes it
/// rigid, and in between its compliance (inverse stiffness, XPBD's `α`) is
/// [`compliance_factor`]`(λ)` times the family's reference compliance
/// ([`REFERENCE_COMPLIANCE`]): `((1 − λ) / λ)²`, so `λ = ½` is the
/// reference material and each step of 0.1 around it is about a factor of
/// two in stiffness. See `docs/method.md` ("Weights").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Weights {
    /// Length limit on weft and warp edges (and the tethers).
    pub stretch: f32,
    /// Co-planarity of neighbours (each lies in the other's tangent plane).
    pub planarity: f32,
    /// Co-normality of neighbours (their normals agree) and, as the paper
    /// pairs them, in-plane shear (the cell diagonals).
    pub normality: f32,
    /// Co-circularity of bend runs: smooth curvature.
    pub curvature: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Self {
            stretch: 1.0,
            planarity: 0.5,
            normality: 0.2,
            curvature: 0.1,
        }
    }
}

impl Weights {
    /// The weight of one family.
    pub fn get(&self, family: Family) -> f32 {
        match family {
            Family::Stretch => self.stretch,
            Family::Planarity => self.planarity,
            Family::Normality => self.normality,
            Family::Curvature => self.curvature,
        }
    }

    /// Mutable access to the weight of one family (for sliders).
    pub fn get_mut(&mut self, family: Family) -> &mut f32 {
        match family {
            Family::Stretch => &mut self.stretch,
            Family::Planarity => &mut self.planarity,
            Family::Normality => &mut self.normality,
            Family::Curvature => &mut self.curvature,
        }
    }
}

/// The reference compliances `α_ref` (at `λ = ½`) of the constraint kinds,
/// for a square cell. A cell of aspect `w / L` (extent across the constraint
/// over its length) divides them by `w / L`, so that the same physical cloth
/// behaves the same at any resolution (see `docs/method.md`).
pub struct ReferenceCompliance {
    /// Weft and warp edges, m/N: the inverse of the cloth's stretch
    /// stiffness `E·t` (1000 N/m at `λ = ½`).
    pub stretch: f32,
    /// Cell diagonals (shear, under the normality weight), m/N: the inverse
    /// of the in-plane shear stiffness `G·t` (2 N/m at `λ = ½`).
    pub shear: f32,
    /// Planarity angles, 1/(N·m): the inverse of the rigidity tying each
    /// normal to the surface around it (1e-5 N·m at `λ = ½`).
    pub planarity: f32,
    /// Normality angles, 1/(N·m): the inverse of the rigidity with which
    /// neighbouring normals agree (1e-5 N·m at `λ = ½`).
    pub normality: f32,
    /// Curvature angles, 1/(N·m): the inverse of the bending rigidity `B`
    /// (1e-5 N·m at `λ = ½`, a light cotton).
    pub curvature: f32,
}

/// The reference compliances weft uses.
pub const REFERENCE_COMPLIANCE: ReferenceCompliance = ReferenceCompliance {
    stretch: 1e-3,
    shear: 0.5,
    planarity: 1e5,
    normality: 1e5,
    curvature: 1e5,
};

/// How a weight scales its family's reference compliance: `((1 − λ) / λ)²`
/// (0 at `λ = 1`, 1 at `λ = ½`, unbounded as `λ → 0`).
#[inline]
pub fn compliance_factor(weight: f32) -> f32 {
    if weight >= 1.0 {
        return 0.0;
    }
    let r = (1.0 - weight) / weight.max(1e-6);
    r * r
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
            weights: Weights::default(),
            phi: std::f32::consts::FRAC_PI_4,
            h: Width::Auto,
            iterations: 4,
            dt: 1.0 / 60.0,
            substeps: 8,
        }
    }
}

/// A parameter that failed validation.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("parameter `{name}` = {value} {problem}; allowed: {range}")]
pub struct ParamError {
    /// Dotted name, as in presets (`weights.curvature`).
    pub name: &'static str,
    /// The rejected value, as text.
    pub value: String,
    /// What is wrong: out of range, or not finite.
    pub problem: &'static str,
    /// The allowed range, human readable.
    pub range: &'static str,
}

/// Checks that `value` is finite and within `[lo, hi]` (or `(lo, hi]` when `open_lo`).
pub(crate) fn check_range(
    name: &'static str,
    value: f32,
    lo: f32,
    hi: f32,
    open_lo: bool,
    range: &'static str,
) -> Result<(), ParamError> {
    let err = |problem| ParamError {
        name,
        value: value.to_string(),
        problem,
        range,
    };
    if !value.is_finite() {
        return Err(err("is not finite"));
    }
    let below = if open_lo { value <= lo } else { value < lo };
    if below || value > hi {
        return Err(err("is out of range"));
    }
    Ok(())
}

fn check_count(
    name: &'static str,
    value: u32,
    lo: u32,
    hi: u32,
    range: &'static str,
) -> Result<(), ParamError> {
    if value < lo || value > hi {
        return Err(ParamError {
            name,
            value: value.to_string(),
            problem: "is out of range",
            range,
        });
    }
    Ok(())
}

impl Params {
    /// Checks every parameter against its range; the first violation is returned.
    pub fn validate(&self) -> Result<(), ParamError> {
        check_range("damping", self.damping, 0.0, 1.0, false, "0 ≤ k ≤ 1")?;
        let w = &self.weights;
        check_range("weights.stretch", w.stretch, 0.0, 1.0, false, "0 ≤ λ ≤ 1")?;
        check_range(
            "weights.planarity",
            w.planarity,
            0.0,
            1.0,
            false,
            "0 ≤ λ ≤ 1",
        )?;
        check_range(
            "weights.normality",
            w.normality,
            0.0,
            1.0,
            false,
            "0 ≤ λ ≤ 1",
        )?;
        check_range(
            "weights.curvature",
            w.curvature,
            0.0,
            1.0,
            false,
            "0 ≤ λ ≤ 1",
        )?;
        check_range(
            "phi",
            self.phi,
            0.0,
            std::f32::consts::PI,
            false,
            "0 ≤ Φ ≤ π (radians)",
        )?;
        if let Width::Fixed(h) = self.h {
            check_range("h", h, 0.0, f32::MAX, false, "\"auto\" or h ≥ 0 (radians)")?;
        }
        check_count(
            "iterations",
            self.iterations,
            1,
            200,
            "1 ≤ iterations ≤ 200",
        )?;
        check_range("dt", self.dt, 0.0, 0.1, true, "0 < Δt ≤ 0.1 s")?;
        check_count("substeps", self.substeps, 1, 64, "1 ≤ substeps ≤ 64")?;
        Ok(())
    }

    /// The damping applied per substep, `k^(1 / substeps)`: `k` is what is
    /// kept of the velocity over a whole `Δt`, whatever the substeps.
    pub fn substep_damping(&self) -> f32 {
        self.damping.powf(1.0 / self.substeps as f32)
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
