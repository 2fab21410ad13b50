//! Loading presets: files and shipped names, `extend`, `--set`, and errors
//! that say where and what.
//!
//! Every way in (a file or shipped name, `--set` on a loaded preset, the
//! text stored in a recording) runs one pipeline over plain TOML tables:
//! 1. `source`: read the file and, recursively, the preset it `extend`s;
//!    deep-merge the chain, the extending file winning (arrays are replaced
//!    whole);
//! 2. `overrides`: apply `--set key.path=value` overrides;
//! 3. deserialise into [`Preset`] (unknown keys are errors) and validate.
//!
//! Every failure carries the dotted key it is about; `locate` finds that
//! key in the sources (the `--set` that caused it, else the file that
//! writes it) to report file, line and column, and suggests the nearest
//! valid key for a typo.

use toml::{Table, Value};

use super::preset::Preset;

mod locate;
mod overrides;
mod source;

pub use locate::PresetError;
pub use overrides::{Override, OverrideError};
pub use source::{MAX_FILE_BYTES, Origin};

pub use crate::scene::preset::nearest;

use locate::{Failure, Source};

/// A preset together with the resolved TOML it was built from.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated preset.
    pub preset: Preset,
    /// The merged, overridden table, as TOML text (what a recording stores).
    pub resolved: String,
    /// What is valid but probably not meant (see [`Preset::warnings`]); the
    /// command line prints them to standard error.
    pub warnings: Vec<String>,
}

/// Loads a preset by path or shipped name, with overrides.
pub fn load(arg: &str, overrides: &[Override]) -> Result<Loaded, PresetError> {
    load_origin(&Origin::resolve(arg)?, overrides)
}

/// Loads a preset from an origin, with overrides.
pub fn load_origin(origin: &Origin, overrides: &[Override]) -> Result<Loaded, PresetError> {
    let mut sources = Vec::new();
    let table = source::read_chain(origin, &mut sources)?;
    build(table, &sources, overrides)
}

/// Applies overrides to an already loaded preset and validates the result,
/// as `--set` does (used by the tuning panel).
pub fn with_overrides(preset: &Preset, overrides: &[Override]) -> Result<Loaded, PresetError> {
    let table = Table::try_from(preset).expect("a preset serializes");
    build(table, &[], overrides)
}

/// Parses a preset from text (e.g. stored in a recording), without `extend`.
pub fn parse(name: &str, text: &str) -> Result<Preset, PresetError> {
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| locate::syntax_error(name, text, &e))?;
    let sources = [Source {
        name: name.to_string(),
        text: text.to_string(),
    }];
    Ok(build(table, &sources, &[])?.preset)
}

/// The pipeline after reading: overrides, deserialisation, validation; a
/// failure is located in `sources` or blamed on a `--set`.
fn build(base: Table, sources: &[Source], overrides: &[Override]) -> Result<Loaded, PresetError> {
    match check(base.clone(), overrides) {
        Ok((table, preset)) => Ok(Loaded {
            warnings: preset.warnings(),
            resolved: to_toml(&table),
            preset,
        }),
        Err(failure) => {
            let culprit = blame(&base, overrides, &failure);
            Err(locate::report(failure, culprit, sources))
        }
    }
}

/// Applies the overrides to `table`, deserialises and validates.
fn check(mut table: Table, overrides: &[Override]) -> Result<(Table, Preset), Failure> {
    for (index, o) in overrides.iter().enumerate() {
        overrides::set(&mut table, o).map_err(|e| Failure::Set {
            index,
            message: e.to_string(),
        })?;
    }
    let preset: Preset = serde_path_to_error::deserialize(table.clone()).map_err(|e| {
        let key = Some(e.path().to_string()).filter(|k| k != ".");
        let (message, hint) = locate::explain(e.inner().message());
        Failure::At { key, message, hint }
    })?;
    preset.validate().map_err(|inv| Failure::At {
        key: Some(inv.key),
        message: inv.message,
        hint: None,
    })?;
    Ok((table, preset))
}

/// The `--set` a failure is blamed on: the last one that wrote its key or a
/// table above it; else, if one wrote below its key (a `--set` of an unknown
/// key deep inside a table, or of a field checked with its neighbours), the
/// first one after which the same failure appears. None: the sources.
fn blame<'a>(base: &Table, overrides: &'a [Override], failure: &Failure) -> Option<&'a Override> {
    let key = match failure {
        Failure::Set { index, .. } => return overrides.get(*index),
        Failure::At { key: None, .. } => return None,
        Failure::At { key: Some(key), .. } => key,
    };
    if let Some(o) = overrides
        .iter()
        .rev()
        .find(|o| overrides::is_within(key, &o.key))
    {
        return Some(o);
    }
    if !overrides.iter().any(|o| overrides::is_within(&o.key, key)) {
        return None;
    }
    let fails_so = |n: usize| check(base.clone(), &overrides[..n]).err().as_ref() == Some(failure);
    (0..=overrides.len())
        .find(|&n| fails_so(n))
        .and_then(|n| n.checked_sub(1))
        .map(|n| &overrides[n])
}

/// TOML text for `value`, with every float that is exactly an `f32` written
/// in its shortest form (`0.35`, not `0.3499999940395355`) when that form
/// reads back to the same `f32`, so saved presets stay readable and exact.
pub fn to_toml<T: serde::Serialize>(value: &T) -> String {
    let mut v = Value::try_from(value).expect("weft's settings serialize to TOML");
    tidy_floats(&mut v);
    toml::to_string(&v).expect("a TOML value serializes")
}

fn tidy_floats(v: &mut Value) {
    match v {
        Value::Float(f) => {
            let single = *f as f32;
            if single as f64 == *f
                && let Ok(short) = single.to_string().parse::<f64>()
                && short as f32 == single
            {
                *f = short;
            }
        }
        Value::Array(a) => a.iter_mut().for_each(tidy_floats),
        Value::Table(t) => t.iter_mut().for_each(|(_, v)| tidy_floats(v)),
        _ => {}
    }
}
