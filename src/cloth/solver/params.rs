//! Solver parameters: one plain struct, validated before use.
//!
//! Every parameter has a documented range; [`Params::validate`] rejects an
//! out-of-range or non-finite value with a [`RangeError`] that names the
//! parameter and writes its [`Range`] from the numbers, so a slider, a preset
//! and the command line all get the same message.

use serde::{Deserialize, Serialize};
use std::fmt;

#[cfg(doc)]
use super::families::ConstraintFamily;
use super::families::{Family, PerFamily};

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

/// A value outside its allowed range: the one error of every range check in
/// weft (solver parameters, the cloth, preset fields, the tuning panel). Its
/// text, `allowed: 0 ≤ λ ≤ 1`, is written from the numbers of its [`Range`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{key}` = {value} {}; allowed: {}", self.problem(), self.allowed())]
pub struct RangeError {
    /// Dotted key, as in presets (`weights.normality`, `cloth.weft`).
    pub key: String,
    /// The rejected value, as text.
    pub value: String,
    /// Whether the value (or a component of it) is not a finite number.
    pub not_finite: bool,
    /// The allowed range.
    pub range: Range,
}

/// The solver's name for a [`RangeError`].
pub type ParamError = RangeError;

impl RangeError {
    /// `is not finite` or `is out of range`.
    pub fn problem(&self) -> &'static str {
        if self.not_finite {
            "is not finite"
        } else {
            "is out of range"
        }
    }

    /// The allowed range as text, e.g. `0 < Δt ≤ 0.1 s`; a range without a
    /// symbol is named after the key's last field.
    pub fn allowed(&self) -> String {
        let r = &self.range;
        let symbol = if r.symbol.is_empty() {
            let last = self.key.rsplit('.').next().unwrap_or(&self.key);
            last.split('[').next().unwrap_or(last)
        } else {
            r.symbol
        };
        let (lo, hi, unit) = (number(r.lo), number(r.hi), r.unit);
        let lt = if r.lo_open { "<" } else { "≤" };
        if r.per_component {
            format!("finite components with magnitude ≤ {hi}{unit}")
        } else if r.hi == f32::INFINITY {
            let gt = if r.lo_open { ">" } else { "≥" };
            format!("{symbol} {gt} {lo}{unit}")
        } else if r.lo == -r.hi && !r.lo_open && r.hi > 0.0 {
            format!("|{symbol}| ≤ {hi}{unit}")
        } else {
            format!("{lo} {lt} {symbol} ≤ {hi}{unit}")
        }
    }

    /// The message without the key: `value 2 is out of range; allowed: …`
    /// (for errors that show the key apart, as a preset error does).
    pub fn detail(&self) -> String {
        format!(
            "value {} {}; allowed: {}",
            self.value,
            self.problem(),
            self.allowed()
        )
    }

    /// The same error with its key under `prefix` (`solver.`), unless it already is.
    pub fn under(mut self, prefix: &str) -> Self {
        if !self.key.starts_with(prefix) {
            self.key = format!("{prefix}{}", self.key);
        }
        self
    }
}

/// A number as a range shows it: `π` for π, else its shortest form.
fn number(x: f32) -> String {
    if x == std::f32::consts::PI {
        "π".into()
    } else {
        x.to_string()
    }
}

/// An allowed range `lo ≤ x ≤ hi` (or `lo < x` when `lo_open`), with the
/// symbol and unit its text uses. Every value must also be finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Lower bound.
    pub lo: f32,
    /// Upper bound (`f32::INFINITY`: none).
    pub hi: f32,
    /// Whether `lo` itself is excluded.
    pub lo_open: bool,
    /// Whether every component of a vector is checked against `|c| ≤ hi`.
    pub per_component: bool,
    /// The name in the text (`λ`, `Δt`); empty: the key's last field.
    pub symbol: &'static str,
    /// The unit, with its leading space (` m`), or a remark.
    pub unit: &'static str,
}

impl Range {
    /// `lo ≤ x ≤ hi`.
    pub const fn new(lo: f32, hi: f32) -> Self {
        Self {
            lo,
            hi,
            lo_open: false,
            per_component: false,
            symbol: "",
            unit: "",
        }
    }

    /// `lo < x ≤ hi`.
    pub const fn above(lo: f32, hi: f32) -> Self {
        Self {
            lo_open: true,
            ..Self::new(lo, hi)
        }
    }

    /// `x ≥ lo`.
    pub const fn at_least(lo: f32) -> Self {
        Self::new(lo, f32::INFINITY)
    }

    /// Every component `c` of a vector finite with `|c| ≤ limit`.
    pub const fn components(limit: f32) -> Self {
        Self {
            per_component: true,
            ..Self::new(-limit, limit)
        }
    }

    /// The same range, written with `symbol`.
    pub const fn of(self, symbol: &'static str) -> Self {
        Self { symbol, ..self }
    }

    /// The same range, with a unit (` m`, `°`).
    pub const fn unit(self, unit: &'static str) -> Self {
        Self { unit, ..self }
    }

    fn contains(&self, v: f32) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        above && v <= self.hi
    }

    /// Checks a number.
    pub fn check(self, key: impl Into<String>, v: f32) -> Result<(), RangeError> {
        if v.is_finite() && self.contains(v) {
            return Ok(());
        }
        Err(self.error(key, v.to_string(), !v.is_finite()))
    }

    /// Checks a count.
    pub fn check_count(self, key: impl Into<String>, n: u32) -> Result<(), RangeError> {
        if self.contains(n as f32) {
            return Ok(());
        }
        Err(self.error(key, n.to_string(), false))
    }

    /// Checks every component of a vector.
    pub fn check_each(self, key: impl Into<String>, v: &[f32]) -> Result<(), RangeError> {
        if v.iter().all(|c| c.is_finite() && self.contains(*c)) {
            return Ok(());
        }
        let text = v.iter().map(f32::to_string).collect::<Vec<_>>().join(", ");
        let not_finite = v.iter().any(|c| !c.is_finite());
        Err(self.error(key, format!("[{text}]"), not_finite))
    }

    fn error(self, key: impl Into<String>, value: String, not_finite: bool) -> RangeError {
        RangeError {
            key: key.into(),
            value,
            not_finite,
            range: self,
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
