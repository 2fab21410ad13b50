//! The distance a fit minimises: to a reference run, and to target figures.
//!
//! A flapping flag is chaotic, so two runs' particles part within a second
//! and a frame-by-frame error measures noise. The distance to a reference
//! compares what stays stable and what a person sees (see
//! `docs/method.md`, "The fit's distance"):
//!
//! | term | what | scale |
//! |---|---|---|
//! | `shape` | RMS distance between the lattice points' mean positions | the cloth's larger side `L` |
//! | `spread` | RMS difference of the lattice points' spreads | `L` |
//! | `amplitude` | the free edge's flapping amplitudes | the larger of the two (at least `L/20`) |
//! | `frequency` | the free edge's dominant frequencies, in octaves | counted only as far as both edges move (`L/20` fully) |
//! | `drape` | the drape coefficients (the cloth's shadow beyond what is held) | 1 |
//! | `strain` | the largest edge strain, averaged over time (runs on the same grid only) | the larger of the two (at least 0.02) |
//! | `horizon` | the candidate restarted from the reference's states, its RMS error after a short horizon (same grid only) | `L` |
//!
//! `D = shape + spread + ¼ amplitude + ¼ frequency + 2 drape + ¼ strain + horizon`.
//! Every term but `horizon` is symmetric in the two runs, so
//! `D(a, b) = D(b, a)` without it, and `D(a, a) = 0` with it.
//!
//! A target figure `F=V` adds `|F − V| / max(|V|, 0.001)`; a bound `F<=V`
//! (or `F>=V`) adds the same only when it is crossed. Each target, and the
//! reference, is multiplied by its weight (`@W`, 1 unless given).

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::measure::{Features, MEASURED};
use crate::compare::{figure, figure_names};
use crate::record::Figures;
use crate::scene::load::nearest;

/// The weights of the reference distance's terms, in the order of [`Terms`].
pub const WEIGHTS: [f64; 7] = [1.0, 1.0, 0.25, 0.25, 2.0, 0.25, 1.0];

/// The terms of the distance to a reference, each unweighted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Terms {
    /// Mean shape, in cloth lengths.
    pub shape: f64,
    /// Spread, in cloth lengths.
    pub spread: f64,
    /// Free-edge amplitude, relative.
    pub amplitude: f64,
    /// Free-edge frequency, in octaves (damped where the edge barely moves).
    pub frequency: f64,
    /// Drape coefficient, absolute.
    pub drape: f64,
    /// Mean strain, relative.
    pub strain: f64,
    /// Short-horizon error from the reference's states, in cloth lengths
    /// (0 where there is none: another grid).
    pub horizon: f64,
}

impl Terms {
    /// The weighted sum.
    pub fn total(&self) -> f64 {
        let t = [
            self.shape,
            self.spread,
            self.amplitude,
            self.frequency,
            self.drape,
            self.strain,
            self.horizon,
        ];
        t.iter().zip(WEIGHTS).map(|(t, w)| t * w).sum()
    }
}

/// `|a − b|` over the larger of `a`, `b` and `floor`.
fn relative(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(floor)
}

/// The distance between two runs' features, measured on the same lattice
/// (`length`: the cloth's larger side).
pub fn between(a: &Features, b: &Features, length: f64) -> Terms {
    let n = a.mean.len().min(b.mean.len()).max(1) as f64;
    let shape = (a
        .mean
        .iter()
        .zip(&b.mean)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]) * (p[k] - q[k])).sum::<f64>())
        .sum::<f64>()
        / n)
        .sqrt()
        / length;
    let spread = (a
        .spread
        .iter()
        .zip(&b.spread)
        .map(|(p, q)| (p - q) * (p - q))
        .sum::<f64>()
        / n)
        .sqrt()
        / length;
    // Amplitudes below L/20 (a cloth that hangs still, a settled drape's
    // corners) are compared in absolute terms: their relative differences
    // are noise.
    let amplitude = relative(a.edge_amplitude, b.edge_amplitude, 0.05 * length);
    let moving = (a.edge_amplitude.min(b.edge_amplitude) / (0.05 * length)).min(1.0);
    let frequency = if a.edge_frequency > 0.0 && b.edge_frequency > 0.0 {
        (a.edge_frequency.log2() - b.edge_frequency.log2()).abs() * moving
    } else {
        0.0
    };
    // An edge's strain depends on the edge's length (a finer grid resolves
    // finer wrinkles), so it is compared only between runs on one grid.
    let strain = if a.grid == b.grid {
        relative(a.mean_strain, b.mean_strain, 0.02)
    } else {
        0.0
    };
    Terms {
        shape,
        spread,
        amplitude,
        frequency,
        drape: (a.drape_coefficient - b.drape_coefficient).abs(),
        strain,
        horizon: 0.0,
    }
}

/// How a target figure is compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Goal {
    /// `F=V`: as close to `V` as can be.
    Equal,
    /// `F<=V`: at most `V`.
    AtMost,
    /// `F>=V`: at least `V`.
    AtLeast,
}

/// One `--target FIGURE=VALUE[@WEIGHT]` (or `<=`, `>=`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// The figure's name.
    pub figure: String,
    /// How it is compared.
    pub goal: Goal,
    /// The value.
    pub value: f64,
    /// Its weight in the distance.
    pub weight: f64,
}

/// A `--target` that does not parse or names no figure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TargetError {
    /// Not `FIGURE=VALUE`.
    #[error(
        "--target {0}: expected FIGURE=VALUE, FIGURE<=VALUE or FIGURE>=VALUE, optionally @WEIGHT (e.g. drape_coefficient=0.45 or max_strain<=0.1@2)"
    )]
    Form(String),
    /// A value or weight that is not a finite number (a weight must be positive).
    #[error("--target {text}: `{part}` is not a {what}")]
    Number {
        /// The target as written.
        text: String,
        /// The part that is wrong.
        part: String,
        /// What it should be.
        what: &'static str,
    },
    /// A figure that does not exist.
    #[error("--target {text}: no figure `{figure}`{}; figures: {}", hint.as_ref().map(|h| format!(" (did you mean `{h}`?)")).unwrap_or_default(), target_figures().join(", "))]
    Figure {
        /// The target as written.
        text: String,
        /// The figure given.
        figure: String,
        /// The nearest figure's name.
        hint: Option<String>,
    },
}

/// Every figure a target may name: the measured ones, then the run
/// summary's (all but the wall-clock ones, which differ from run to run).
pub fn target_figures() -> Vec<String> {
    MEASURED
        .iter()
        .map(|(n, _)| n.to_string())
        .chain(
            figure_names()
                .into_iter()
                .filter(|n| !["steps_per_second", "wall_seconds"].contains(&n.as_str())),
        )
        .collect()
}

/// A figure of a run by name: measured, or from its summary.
pub fn figure_of(features: &Features, figures: &Figures, name: &str) -> Option<f64> {
    features.figure(name).or_else(|| figure(figures, name))
}

impl FromStr for Target {
    type Err = TargetError;

    fn from_str(s: &str) -> Result<Self, TargetError> {
        let (body, weight) = match s.rsplit_once('@') {
            Some((b, w)) => (b, Some(w)),
            None => (s, None),
        };
        let (figure, goal, value) = if let Some((f, v)) = body.split_once("<=") {
            (f, Goal::AtMost, v)
        } else if let Some((f, v)) = body.split_once(">=") {
            (f, Goal::AtLeast, v)
        } else if let Some((f, v)) = body.split_once('=') {
            (f, Goal::Equal, v)
        } else {
            return Err(TargetError::Form(s.into()));
        };
        let figure = figure.trim();
        if figure.is_empty() {
            return Err(TargetError::Form(s.into()));
        }
        let number = |part: &str, what: &'static str, positive: bool| {
            part.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && (!positive || *v > 0.0))
                .ok_or_else(|| TargetError::Number {
                    text: s.into(),
                    part: part.into(),
                    what,
                })
        };
        let value = number(value, "finite number", false)?;
        let weight = match weight {
            Some(w) => number(w, "positive weight", true)?,
            None => 1.0,
        };
        let names = target_figures();
        if !names.iter().any(|n| n == figure) {
            return Err(TargetError::Figure {
                text: s.into(),
                figure: figure.into(),
                hint: nearest(figure, names.iter().map(String::as_str)).map(str::to_string),
            });
        }
        Ok(Self {
            figure: figure.into(),
            goal,
            value,
            weight,
        })
    }
}

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let op = match self.goal {
            Goal::Equal => "=",
            Goal::AtMost => "<=",
            Goal::AtLeast => ">=",
        };
        write!(f, "{}{op}{}", self.figure, self.value)?;
        if self.weight != 1.0 {
            write!(f, "@{}", self.weight)?;
        }
        Ok(())
    }
}

impl Target {
    /// How far `value` is from this target (0 when a bound holds).
    pub fn miss(&self, value: f64) -> f64 {
        let scale = self.value.abs().max(1e-3);
        let off = match self.goal {
            Goal::Equal => (value - self.value).abs(),
            Goal::AtMost => (value - self.value).max(0.0),
            Goal::AtLeast => (self.value - value).max(0.0),
        };
        if off.is_nan() {
            f64::INFINITY
        } else {
            off / scale
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn features(shift: f64, amp: f64, freq: f64) -> Features {
        Features {
            frames: 10,
            finite: true,
            mean: vec![[shift, 0.0, 1.0], [1.0, shift, 0.5]],
            spread: vec![0.0, amp],
            edge_amplitude: amp,
            edge_frequency: freq,
            mean_strain: 0.02,
            ..Features::default()
        }
    }

    #[test]
    fn zero_against_itself_and_symmetric() {
        let a = features(0.1, 0.2, 2.0);
        let b = features(0.3, 0.1, 3.0);
        assert_eq!(between(&a, &a, 1.0).total(), 0.0);
        assert_eq!(between(&a, &b, 1.0), between(&b, &a, 1.0));
        assert!(between(&a, &b, 1.0).total() > 0.0);
    }

    #[test]
    fn farther_shapes_are_farther() {
        let r = features(0.0, 0.1, 2.0);
        let d: Vec<f64> = [0.0, 0.05, 0.1, 0.3]
            .iter()
            .map(|&s| between(&features(s, 0.1, 2.0), &r, 1.0).total())
            .collect();
        assert!(d.windows(2).all(|w| w[0] < w[1]), "{d:?}");
    }

    #[test]
    fn targets_parse_and_miss() {
        let t: Target = "drape_coefficient=0.45".parse().unwrap();
        assert_eq!(t.goal, Goal::Equal);
        assert!((t.miss(0.45)).abs() < 1e-12);
        let b: Target = "max_strain<=0.1@2".parse().unwrap();
        assert_eq!((b.goal, b.weight), (Goal::AtMost, 2.0));
        assert_eq!(b.miss(0.05), 0.0);
        assert!(b.miss(0.2) > 0.0);
        let e = "drape_coeficient=0.4".parse::<Target>().unwrap_err();
        assert!(
            e.to_string().contains("did you mean `drape_coefficient`"),
            "{e}"
        );
        assert!("steps_per_second=3".parse::<Target>().is_err());
        assert!("max_strain=x".parse::<Target>().is_err());
        assert!("max_strain=0.1@0".parse::<Target>().is_err());
    }
}
