//! Allowed ranges: the one check and the one error of every bounded value
//! in weft (solver parameters, the cloth, preset fields, the tuning panel).
//!
//! A [`Range`] knows its bounds, symbol and unit; a failed check is a
//! [`RangeError`] that names the key and writes the range from the numbers
//! (`allowed: 0 ≤ λ ≤ 1`), so a slider, a preset and the command line all
//! get the same message. A leaf: it uses nothing else of the solver.

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
