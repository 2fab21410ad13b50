//! Where a preset's text comes from: a file or a shipped name ([`Origin`]),
//! read with limits (a regular file of at most [`MAX_FILE_BYTES`], UTF-8),
//! and the `extend` chain, deep-merged with the extending file winning.
//!
//! Files are told apart by their canonical path, so a cycle written through
//! `../` or a symbolic link is still a cycle; messages show paths tidied
//! (`a/b/../c.toml` as `a/c.toml`).

use std::{
    io::Read,
    path::{Component, Path, PathBuf},
};

use toml::{Table, Value};

use super::locate::{PresetError, Source, find_key, line_col, syntax_error};
use super::overrides::Segment;
use crate::scene::{preset::nearest, shipped};

/// How deep `extend` chains may go.
const MAX_EXTEND_DEPTH: usize = 16;

/// The largest preset file read, in bytes (shipped presets are under 4 KiB).
pub const MAX_FILE_BYTES: u64 = 1 << 20;

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
        let names = || shipped::ALL.iter().map(|p| p.name);
        shipped::find(arg)
            .map(|p| Origin::Shipped(p.name))
            .ok_or_else(|| PresetError {
                hint: nearest(arg, names()).map(|n| format!("did you mean `{n}`?")),
                ..PresetError::plain(
                    crate::scene::preset::clip(arg),
                    format!(
                        "no such file, and no shipped preset of that name; shipped: {}",
                        names().collect::<Vec<_>>().join(", ")
                    ),
                )
            })
    }

    /// How messages name it.
    fn label(&self) -> String {
        match self {
            Origin::File(p) => tidy(p).display().to_string(),
            Origin::Shipped(name) => format!("shipped preset {name}"),
        }
    }

    /// What tells it apart from every other origin: the canonical path of a
    /// file (or the path as written, if it cannot be resolved).
    fn identity(&self) -> String {
        match self {
            Origin::File(p) => std::fs::canonicalize(p)
                .unwrap_or_else(|_| tidy(p))
                .display()
                .to_string(),
            Origin::Shipped(name) => format!("shipped:{name}"),
        }
    }

    /// Reads the text, refusing anything but a regular file of at most
    /// [`MAX_FILE_BYTES`] before reading it.
    fn read(&self) -> Result<String, ReadError> {
        let path = match self {
            Origin::File(p) => p,
            Origin::Shipped(name) => {
                return Ok(shipped::find(name).expect("resolved").text.to_string());
            }
        };
        let meta = std::fs::metadata(path)
            .map_err(|e| ReadError::Refused(format!("cannot be read: {e}")))?;
        if meta.is_dir() {
            return Err(ReadError::Refused(
                "is a directory, not a preset file".into(),
            ));
        }
        if !meta.is_file() {
            return Err(ReadError::Refused(
                "is not a regular file (a device, pipe or socket); a preset is a TOML file".into(),
            ));
        }
        let too_large = |size: u64| {
            ReadError::Refused(format!(
                "is too large for a preset ({size} bytes; at most {MAX_FILE_BYTES})"
            ))
        };
        if meta.len() > MAX_FILE_BYTES {
            return Err(too_large(meta.len()));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| ReadError::Refused(format!("cannot be read: {e}")))?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(too_large(bytes.len() as u64));
        }
        String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let valid = std::str::from_utf8(&e.as_bytes()[..at]).expect("valid up to here");
            ReadError::NotText(PresetError {
                position: Some(line_col(valid, at)),
                ..PresetError::plain(
                    self.label(),
                    format!("the file is not UTF-8 text (invalid byte at offset {at})"),
                )
            })
        })
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

/// Why a source could not be read.
enum ReadError {
    /// Missing, not a regular file, or too large: reported where it was
    /// named (the `extend` line, or the command line).
    Refused(String),
    /// Not UTF-8: reported in the file itself, at the first bad byte.
    NotText(PresetError),
}

/// `path` without `.` segments and with each `name/..` pair removed.
fn tidy(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            c => out.push(c),
        }
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    out
}

/// Reads `origin` and, recursively, what it extends; returns the merged
/// table and pushes each source read, the extending file first.
pub(super) fn read_chain(origin: &Origin, sources: &mut Vec<Source>) -> Result<Table, PresetError> {
    let text = match origin.read() {
        Ok(text) => text,
        Err(ReadError::Refused(why)) => return Err(PresetError::plain(origin.label(), why)),
        Err(ReadError::NotText(e)) => return Err(e),
    };
    read_from(origin, text, &mut vec![origin.identity()], sources)
}

fn read_from(
    origin: &Origin,
    text: String,
    chain: &mut Vec<String>,
    sources: &mut Vec<Source>,
) -> Result<Table, PresetError> {
    let name = origin.label();
    if text.trim().is_empty() {
        return Err(PresetError::plain(
            name,
            "the file is empty; a preset needs at least `description` and a [cloth] table",
        ));
    }
    let mut table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax_error(&name, &text, &e))?;
    let at_extend = |message: String| PresetError {
        key: Some("extend".into()),
        position: find_key(&text, &[Segment::Key("extend".into())]),
        ..PresetError::plain(name.clone(), message)
    };
    let base = match table.remove("extend") {
        None => None,
        Some(Value::String(target)) => {
            let base = origin
                .extend(&target)
                .map_err(|e| at_extend(e.to_string()))?;
            let id = base.identity();
            if let Some(i) = chain.iter().position(|c| *c == id) {
                let mut names: Vec<String> = sources[i..].iter().map(|s| s.name.clone()).collect();
                names.extend([name.clone(), base.label()]);
                return Err(at_extend(format!(
                    "`extend` forms a cycle: {}",
                    names.join(" → ")
                )));
            }
            if chain.len() > MAX_EXTEND_DEPTH {
                return Err(at_extend(format!(
                    "`extend` chain is longer than {MAX_EXTEND_DEPTH}"
                )));
            }
            let base_text = match base.read() {
                Ok(text) => text,
                Err(ReadError::Refused(why)) => {
                    return Err(at_extend(format!("`{}` {why}", base.label())));
                }
                Err(ReadError::NotText(e)) => return Err(e),
            };
            Some((base, base_text, id))
        }
        Some(other) => {
            return Err(at_extend(format!(
                "expected a preset name or path (a string), found {}",
                other.type_str()
            )));
        }
    };
    sources.push(Source { name, text });
    let Some((base, base_text, id)) = base else {
        return Ok(table);
    };
    chain.push(id);
    let mut merged = read_from(&base, base_text, chain, sources)?;
    merge(&mut merged, table);
    Ok(merged)
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
