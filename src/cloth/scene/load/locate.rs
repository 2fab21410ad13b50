//! Where a preset error is: [`PresetError`] (file, line, column, key, what,
//! hint), finding a dotted key in the TOML sources, and serde's messages
//! rewritten in the preset's terms.
//!
//! A failure is reported at the `--set` that caused it if there is one,
//! else at the first source (the file itself, then what it extends) that
//! writes its key, else at the nearest written parent of that key.

use std::fmt;

use toml::de::{DeTable, DeValue};

use super::overrides::{Override, Segment, parse_path};
use crate::scene::preset::{clip, nearest};

/// A preset that could not be loaded, located in its source.
#[derive(Clone, Debug, PartialEq)]
pub struct PresetError {
    /// The file (or `--set …`, or `shipped preset NAME`) the problem is in.
    pub source: String,
    /// 1-based line and column, when known.
    pub position: Option<(usize, usize)>,
    /// The dotted key the problem is about, when known.
    pub key: Option<String>,
    /// What is wrong, with the expected type or range.
    pub message: String,
    /// A suggestion, such as the nearest valid key.
    pub hint: Option<String>,
}

impl fmt::Display for PresetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.source)?;
        if let Some((line, col)) = self.position {
            write!(f, ":{line}:{col}")?;
        }
        write!(f, ": ")?;
        if let Some(key) = &self.key {
            write!(f, "`{}`: ", clip(key))?;
        }
        write!(f, "{}", self.message)?;
        if let Some(hint) = &self.hint {
            write!(f, " ({hint})")?;
        }
        Ok(())
    }
}

impl std::error::Error for PresetError {}

impl PresetError {
    /// An error about a whole source, without a position.
    pub(super) fn plain(source: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            source: source.into(),
            position: None,
            key: None,
            message: message.into(),
            hint: None,
        }
    }
}

/// The text of one source of a preset, for locating keys.
#[derive(Clone, Debug)]
pub(super) struct Source {
    /// How messages name it: a tidy path, or `shipped preset NAME`.
    pub name: String,
    pub text: String,
}

/// Why a preset did not make it through overrides, deserialisation and
/// validation, before it is located.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Failure {
    /// The `--set` at this index could not be written.
    Set { index: usize, message: String },
    /// The problem at a dotted key (none: the whole preset).
    At {
        key: Option<String>,
        message: String,
        hint: Option<String>,
    },
}

/// The `--set` source name of an override.
fn set_source(o: &Override) -> String {
    format!("--set {}", clip(&o.key))
}

/// Locates a failure: at `culprit` (the `--set` it is blamed on) if any,
/// else in the sources.
pub(super) fn report(
    failure: Failure,
    culprit: Option<&Override>,
    sources: &[Source],
) -> PresetError {
    let first = sources.first().map(|s| s.name.clone()).unwrap_or_default();
    let (key, message, hint) = match failure {
        Failure::Set { message, .. } => {
            let o = culprit.expect("a --set failure names its override");
            return PresetError {
                key: Some(o.key.clone()),
                ..PresetError::plain(set_source(o), message)
            };
        }
        Failure::At {
            key: None,
            message,
            hint,
        } => {
            return PresetError {
                hint,
                position: (!sources.is_empty()).then_some((1, 1)),
                ..PresetError::plain(first, message)
            };
        }
        Failure::At {
            key: Some(key),
            message,
            hint,
        } => (key, message, hint),
    };
    let base = PresetError {
        key: Some(key.clone()),
        hint,
        ..PresetError::plain(first, message)
    };
    if let Some(o) = culprit {
        return PresetError {
            source: set_source(o),
            ..base
        };
    }
    // serde_path_to_error writes `a.b[0].c`; an unknown key's path ends in it.
    let path = parse_path(&key).unwrap_or_default();
    // The first source that has the key; if none (a missing key), the first
    // that has its nearest parent.
    for cut in (0..=path.len()).rev() {
        for s in sources {
            if let Some(pos) = find_key(&s.text, &path[..cut]) {
                return PresetError {
                    source: s.name.clone(),
                    position: Some(pos),
                    ..base
                };
            }
        }
    }
    base
}

/// An error in the TOML syntax of a source.
pub(super) fn syntax_error(name: &str, text: &str, e: &toml::de::Error) -> PresetError {
    PresetError {
        position: e.span().map(|s| line_col(text, s.start)),
        ..PresetError::plain(name, format!("invalid TOML: {}", e.message().trim()))
    }
}

/// Rewrites serde's messages in the preset's terms and finds a hint.
pub(super) fn explain(message: &str) -> (String, Option<String>) {
    let expected = |rest: &str| -> Vec<String> {
        rest.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let hint = |word: &str, valid: &[String]| {
        nearest(word, valid.iter().map(String::as_str)).map(|n| format!("did you mean `{n}`?"))
    };
    if let Some(rest) = message.strip_prefix("unknown field `")
        && let Some((field, rest)) = rest.split_once('`')
    {
        let valid = expected(rest);
        let list = if valid.is_empty() {
            "none".to_string()
        } else {
            valid.join(", ")
        };
        let text = format!("unknown key `{}`; valid keys here: {list}", clip(field));
        return (text, hint(field, &valid));
    }
    if let Some(rest) = message.strip_prefix("unknown variant `")
        && let Some((value, rest)) = rest.split_once('`')
    {
        let valid = expected(rest);
        let text = format!(
            "unknown value `{}`; allowed: {}",
            clip(value),
            valid.join(", ")
        );
        return (text, hint(value, &valid));
    }
    if let Some(rest) = message.strip_prefix("missing field `")
        && let Some((field, _)) = rest.split_once('`')
    {
        return (format!("missing required key or section `{field}`"), None);
    }
    (message.trim().to_string(), None)
}

/// Line and column of the key at `path` in `text`, if it is written there
/// (the whole text for an empty path).
pub(super) fn find_key(text: &str, path: &[Segment]) -> Option<(usize, usize)> {
    if path.is_empty() {
        return Some((1, 1));
    }
    let doc = DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut span = None;
    let mut value: Option<&DeValue> = None;
    for seg in path {
        match (seg, value) {
            (Segment::Key(k), None) => {
                let (key, v) = table.iter().find(|(key, _)| key.get_ref() == k)?;
                span = Some(key.span());
                value = Some(v.get_ref());
            }
            (Segment::Key(k), Some(DeValue::Table(t))) => {
                table = t;
                let (key, v) = table.iter().find(|(key, _)| key.get_ref() == k)?;
                span = Some(key.span());
                value = Some(v.get_ref());
            }
            (Segment::Index(i), Some(DeValue::Array(a))) => {
                let item = a.get(*i)?;
                span = Some(item.span());
                value = Some(item.get_ref());
            }
            _ => return None,
        }
    }
    span.map(|s| line_col(text, s.start))
}

/// 1-based line and column (counted in bytes) of a byte offset.
pub(super) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rfind('\n')
        .map_or(before.len(), |i| before.len() - i - 1)
        + 1;
    (line, col)
}
