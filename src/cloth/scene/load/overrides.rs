//! `--set key.path=value` overrides: parsing them, and writing them into a
//! preset's TOML table before it is deserialised.

use toml::{Table, Value};

use crate::scene::preset::clip;

/// A `--set key.path=value` override.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The dotted key path, e.g. `solver.iterations` or `bodies[0].car.heading`.
    pub key: String,
    /// The value, parsed as TOML (a bare word becomes a string).
    pub value: Value,
}

/// An override that does not parse, or does not fit the preset.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OverrideError {
    /// No `=`.
    #[error("`{0}` is not of the form key.path=value")]
    NoValue(String),
    /// The key is not a dotted path.
    #[error("`{0}` is not a key path like `solver.iterations` or `bodies[0].car.heading`")]
    NotAPath(String),
    /// `extend` names a file, resolved when it is read.
    #[error(
        "`extend` cannot be set with --set: it is resolved when the file is read; write `extend = \"…\"` in a preset file that you load instead"
    )]
    Extend,
    /// The path goes into a value that is not a table.
    #[error("`{0}` is not a table")]
    NotATable(String),
    /// The path indexes a value that is not an array.
    #[error("`{0}` is not an array")]
    NotAnArray(String),
    /// The path indexes past an array's end.
    #[error("index {index} is out of range: `{array}` has {len} items")]
    OutOfRange {
        /// The array's path.
        array: String,
        /// The index given.
        index: usize,
        /// How many items it has.
        len: usize,
    },
}

impl std::str::FromStr for Override {
    type Err = OverrideError;

    fn from_str(s: &str) -> Result<Self, OverrideError> {
        let (key, raw) = s
            .split_once('=')
            .ok_or_else(|| OverrideError::NoValue(clip(s).into_owned()))?;
        let key = key.trim();
        if key.is_empty() || parse_path(key).is_none() {
            return Err(OverrideError::NotAPath(clip(key).into_owned()));
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
pub(super) enum Segment {
    Key(String),
    Index(usize),
}

/// Splits `a.b[2].c` into segments.
pub(super) fn parse_path(path: &str) -> Option<Vec<Segment>> {
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

/// Whether `key` is `path` or lies below it (`a.b[1].c` lies below `a.b`).
pub(super) fn is_within(key: &str, path: &str) -> bool {
    key.strip_prefix(path)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
}

/// Writes `o.value` at `o.key`, creating tables on the way.
pub(super) fn set(table: &mut Table, o: &Override) -> Result<(), OverrideError> {
    let path =
        parse_path(&o.key).ok_or_else(|| OverrideError::NotAPath(clip(&o.key).into_owned()))?;
    if path.first() == Some(&Segment::Key("extend".into())) {
        return Err(OverrideError::Extend);
    }
    let mut root = Value::Table(std::mem::take(table));
    let result = set_in(&mut root, &path, 0, &o.value);
    let Value::Table(t) = root else {
        unreachable!("the root stays a table")
    };
    *table = t;
    result
}

fn set_in(
    here: &mut Value,
    path: &[Segment],
    depth: usize,
    new: &Value,
) -> Result<(), OverrideError> {
    let Some(seg) = path.get(depth) else {
        *here = new.clone();
        return Ok(());
    };
    let walked = || clip(&join(&path[..depth])).into_owned();
    match seg {
        Segment::Key(k) => {
            let Value::Table(t) = here else {
                return Err(OverrideError::NotATable(walked()));
            };
            let child = t
                .entry(k.clone())
                .or_insert_with(|| Value::Table(Table::new()));
            set_in(child, path, depth + 1, new)
        }
        Segment::Index(i) => {
            let Value::Array(a) = here else {
                return Err(OverrideError::NotAnArray(walked()));
            };
            let len = a.len();
            let item = a.get_mut(*i).ok_or_else(|| OverrideError::OutOfRange {
                array: walked(),
                index: *i,
                len,
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
