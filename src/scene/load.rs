//! Loading presets: files and shipped names, `extend`, `--set`, and errors
//! that say where and what.
//!
//! Loading runs in three passes over plain TOML tables:
//! 1. read the file and, recursively, the preset it `extend`s; deep-merge the
//!    chain, the extending file winning (arrays are replaced whole);
//! 2. apply `--set key.path=value` overrides;
//! 3. deserialize into [`Preset`] (unknown keys are errors) and validate.
//!
//! Every error carries the dotted key it is about; [`PresetError`] finds that
//! key in the sources (the `--set` that wrote it, else the file that defines
//! it) to report file, line and column, and suggests the nearest valid key
//! for a typo.

use std::{
    fmt,
    path::{Path, PathBuf},
};

use toml::{Table, Value};

use super::{preset::Preset, shipped};

/// How deep `extend` chains may go.
const MAX_EXTEND_DEPTH: usize = 16;

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
            write!(f, "`{key}`: ")?;
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
    fn plain(source: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            source: source.into(),
            position: None,
            key: None,
            message: message.into(),
            hint: None,
        }
    }
}

/// A `--set key.path=value` override.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The dotted key path, e.g. `solver.weights.curvature` or `bodies[0].car.heading`.
    pub key: String,
    /// The value, parsed as TOML (a bare word becomes a string).
    pub value: Value,
}

impl std::str::FromStr for Override {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (key, raw) = s
            .split_once('=')
            .ok_or_else(|| format!("`{s}` is not of the form key.path=value"))?;
        let key = key.trim();
        if key.is_empty() || parse_path(key).is_none() {
            return Err(format!(
                "`{key}` is not a key path like `solver.weights.curvature` or `bodies[0].car.heading`"
            ));
        }
        let raw = raw.trim();
        let value = format!("v = {raw}")
            .parse::<Table>()
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| Value::String(raw.to_string()));
        Ok(Self {
            key: key.to_string(),
            value,
        })
    }
}

/// One segment of a key path.
#[derive(Clone, Debug, PartialEq)]
enum Segment {
    Key(String),
    Index(usize),
}

/// Splits `a.b[2].c` into segments.
fn parse_path(path: &str) -> Option<Vec<Segment>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if name.is_empty() {
            return None;
        }
        out.push(Segment::Key(name.to_string()));
        while let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']')?;
            out.push(Segment::Index(r[..end].parse().ok()?));
            rest = &r[end + 1..];
        }
        if !rest.is_empty() {
            return None;
        }
    }
    Some(out)
}

/// The text of one source of a preset, for locating keys.
#[derive(Clone, Debug)]
struct Source {
    name: String,
    text: String,
}

/// Where a preset comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// A file on disk.
    File(PathBuf),
    /// A preset shipped inside the binary.
    Shipped(&'static str),
}

impl Origin {
    /// A file path if one exists (or the argument looks like one), else a shipped name.
    pub fn resolve(arg: &str) -> Result<Self, PresetError> {
        let path = Path::new(arg);
        if path.exists() || arg.ends_with(".toml") || arg.contains('/') {
            return Ok(Origin::File(path.to_path_buf()));
        }
        shipped::find(arg)
            .map(|p| Origin::Shipped(p.name))
            .ok_or_else(|| {
                let hint = nearest(arg, shipped::ALL.iter().map(|p| p.name))
                    .map(|n| format!("did you mean `{n}`?"));
                PresetError {
                    hint,
                    ..PresetError::plain(
                        arg,
                        format!(
                            "no such file, and no shipped preset of that name; shipped: {}",
                            shipped::ALL
                                .iter()
                                .map(|p| p.name)
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                }
            })
    }

    fn label(&self) -> String {
        match self {
            Origin::File(p) => p.display().to_string(),
            Origin::Shipped(name) => format!("shipped preset {name}"),
        }
    }

    fn read(&self) -> Result<String, PresetError> {
        match self {
            Origin::File(p) => std::fs::read_to_string(p).map_err(|e| {
                PresetError::plain(p.display().to_string(), format!("cannot read: {e}"))
            }),
            Origin::Shipped(name) => Ok(shipped::find(name).expect("resolved").text.to_string()),
        }
    }

    /// Resolves an `extend` value written in this origin.
    fn extend(&self, target: &str) -> Result<Origin, PresetError> {
        match self {
            Origin::File(p) if target.ends_with(".toml") || target.contains('/') => Ok(
                Origin::File(p.parent().unwrap_or(Path::new(".")).join(target)),
            ),
            _ => Origin::resolve(target),
        }
    }
}

/// A preset together with the resolved TOML it was built from.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated preset.
    pub preset: Preset,
    /// The merged, overridden table, as TOML text (what a recording stores).
    pub resolved: String,
}

/// Loads a preset by path or shipped name, with overrides.
pub fn load(arg: &str, overrides: &[Override]) -> Result<Loaded, PresetError> {
    load_origin(&Origin::resolve(arg)?, overrides)
}

/// Loads a preset from an origin, with overrides.
pub fn load_origin(origin: &Origin, overrides: &[Override]) -> Result<Loaded, PresetError> {
    let mut sources = Vec::new();
    let mut table = read_chain(origin, 0, &mut sources)?;
    for o in overrides {
        set(&mut table, o).map_err(|message| PresetError {
            key: Some(o.key.clone()),
            ..PresetError::plain(format!("--set {}", o.key), message)
        })?;
    }
    let locate = |key: &str, message: String, hint: Option<String>| {
        locate_error(&sources, overrides, key, message, hint)
    };
    let preset: Preset = serde_path_to_error::deserialize(table.clone()).map_err(|e| {
        let key = e.path().to_string();
        let (message, hint) = explain(e.inner().message());
        if key == "." {
            let sources_name = sources.first().map(|s| s.name.clone()).unwrap_or_default();
            return PresetError {
                hint,
                position: Some((1, 1)),
                ..PresetError::plain(sources_name, message)
            };
        }
        locate(&key, message, hint)
    })?;
    preset
        .validate()
        .map_err(|inv| locate(&inv.key, inv.message, None))?;
    let resolved = to_toml(&table);
    Ok(Loaded { preset, resolved })
}

/// Applies overrides to an already loaded preset and validates the result,
/// as `--set` does (used by the tuning panel).
pub fn with_overrides(preset: &Preset, overrides: &[Override]) -> Result<Loaded, PresetError> {
    let mut table = Table::try_from(preset).expect("a preset serializes");
    for o in overrides {
        set(&mut table, o).map_err(|message| PresetError {
            key: Some(o.key.clone()),
            ..PresetError::plain(format!("--set {}", o.key), message)
        })?;
    }
    let preset: Preset = serde_path_to_error::deserialize(table.clone()).map_err(|e| {
        let (message, hint) = explain(e.inner().message());
        locate_error(&[], overrides, &e.path().to_string(), message, hint)
    })?;
    preset
        .validate()
        .map_err(|inv| locate_error(&[], overrides, &inv.key, inv.message, None))?;
    let resolved = to_toml(&table);
    Ok(Loaded { preset, resolved })
}

/// Parses a preset from text (e.g. stored in a recording), without `extend`.
pub fn parse(name: &str, text: &str) -> Result<Preset, PresetError> {
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax_error(name, text, &e))?;
    let sources = vec![Source {
        name: name.to_string(),
        text: text.to_string(),
    }];
    let preset: Preset = serde_path_to_error::deserialize(table).map_err(|e| {
        let (message, hint) = explain(e.inner().message());
        locate_error(&sources, &[], &e.path().to_string(), message, hint)
    })?;
    preset
        .validate()
        .map_err(|inv| locate_error(&sources, &[], &inv.key, inv.message, None))?;
    Ok(preset)
}

fn read_chain(
    origin: &Origin,
    depth: usize,
    sources: &mut Vec<Source>,
) -> Result<Table, PresetError> {
    if depth > MAX_EXTEND_DEPTH {
        return Err(PresetError::plain(
            origin.label(),
            format!("`extend` chain is longer than {MAX_EXTEND_DEPTH} (a cycle?)"),
        ));
    }
    let name = origin.label();
    if sources.iter().any(|s| s.name == name) {
        return Err(PresetError::plain(name, "`extend` forms a cycle"));
    }
    let text = origin.read()?;
    if text.trim().is_empty() {
        return Err(PresetError::plain(
            name,
            "the file is empty; a preset needs at least `description` and a [cloth] table",
        ));
    }
    let mut table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax_error(&name, &text, &e))?;
    sources.push(Source {
        name: name.clone(),
        text: text.clone(),
    });
    match table.remove("extend") {
        None => Ok(table),
        Some(Value::String(target)) => {
            let base_origin = origin.extend(&target).map_err(|e| PresetError {
                key: Some("extend".into()),
                position: find_key(&text, &[Segment::Key("extend".into())]),
                ..PresetError::plain(name.clone(), e.to_string())
            })?;
            let mut base = read_chain(&base_origin, depth + 1, sources)?;
            merge(&mut base, table);
            Ok(base)
        }
        Some(other) => Err(PresetError {
            key: Some("extend".into()),
            position: find_key(&text, &[Segment::Key("extend".into())]),
            ..PresetError::plain(
                name,
                format!(
                    "expected a preset name or path (a string), found {}",
                    other.type_str()
                ),
            )
        }),
    }
}

/// Deep-merges `over` into `base`; tables merge, everything else is replaced.
fn merge(base: &mut Table, over: Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(Value::Table(b)), Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Writes `o.value` at `o.key`, creating tables on the way.
fn set(table: &mut Table, o: &Override) -> Result<(), String> {
    let path = parse_path(&o.key).ok_or("not a key path")?;
    let mut root = Value::Table(std::mem::take(table));
    let result = set_in(&mut root, &path, 0, &o.value);
    let Value::Table(t) = root else {
        unreachable!("the root stays a table")
    };
    *table = t;
    result
}

fn set_in(here: &mut Value, path: &[Segment], depth: usize, new: &Value) -> Result<(), String> {
    let Some(seg) = path.get(depth) else {
        *here = new.clone();
        return Ok(());
    };
    let walked = || join(&path[..depth]);
    match seg {
        Segment::Key(k) => {
            let Value::Table(t) = here else {
                return Err(format!("`{}` is not a table", walked()));
            };
            let child = t
                .entry(k.clone())
                .or_insert_with(|| Value::Table(Table::new()));
            set_in(child, path, depth + 1, new)
        }
        Segment::Index(i) => {
            let Value::Array(a) = here else {
                return Err(format!("`{}` is not an array", walked()));
            };
            let len = a.len();
            let item = a.get_mut(*i).ok_or_else(|| {
                format!("index {i} is out of range: `{}` has {len} items", walked())
            })?;
            set_in(item, path, depth + 1, new)
        }
    }
}

fn join(path: &[Segment]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Segment::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Segment::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

fn syntax_error(name: &str, text: &str, e: &toml::de::Error) -> PresetError {
    PresetError {
        position: e.span().map(|s| line_col(text, s.start)),
        ..PresetError::plain(name, format!("invalid TOML: {}", e.message().trim()))
    }
}

/// Rewrites serde's messages in the preset's terms and finds a hint.
fn explain(message: &str) -> (String, Option<String>) {
    if let Some(rest) = message.strip_prefix("unknown field `")
        && let Some((field, expected)) = rest.split_once('`')
    {
        let valid: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
        let hint = nearest(field, valid.iter().copied()).map(|n| format!("did you mean `{n}`?"));
        let list = if valid.is_empty() {
            "none".to_string()
        } else {
            valid.join(", ")
        };
        return (
            format!("unknown key `{field}`; valid keys here: {list}"),
            hint,
        );
    }
    if let Some(rest) = message.strip_prefix("unknown variant `")
        && let Some((value, expected)) = rest.split_once('`')
    {
        let valid: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
        let hint = nearest(value, valid.iter().copied()).map(|n| format!("did you mean `{n}`?"));
        return (
            format!("unknown value `{value}`; allowed: {}", valid.join(", ")),
            hint,
        );
    }
    if let Some(rest) = message.strip_prefix("missing field `")
        && let Some((field, _)) = rest.split_once('`')
    {
        return (format!("missing required key or section `{field}`"), None);
    }
    (message.trim().to_string(), None)
}

/// The candidate closest to `word` by edit distance, if close enough.
pub fn nearest<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .map(|c| (strsim::damerau_levenshtein(word, c), c))
        .filter(|(d, c)| *d <= (c.len().max(word.len()) / 3).max(1) + 1)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn locate_error(
    sources: &[Source],
    overrides: &[Override],
    key: &str,
    message: String,
    hint: Option<String>,
) -> PresetError {
    // serde_path_to_error writes `a.b[0].c`; an unknown key's path ends in it.
    let path = parse_path(key).unwrap_or_default();
    let base = PresetError {
        key: Some(key.to_string()),
        hint,
        ..PresetError::plain("", message)
    };
    for o in overrides.iter().rev() {
        if key == o.key
            || key.starts_with(&format!("{}.", o.key))
            || key.starts_with(&format!("{}[", o.key))
        {
            return PresetError {
                source: format!("--set {}", o.key),
                ..base
            };
        }
    }
    // The first source (the file itself, then what it extends) that has the key.
    for s in sources {
        if let Some(pos) = find_key(&s.text, &path) {
            return PresetError {
                source: s.name.clone(),
                position: Some(pos),
                ..base
            };
        }
    }
    // Not written anywhere (a missing key): point at its nearest written parent.
    for cut in (0..path.len()).rev() {
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
    PresetError {
        source: sources.first().map(|s| s.name.clone()).unwrap_or_default(),
        position: None,
        ..base
    }
}

/// Line and column of the key at `path` in `text`, if it is written there.
fn find_key(text: &str, path: &[Segment]) -> Option<(usize, usize)> {
    use toml::de::{DeTable, DeValue};
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

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rfind('\n')
        .map_or(before.len(), |i| before.len() - i - 1)
        + 1;
    (line, col)
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
