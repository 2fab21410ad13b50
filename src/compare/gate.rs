//! `--fail-if`: a regression gate over compared runs.
//!
//! A bound is `FIGURE OP LIMIT`:
//!
//! - `FIGURE`: `max_strain`, `max_violation.FAMILY` (any of
//!   [`Family::NAMES`](crate::solver::Family::NAMES)), `final_energy`,
//!   `steps_per_second`, `wall_seconds`, `frames`, `sim_seconds`;
//! - `OP`: `>`, `>=`, `<`, `<=`: the run *fails* when `value OP LIMIT` holds;
//! - `LIMIT`: a number (`0.05`), or relative to the first run `A`:
//!   `A`, `1.1*A`, `A*1.1`, `A+0.002`, `1.1*A-0.001`.
//!
//! A relative bound checks every run but `A`; an absolute one checks every
//! run. Examples: `max_strain > 1.1*A`, `steps_per_second < 0.8*A`,
//! `max_violation.stretch > 0.05`.

use std::fmt;
use std::str::FromStr;

use super::{RunData, figure, figure_names};

/// A comparison operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `<`
    Lt,
    /// `<=`
    Le,
}

impl Op {
    fn holds(self, a: f64, b: f64) -> bool {
        match self {
            Op::Gt => a > b,
            Op::Ge => a >= b,
            Op::Lt => a < b,
            Op::Le => a <= b,
        }
    }
}

/// The right-hand side: `scale * A + offset`, or a plain number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// A fixed number.
    Absolute(f64),
    /// `scale * A + offset`, `A` being the first run's value.
    Relative {
        /// Multiplies `A`.
        scale: f64,
        /// Added after.
        offset: f64,
    },
}

/// One `--fail-if` bound.
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    /// As written.
    pub text: String,
    /// The figure's name.
    pub figure: String,
    /// The operator.
    pub op: Op,
    /// The limit.
    pub limit: Limit,
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// How a bound is written.
const SYNTAX: &str = "expected FIGURE OP LIMIT, e.g. `max_strain > 1.1*A` (OP: > >= < <=; LIMIT: a number, or A, k*A, A+k, k*A-k)";

/// A `--fail-if` bound that does not parse.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("--fail-if `{text}`: {problem}")]
pub struct BoundError {
    /// The bound, as written.
    pub text: String,
    /// What is wrong with it.
    pub problem: BoundProblem,
}

/// What is wrong with a `--fail-if` bound.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BoundProblem {
    /// No `>`, `>=`, `<` or `<=`.
    #[error("no comparison; {SYNTAX}")]
    NoComparison,
    /// The figure is not one weft measures.
    #[error("unknown figure `{name}`{}; figures: {}", hint.as_ref().map(|n| format!(" (did you mean `{n}`?)")).unwrap_or_default(), figure_names().join(", "))]
    UnknownFigure {
        /// The name given.
        name: String,
        /// The nearest figure's name.
        hint: Option<String>,
    },
    /// Nothing after the comparison.
    #[error("no limit; {SYNTAX}")]
    NoLimit,
    /// A part that should be a number is not.
    #[error("`{0}` is not a number")]
    NotANumber(String),
    /// A factor not written as `k*A`.
    #[error("write the factor as `k*A`; {SYNTAX}")]
    Factor,
    /// Something after the limit.
    #[error("unexpected `{0}`; {SYNTAX}")]
    Unexpected(String),
}

fn number(s: &str) -> Result<f64, BoundProblem> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| BoundProblem::NotANumber(s.to_string()))
}

impl FromStr for Bound {
    type Err = BoundError;

    fn from_str(text: &str) -> Result<Self, BoundError> {
        Self::parse(text).map_err(|problem| BoundError {
            text: text.to_string(),
            problem,
        })
    }
}

impl Bound {
    fn parse(text: &str) -> Result<Self, BoundProblem> {
        let (i, op, len) = [(">=", Op::Ge), ("<=", Op::Le), (">", Op::Gt), ("<", Op::Lt)]
            .iter()
            .find_map(|(s, op)| text.find(s).map(|i| (i, *op, s.len())))
            .ok_or(BoundProblem::NoComparison)?;
        let name = text[..i].trim();
        let rhs: String = text[i + len..]
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
        if !figure_names().iter().any(|n| n == name) {
            let names = figure_names();
            let hint = crate::scene::load::nearest(name, names.iter().map(|s| s.as_str()));
            return Err(BoundProblem::UnknownFigure {
                name: name.to_string(),
                hint: hint.map(str::to_string),
            });
        }
        if rhs.is_empty() {
            return Err(BoundProblem::NoLimit);
        }
        let limit = match rhs.find('A') {
            None => Limit::Absolute(number(&rhs)?),
            Some(a) => {
                let before = &rhs[..a];
                let after = &rhs[a + 1..];
                let mut scale = match before {
                    "" => 1.0,
                    b => number(b.strip_suffix('*').ok_or(BoundProblem::Factor)?)?,
                };
                let mut rest = after;
                if let Some(r) = rest.strip_prefix('*') {
                    let end = r.find(['+', '-']).filter(|i| *i > 0).unwrap_or(r.len());
                    scale *= number(&r[..end])?;
                    rest = &r[end..];
                }
                let offset = match rest {
                    "" => 0.0,
                    r if r.starts_with('+') || r.starts_with('-') => number(r)?,
                    r => return Err(BoundProblem::Unexpected(r.to_string())),
                };
                Limit::Relative { scale, offset }
            }
        };
        Ok(Self {
            text: text.trim().to_string(),
            figure: name.to_string(),
            op,
            limit,
        })
    }
}

/// A run that crossed a bound.
#[derive(Clone, Debug, PartialEq)]
pub struct Regression {
    /// The run's name.
    pub run: String,
    /// The bound, as written.
    pub bound: String,
    /// What the run measured.
    pub value: f64,
    /// The limit it was held to.
    pub limit: f64,
}

/// Checks every bound on every run it applies to; returns what regressed.
pub fn check(bounds: &[Bound], runs: &[RunData]) -> Vec<Regression> {
    let mut out = Vec::new();
    let Some(a) = runs.first() else {
        return out;
    };
    for b in bounds {
        let base = figure(&a.figures, &b.figure).unwrap_or(0.0);
        let (limit, skip_a) = match b.limit {
            Limit::Absolute(v) => (v, false),
            Limit::Relative { scale, offset } => (scale * base + offset, true),
        };
        for r in runs.iter().skip(skip_a as usize) {
            let value = figure(&r.figures, &b.figure).unwrap_or(0.0);
            if b.op.holds(value, limit) {
                out.push(Regression {
                    run: r.name.clone(),
                    bound: b.text.clone(),
                    value,
                    limit,
                });
            }
        }
    }
    out
}

/// The table of regressions, for the terminal.
pub fn table(regressions: &[Regression], bounds: &[Bound]) -> String {
    let width = regressions
        .iter()
        .map(|r| r.run.len())
        .max()
        .unwrap_or(3)
        .max(3);
    let mut s = format!(
        "regressed ({} of the bounds {}):\n",
        regressions.len(),
        bounds
            .iter()
            .map(|b| format!("`{b}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s += &format!(
        "  {:<width$}  {:<32} {:>12} {:>12}\n",
        "run", "bound", "measured", "limit"
    );
    for r in regressions {
        s += &format!(
            "  {:<width$}  {:<32} {:>12} {:>12}\n",
            r.run,
            r.bound,
            format!("{:.4e}", r.value),
            format!("{:.4e}", r.limit)
        );
    }
    s
}
