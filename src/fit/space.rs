//! The search space: `--vary KEY=LO..HI`, each a live preset key and the
//! range it is searched in.
//!
//! The search works in the unit cube, one coordinate per varied key; a
//! coordinate `x` ∈ [0, 1] is the value `LO + x (HI − LO)`, rounded to what
//! the preset stores (an `f32`, or a whole number for an integer key such as
//! `solver.iterations`). The point's override is that rounded value, so
//! what ran is exactly what the point's file says.

use std::collections::BTreeMap;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::compare::flatten;
use crate::scene::load::{self, Override, nearest};
use crate::scene::{Preset, Tuning};

/// One `--vary KEY=LO..HI`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Vary {
    /// The dotted key.
    pub key: String,
    /// The low end.
    pub lo: f64,
    /// The high end.
    pub hi: f64,
    /// Whether the key holds a whole number.
    #[serde(default)]
    pub integer: bool,
}

/// A `--vary` that is wrong, told before anything runs.
#[derive(Debug, thiserror::Error)]
pub enum VaryError {
    /// Not `KEY=LO..HI`.
    #[error("--vary {0}: expected KEY=LO..HI, e.g. solver.weights.curvature=0.5..0.95")]
    Form(String),
    /// An end that is not a finite number.
    #[error("--vary {text}: `{end}` is not a finite number")]
    End {
        /// As written.
        text: String,
        /// The end.
        end: String,
    },
    /// `LO ≥ HI`.
    #[error("--vary {text}: the range is {what}; write LO..HI with LO below HI")]
    Range {
        /// As written.
        text: String,
        /// `empty` or `reversed`.
        what: &'static str,
    },
    /// A key the preset does not have, or that holds no number.
    #[error("--vary {key}: the preset has no number under this key{}; live numeric keys: {}", hint.as_ref().map(|h| format!(" (did you mean `{h}`?)")).unwrap_or_default(), live.join(", "))]
    NoKey {
        /// The key.
        key: String,
        /// The nearest live numeric key.
        hint: Option<String>,
        /// Every live numeric key of the preset.
        live: Vec<String>,
    },
    /// A key that needs a new scene (the cloth, bodies, colliders).
    #[error(
        "--vary {0}: not a live key (only the solver's settings and the wind change a running scene; a fit varies those: solver.*, environment.wind.*)"
    )]
    NotLive(String),
    /// A live key whose value is not a number (`h = "auto"`, a vector).
    #[error(
        "--vary {key}: the preset's value is {value}, not a number; to vary it, give it a number first (--set {key}=…)"
    )]
    NotNumber {
        /// The key.
        key: String,
        /// Its value.
        value: String,
    },
    /// A key varied twice.
    #[error("--vary {0}: the key is varied twice")]
    Twice(String),
    /// The preset itself (with `--set`) does not load.
    #[error(transparent)]
    Base(Box<load::PresetError>),
    /// An end of the range that the preset refuses.
    #[error("--vary {key}={lo}..{hi}: {source}")]
    Refused {
        /// The key.
        key: String,
        /// Low end.
        lo: f64,
        /// High end.
        hi: f64,
        /// Why the preset refuses it (with the allowed range).
        source: Box<load::PresetError>,
    },
}

impl FromStr for Vary {
    type Err = VaryError;

    fn from_str(s: &str) -> Result<Self, VaryError> {
        let (key, range) = s.split_once('=').ok_or_else(|| VaryError::Form(s.into()))?;
        let (lo, hi) = range
            .split_once("..")
            .ok_or_else(|| VaryError::Form(s.into()))?;
        let key = key.trim();
        if key.is_empty() {
            return Err(VaryError::Form(s.into()));
        }
        let num = |t: &str| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| VaryError::End {
                    text: s.into(),
                    end: t.into(),
                })
        };
        let (lo, hi) = (num(lo)?, num(hi)?);
        if lo == hi {
            return Err(VaryError::Range {
                text: s.into(),
                what: "empty",
            });
        }
        if lo > hi {
            return Err(VaryError::Range {
                text: s.into(),
                what: "reversed",
            });
        }
        Ok(Self {
            key: key.into(),
            lo,
            hi,
            integer: false,
        })
    }
}

impl std::fmt::Display for Vary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}..{}", self.key, self.lo, self.hi)
    }
}

/// A float as a person writes it: its shortest `f32` form, always with a point.
pub fn float_text(v: f64) -> String {
    let s = (v as f32).to_string();
    if s.contains(['.', 'e', 'E', 'N', 'i']) {
        s
    } else {
        format!("{s}.0")
    }
}

impl Vary {
    /// The value at unit coordinate `x` (clamped to [0, 1]), as stored, and
    /// its text.
    pub fn at(&self, x: f64) -> (toml::Value, String) {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        let v = self.lo + x * (self.hi - self.lo);
        if self.integer {
            let n = v.round() as i64;
            (toml::Value::Integer(n), n.to_string())
        } else {
            let f = v as f32;
            (toml::Value::Float(f as f64), float_text(f as f64))
        }
    }

    /// The unit coordinate of `value` (clamped to [0, 1]).
    pub fn unit(&self, value: f64) -> f64 {
        ((value - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0)
    }

    /// The override for unit coordinate `x`.
    pub fn set(&self, x: f64) -> Override {
        Override {
            key: self.key.clone(),
            value: self.at(x).0,
        }
    }
}

/// The preset's live keys that hold a number, with their values.
pub fn live_numbers(preset: &Preset) -> BTreeMap<String, toml::Value> {
    let table = toml::Table::try_from(preset).expect("a preset serializes");
    let mut flat = BTreeMap::new();
    flatten("", &toml::Value::Table(table.clone()), &mut flat);
    let mut out = BTreeMap::new();
    for key in flat.keys().filter(|k| Tuning::is_live(k)) {
        // The typed value, found again in the table by its dotted path.
        let mut at: Option<&toml::Value> = None;
        let mut cur = &table;
        for (n, part) in key.split('.').enumerate() {
            match cur.get(part) {
                Some(toml::Value::Table(t)) => cur = t,
                Some(v) if n == key.split('.').count() - 1 => at = Some(v),
                _ => break,
            }
        }
        if let Some(v @ (toml::Value::Float(_) | toml::Value::Integer(_))) = at {
            out.insert(key.clone(), v.clone());
        }
    }
    out
}

/// Checks the varied keys against the preset (`base` overrides applied,
/// which must load): each exists, holds a number, is live, is varied once,
/// and both ends of its range load. Marks integer keys.
pub fn check(preset: &str, base: &[Override], vary: &mut [Vary]) -> Result<(), VaryError> {
    let loaded = load::load(preset, base).map_err(|source| VaryError::Base(Box::new(source)))?;
    let live = live_numbers(&loaded.preset);
    for k in 0..vary.len() {
        let key = vary[k].key.clone();
        if vary[..k].iter().any(|v| v.key == key) {
            return Err(VaryError::Twice(key));
        }
        let Some(value) = live.get(&key) else {
            // A key that exists but is not live says so; else a typo.
            let table = toml::Table::try_from(&loaded.preset).expect("a preset serializes");
            let mut flat = BTreeMap::new();
            flatten("", &toml::Value::Table(table), &mut flat);
            if let Some(value) = flat.get(&key) {
                if !Tuning::is_live(&key) {
                    return Err(VaryError::NotLive(key));
                }
                return Err(VaryError::NotNumber {
                    key,
                    value: value.clone(),
                });
            }
            return Err(VaryError::NoKey {
                hint: nearest(&key, live.keys().map(String::as_str)).map(str::to_string),
                key,
                live: live.keys().cloned().collect(),
            });
        };
        vary[k].integer = matches!(value, toml::Value::Integer(_));
        for x in [0.0, 1.0] {
            let mut sets = base.to_vec();
            sets.push(vary[k].set(x));
            load::load(preset, &sets).map_err(|source| VaryError::Refused {
                key: key.clone(),
                lo: vary[k].lo,
                hi: vary[k].hi,
                source: Box::new(source),
            })?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_refuse() {
        let v: Vary = "solver.weights.curvature=0.5..0.95".parse().unwrap();
        assert_eq!((v.lo, v.hi), (0.5, 0.95));
        assert_eq!(v.at(0.0).1, "0.5");
        assert_eq!(v.at(1.0).1, "0.95");
        assert!(matches!(
            "a=1..1".parse::<Vary>(),
            Err(VaryError::Range { what: "empty", .. })
        ));
        assert!(matches!(
            "a=2..1".parse::<Vary>(),
            Err(VaryError::Range {
                what: "reversed",
                ..
            })
        ));
        assert!(matches!("a=1".parse::<Vary>(), Err(VaryError::Form(_))));
        assert!(matches!(
            "a=x..1".parse::<Vary>(),
            Err(VaryError::End { .. })
        ));
    }

    #[test]
    fn keys_are_checked_against_the_preset() {
        let mut ok = vec!["solver.iterations=2..10".parse::<Vary>().unwrap()];
        check("windy_flag", &[], &mut ok).unwrap();
        assert!(ok[0].integer);
        let mut typo = vec!["solver.weights.curvture=0.1..0.5".parse().unwrap()];
        let e = check("windy_flag", &[], &mut typo).unwrap_err();
        assert!(
            e.to_string()
                .contains("did you mean `solver.weights.curvature`"),
            "{e}"
        );
        let mut auto = vec!["solver.h=0.001..0.01".parse().unwrap()];
        assert!(matches!(
            check("windy_flag", &[], &mut auto),
            Err(VaryError::NotNumber { .. })
        ));
        let mut set = vec!["solver.h=0.001..0.01".parse().unwrap()];
        let h = "solver.h=0.005".parse::<Override>().unwrap();
        check("windy_flag", &[h], &mut set).unwrap();
        let mut dead = vec!["cloth.width=1..2".parse().unwrap()];
        assert!(matches!(
            check("windy_flag", &[], &mut dead),
            Err(VaryError::NotLive(_))
        ));
        let mut wide = vec!["solver.weights.curvature=0.5..7".parse().unwrap()];
        let e = check("windy_flag", &[], &mut wide).unwrap_err();
        assert!(matches!(e, VaryError::Refused { .. }), "{e}");
    }
}
