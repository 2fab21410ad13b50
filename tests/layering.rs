//! The layering, checked: `src/solver/` uses nothing above it.
//!
//! The solver is the method and nothing else. It must not name Rerun, egui,
//! eframe, TOML or any of weft's upper layers (`scene`, `telemetry`,
//! `record`, `replay`, `app`, `cli`), so that it can be read, tested and
//! reused on its own. This test reads every source file under `src/solver/`
//! and fails with the file and line of each path that reaches upward.

use std::path::{Path, PathBuf};

/// Crates the solver must not use (as a path root, `name::…`).
const FORBIDDEN_CRATES: [&str; 9] = [
    "rerun",
    "egui",
    "eframe",
    "toml",
    "serde_json",
    "clap",
    "tokio",
    "indicatif",
    "anyhow",
];

/// weft's modules above the solver.
const UPPER_MODULES: [&str; 6] = ["scene", "telemetry", "record", "replay", "app", "cli"];

/// One path that reaches above the solver.
#[derive(Debug, PartialEq)]
struct Violation {
    line: usize,
    path: String,
}

/// The upward paths in one file's text; `depth` is how many modules below
/// `solver` the file's module is, so how many `super`s stay inside it.
fn violations(text: &str, depth: usize) -> Vec<Violation> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or_default();
        for path in paths_in(code) {
            let mut segments = path.split("::");
            let root = segments.next().unwrap_or_default();
            let upward = if root == "crate" {
                segments.next().is_some_and(|m| UPPER_MODULES.contains(&m))
            } else if root == "super" {
                // `super` repeated more times than the file is deep leaves the solver.
                let supers = 1 + path
                    .split("::")
                    .skip(1)
                    .take_while(|s| *s == "super")
                    .count();
                supers > depth
            } else {
                FORBIDDEN_CRATES.contains(&root) || root.starts_with("re_")
            };
            if upward {
                out.push(Violation { line: i + 1, path });
            }
        }
    }
    out
}

/// Every `a::b::c` path in a line of code (identifiers joined by `::`).
fn paths_in(code: &str) -> Vec<String> {
    let bytes = code.as_bytes();
    let ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if !ident(bytes[i]) || (i > 0 && (ident(bytes[i - 1]) || bytes[i - 1] == b':')) {
            i += 1;
            continue;
        }
        let start = i;
        let mut end = i;
        loop {
            while end < bytes.len() && ident(bytes[end]) {
                end += 1;
            }
            if code[end..].starts_with("::") && end + 2 < bytes.len() && ident(bytes[end + 2]) {
                end += 2;
            } else {
                break;
            }
        }
        if code[start..end].contains("::") {
            out.push(code[start..end].to_string());
        }
        i = end.max(i + 1);
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/solver is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_solver_uses_nothing_above_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/solver");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.sort();
    assert!(files.len() >= 10, "found only {files:?}");
    let mut report = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&root).expect("under src/solver");
        // How many modules below `solver` the file's module is: `mod.rs` is
        // the solver itself (0), `x.rs` and `a/mod.rs` are 1, `a/x.rs` is 2.
        let is_mod = rel.file_name().is_some_and(|n| n == "mod.rs");
        let depth = rel.components().count() - usize::from(is_mod);
        let text = std::fs::read_to_string(file).expect("a source file");
        for v in violations(&text, depth) {
            report.push(format!(
                "src/solver/{}:{}: `{}`",
                rel.display(),
                v.line,
                v.path
            ));
        }
    }
    assert!(
        report.is_empty(),
        "the solver reaches above its layer:\n{}",
        report.join("\n")
    );
}

/// The checker itself finds what it must (so the test above can fail).
#[test]
fn the_checker_finds_upward_paths() {
    let text = "\
use crate::scene::Preset;
use crate::solver::Params; // fine
let s = toml::to_string(&x);
use super::super::super::telemetry::Telemetry;
use rerun::RecordingStream;
let v = glam::Vec3::ZERO; // fine
// use egui::Ui; in a comment: fine
let c = re_viewer::App::new();
";
    let found: Vec<(usize, String)> = violations(text, 2)
        .into_iter()
        .map(|v| (v.line, v.path))
        .collect();
    assert_eq!(
        found,
        vec![
            (1, "crate::scene::Preset".to_string()),
            (3, "toml::to_string".to_string()),
            (4, "super::super::super::telemetry::Telemetry".to_string()),
            (5, "rerun::RecordingStream".to_string()),
            (8, "re_viewer::App::new".to_string()),
        ]
    );
    // `super::super` from two modules deep stays inside the solver.
    assert!(violations("use super::super::cloth::ClothSpec;", 2).is_empty());
}
