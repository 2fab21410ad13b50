//! The grid of a sweep: `--set KEY=V1,V2,…` and `--set KEY=A..B:N` axes,
//! their cartesian product in a fixed order, and each point's name.
//!
//! The first `--set` varies slowest, the last fastest, as in nested loops
//! written in the order of the command line. A point's index is its place in
//! that order, so the same command always gives the same points with the
//! same indices and names, on any machine and in any shard.

use std::str::FromStr;

use crate::scene::load::{Override, OverrideError};

/// One `--set` of a sweep: a key and the values it takes.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The dotted key, as `--set` takes it.
    pub key: String,
    /// Each value as written (ranges expanded), the text used in names.
    pub texts: Vec<String>,
    /// Each value as an override of the key.
    pub overrides: Vec<Override>,
}

/// Splits at commas outside brackets, braces and quotes (`[1, 2]` is one value).
fn split_values(raw: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth, mut quote) = (Vec::new(), String::new(), 0i32, None);
    for c in raw.chars() {
        match (c, quote) {
            ('"' | '\'', None) => quote = Some(c),
            (q, Some(open)) if q == open => quote = None,
            ('[' | '{', None) => depth += 1,
            (']' | '}', None) => depth -= 1,
            (',', None) if depth == 0 => {
                out.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// A float as a person writes it: its shortest `f32` form, always with a point.
fn float_text(v: f64) -> String {
    let s = (v as f32).to_string();
    if s.contains(['.', 'e', 'E', 'N', 'i']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// A `--set` axis of a sweep that does not parse.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AxisError {
    /// No `=`.
    #[error("`{0}` is not of the form key.path=V1,V2,… or key.path=A..B:N")]
    NoValues(String),
    /// `a,,b`.
    #[error("`{0}`: an empty value in the list")]
    EmptyValue(String),
    /// A range `A..B:N` written wrong.
    #[error("range `{range}`: {problem}; write A..B:N, e.g. 0.05..0.4:8")]
    Range {
        /// The range as written.
        range: String,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// A value that does not make an override.
    #[error(transparent)]
    Override(#[from] OverrideError),
    /// A value listed twice.
    #[error("`{axis}`: the value `{value}` is listed twice")]
    Twice {
        /// The axis as written.
        axis: String,
        /// The value.
        value: String,
    },
    /// A key swept by two axes.
    #[error("--set {0}: the key is swept twice")]
    KeyTwice(String),
}

/// Expands `A..B:N` into `N` evenly spaced values from `A` to `B` inclusive
/// (integers when `A`, `B` and the step are).
fn range(text: &str) -> Option<Result<Vec<String>, AxisError>> {
    let (span, count) = text.rsplit_once(':').unwrap_or((text, ""));
    let (a, b) = span.split_once("..")?;
    let bad = |problem: &'static str| {
        Some(Err(AxisError::Range {
            range: text.to_string(),
            problem,
        }))
    };
    let (Ok(x), Ok(y)) = (a.trim().parse::<f64>(), b.trim().parse::<f64>()) else {
        return bad("its ends must be numbers");
    };
    if !x.is_finite() || !y.is_finite() {
        return bad("its ends must be finite");
    }
    if count.is_empty() {
        return bad("say how many values with `:N`");
    }
    let Ok(n) = count.trim().parse::<usize>() else {
        return bad("N must be a whole number");
    };
    if n < 2 {
        return bad("N must be at least 2");
    }
    let integers = [a, b].iter().all(|s| s.trim().parse::<i64>().is_ok());
    let step = (y - x) / (n - 1) as f64;
    let whole_step = integers && step.fract() == 0.0;
    Some(Ok((0..n)
        .map(|k| {
            let v = if k == n - 1 { y } else { x + step * k as f64 };
            if whole_step {
                format!("{}", v as i64)
            } else {
                float_text(v)
            }
        })
        .collect()))
}

impl FromStr for Axis {
    type Err = AxisError;

    fn from_str(s: &str) -> Result<Self, AxisError> {
        let (key, raw) = s
            .split_once('=')
            .ok_or_else(|| AxisError::NoValues(s.to_string()))?;
        let key = key.trim();
        let mut texts = Vec::new();
        for v in split_values(raw) {
            if v.is_empty() {
                return Err(AxisError::EmptyValue(s.to_string()));
            }
            match range(&v) {
                Some(r) => texts.extend(r?),
                None => texts.push(v),
            }
        }
        let mut overrides = Vec::new();
        for t in &texts {
            overrides.push(format!("{key}={t}").parse::<Override>()?);
        }
        for (i, t) in texts.iter().enumerate() {
            if texts[..i].contains(t) {
                return Err(AxisError::Twice {
                    axis: s.to_string(),
                    value: t.clone(),
                });
            }
        }
        Ok(Self {
            key: key.to_string(),
            texts,
            overrides,
        })
    }
}

/// One point of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Its place in the grid order.
    pub index: usize,
    /// Its file-name-safe name: the index, then `key=value` of each axis
    /// with more than one value (`03_normality=0.35_iterations=10`).
    pub name: String,
    /// `(key, value as written)` for every axis.
    pub settings: Vec<(String, String)>,
    /// The overrides that make this point.
    pub overrides: Vec<Override>,
}

/// The longest point name (all ASCII), leaving room for `.rrd.part`.
pub const MAX_NAME: usize = 200;

/// The last segment of a key (`solver.weights.normality` → `normality`).
pub fn short(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}

/// Letters, digits and `.=+-` are kept, anything else becomes `_`.
pub fn safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || ".=+-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Checks the axes together: each key once.
pub fn check(axes: &[Axis]) -> Result<(), AxisError> {
    for (i, a) in axes.iter().enumerate() {
        if axes[..i].iter().any(|b| b.key == a.key) {
            return Err(AxisError::KeyTwice(a.key.clone()));
        }
    }
    Ok(())
}

/// Every point of the grid, in order.
pub fn points(axes: &[Axis]) -> Vec<Point> {
    let total: usize = axes.iter().map(|a| a.texts.len()).product();
    let width = total.saturating_sub(1).to_string().len();
    let named: Vec<&Axis> = axes.iter().filter(|a| a.texts.len() > 1).collect();
    let label = |a: &Axis| -> String {
        let s = short(&a.key);
        if named.iter().filter(|b| short(&b.key) == s).count() > 1 {
            a.key.clone()
        } else {
            s.to_string()
        }
    };
    (0..total)
        .map(|index| {
            // Mixed radix, the last axis fastest.
            let mut rest = index;
            let mut choice = vec![0; axes.len()];
            for (k, a) in axes.iter().enumerate().rev() {
                choice[k] = rest % a.texts.len();
                rest /= a.texts.len();
            }
            let mut name = format!("{index:0width$}");
            for (a, &c) in axes.iter().zip(&choice) {
                if a.texts.len() > 1 {
                    name += &format!("_{}={}", label(a), a.texts[c]);
                }
            }
            // File names have a limit (255 bytes on most file systems); the
            // index prefix keeps a shortened name unique.
            let mut name = safe(&name);
            name.truncate(MAX_NAME);
            Point {
                index,
                name,
                settings: axes
                    .iter()
                    .zip(&choice)
                    .map(|(a, &c)| (a.key.clone(), a.texts[c].clone()))
                    .collect(),
                overrides: axes
                    .iter()
                    .zip(&choice)
                    .map(|(a, &c)| a.overrides[c].clone())
                    .collect(),
            }
        })
        .collect()
}
