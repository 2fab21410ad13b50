//! What a tuned preset changed against the preset it started from: for the
//! names of runs (`normality 0.2→0.45`) and for saving a preset as
//! `extend = "<base>"` plus only the changed keys.
//!
//! Presets are compared as TOML tables: tables key by key, anything else
//! (numbers, strings, arrays such as `[[attachments]]`) as a whole, the way
//! `extend` merges them.

use std::path::Path;

use toml::{Table, Value};

use crate::scene::{Preset, load};

/// One changed key: its dotted path, the base's value (if it had one) and
/// the new value.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// `solver.weights.normality`.
    pub key: String,
    /// The value in the base.
    pub old: Option<Value>,
    /// The value now.
    pub new: Value,
}

fn table(p: &Preset) -> Table {
    // Floats in their shortest `f32` form, as saved presets write them.
    load::to_toml(p).parse().expect("a preset's TOML parses")
}

/// The keys `current` changes against `base`, in key order.
pub fn changes(base: &Preset, current: &Preset) -> Vec<Change> {
    let mut out = Vec::new();
    walk("", &table(base), &table(current), &mut out);
    out
}

fn walk(prefix: &str, a: &Table, b: &Table, out: &mut Vec<Change>) {
    for (k, vb) in b {
        let key = format!("{prefix}{k}");
        match (a.get(k), vb) {
            (Some(Value::Table(ta)), Value::Table(tb)) => walk(&format!("{key}."), ta, tb, out),
            (Some(va), vb) if va == vb => {}
            (old, new) => out.push(Change {
                key,
                old: old.cloned(),
                new: new.clone(),
            }),
        }
    }
}

fn short(v: &Value) -> String {
    match v {
        Value::Float(f) => (*f as f32).to_string(),
        Value::String(s) => s.clone(),
        Value::Array(_) | Value::Table(_) => "…".into(),
        other => other.to_string(),
    }
}

/// The changes a person cares about in a run's name: `normality 0.2→0.45,
/// iterations 10→14` (the last part of each key; telemetry left out; at
/// most three, then `+N more`).
pub fn describe(base: &Preset, current: &Preset) -> String {
    let all: Vec<Change> = changes(base, current)
        .into_iter()
        .filter(|c| !c.key.starts_with("telemetry."))
        .collect();
    let mut parts: Vec<String> = all
        .iter()
        .take(3)
        .map(|c| {
            let name = c.key.rsplit('.').next().unwrap_or(&c.key);
            match &c.old {
                Some(old) => format!("{name} {}→{}", short(old), short(&c.new)),
                None => format!("{name} {}", short(&c.new)),
            }
        })
        .collect();
    if all.len() > 3 {
        parts.push(format!("+{} more", all.len() - 3));
    }
    parts.join(", ")
}

/// The text of a preset file at `path` that extends `base_arg` (a shipped
/// name or a preset file) with only the keys `current` changes, preceded by
/// a `comment` line. `None` when the changes cannot be written as an
/// extension (a key the base has and the current preset lacks).
pub fn as_extension(
    comment: &str,
    base_arg: &str,
    base: &Preset,
    current: &Preset,
    path: &Path,
) -> Option<String> {
    let (a, b) = (table(base), table(current));
    if lost_key(&a, &b) {
        return None;
    }
    let mut diff = Table::new();
    for c in changes(base, current) {
        insert(&mut diff, &c.key, c.new);
    }
    // A base file is named relative to the saved file when they share a
    // directory, else by its absolute path.
    let extend = match load::Origin::resolve(base_arg).ok()? {
        load::Origin::Shipped(name) => name.to_string(),
        load::Origin::File(file) => {
            let abs = std::fs::canonicalize(&file).ok()?;
            let dir = match path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            let dir = std::fs::canonicalize(dir).ok();
            match (abs.parent(), dir) {
                (Some(p), Some(d)) if p == d => abs.file_name()?.to_string_lossy().into_owned(),
                _ => abs.to_string_lossy().into_owned(),
            }
        }
    };
    let mut text = format!("# {comment}\nextend = {}\n", Value::String(extend));
    if !diff.is_empty() {
        text += "\n";
        text += &load::to_toml(&diff);
    }
    Some(text)
}

fn lost_key(a: &Table, b: &Table) -> bool {
    a.iter().any(|(k, va)| match (va, b.get(k)) {
        (_, None) => true,
        (Value::Table(ta), Some(Value::Table(tb))) => lost_key(ta, tb),
        _ => false,
    })
}

fn insert(t: &mut Table, key: &str, v: Value) {
    match key.split_once('.') {
        None => {
            t.insert(key.to_string(), v);
        }
        Some((head, rest)) => {
            let sub = t
                .entry(head.to_string())
                .or_insert_with(|| Value::Table(Table::new()));
            if let Value::Table(sub) = sub {
                insert(sub, rest, v);
            }
        }
    }
}
