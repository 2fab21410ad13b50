//! The layering, checked: each module of `src/` uses only the modules and
//! crates its layer may (ARCHITECTURE.md, "Layers").
//!
//! The solver is the method and nothing else: it must not name Rerun, egui,
//! eframe, TOML or any of weft's other modules, so that it can be read,
//! tested and reused on its own. Above it, each layer uses only the layers
//! below it ([`ALLOWED`]); only the desktop debugger (`app`) knows egui,
//! eframe and the Rerun viewer; `compare`, `sweep` and `fit` are libraries, their
//! command lines live in `cli`. This test reads every source file under
//! `src/` and fails with the file and line of each path that reaches where
//! its module may not.

use std::path::{Path, PathBuf};

#[path = "source/mod.rs"]
mod source;
use source::{paths_in, rust_files};

/// Each module of the crate and the modules it may use.
const ALLOWED: [(&str, &[&str]); 12] = [
    ("solver", &[]),
    ("scene", &["solver"]),
    ("telemetry", &["scene", "solver"]),
    ("record", &["telemetry", "scene", "solver"]),
    ("replay", &["record", "telemetry", "scene", "solver"]),
    (
        "compare",
        &["record", "replay", "telemetry", "scene", "solver"],
    ),
    (
        "sweep",
        &[
            "compare",
            "record",
            "replay",
            "telemetry",
            "scene",
            "solver",
            "interrupt",
        ],
    ),
    (
        "fit",
        &[
            "sweep",
            "compare",
            "record",
            "replay",
            "telemetry",
            "scene",
            "solver",
            "interrupt",
        ],
    ),
    (
        "report",
        &[
            "fit",
            "sweep",
            "compare",
            "record",
            "replay",
            "telemetry",
            "scene",
            "solver",
            "interrupt",
        ],
    ),
    ("app", &["record", "replay", "telemetry", "scene", "solver"]),
    (
        "cli",
        &[
            "app",
            "report",
            "compare",
            "fit",
            "sweep",
            "record",
            "replay",
            "telemetry",
            "scene",
            "solver",
            "interrupt",
        ],
    ),
    ("interrupt", &[]),
];

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

/// The window's crates: only `app` may use them.
const WINDOW_CRATES: [&str; 5] = ["egui", "eframe", "egui_kittest", "winit", "wgpu"];

/// Whether `module` may use the crate `root` (a path's first segment that
/// is neither `crate`, `super` nor `self`).
fn crate_allowed(module: &str, root: &str) -> bool {
    let window = WINDOW_CRATES.contains(&root) || (root.starts_with("re_") && root != "re_log");
    match module {
        "solver" => !FORBIDDEN_CRATES.contains(&root) && !root.starts_with("re_"),
        "app" => true,
        _ => !window,
    }
}

/// Whether `module` may use weft's module `other`.
fn module_allowed(module: &str, other: &str) -> bool {
    other == module
        || ALLOWED
            .iter()
            .find(|(m, _)| *m == module)
            .is_some_and(|(_, allowed)| allowed.contains(&other))
}

/// One path that reaches where its module may not.
#[derive(Debug, PartialEq)]
struct Violation {
    line: usize,
    path: String,
}

/// The paths in one file's text that `module` may not use; `depth` is how
/// many modules below `module` the file's module is, so how many `super`s
/// stay inside it.
fn violations(text: &str, module: &str, depth: usize) -> Vec<Violation> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or_default();
        for path in paths_in(code) {
            let mut segments = path.split("::");
            let root = segments.next().unwrap_or_default();
            let ok = match root {
                "crate" | "$crate" => segments.next().is_none_or(|m| module_allowed(module, m)),
                "super" => {
                    // `super` repeated more times than the file is deep
                    // leaves the module, for the crate's root.
                    let supers = 1 + path
                        .split("::")
                        .skip(1)
                        .take_while(|s| *s == "super")
                        .count();
                    supers <= depth
                        || path
                            .split("::")
                            .nth(supers)
                            .is_none_or(|m| module_allowed(module, m))
                }
                "self" | "Self" => true,
                _ => crate_allowed(module, root),
            };
            if !ok {
                out.push(Violation { line: i + 1, path });
            }
        }
    }
    out
}

/// The modules of the cloth library (the crate `weft-cloth`, in
/// `src/cloth/`), which the `weft` crate re-exports.
const CLOTH: [&str; 2] = ["solver", "scene"];

/// Where a module's source is: `src/cloth/` for the cloth library's, `src/`
/// for the rest.
fn source_root(module: &str) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    if CLOTH.contains(&module) {
        src.join("cloth")
    } else {
        src
    }
}

/// Every `.rs` file under `src/<module>/` (or `src/<module>.rs`), with how
/// many modules below `module` each file's module is: `mod.rs` is the
/// module itself (0), `x.rs` and `a/mod.rs` are 1, `a/x.rs` is 2.
fn module_files(module: &str) -> Vec<(PathBuf, usize)> {
    let src = source_root(module);
    let file = src.join(format!("{module}.rs"));
    if file.is_file() {
        return vec![(file, 0)];
    }
    let root = src.join(module);
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|f| {
            let rel = f
                .strip_prefix(&root)
                .expect("under the module")
                .to_path_buf();
            let is_mod = rel.file_name().is_some_and(|n| n == "mod.rs");
            let depth = rel.components().count() - usize::from(is_mod);
            (f, depth)
        })
        .collect()
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // Every module of the two crates is in the table.
    let entries = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .expect("src is readable")
            .map(|e| e.expect("an entry").path())
            .filter(|p| p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
            .filter_map(|p| {
                let name = p.file_stem()?.to_str()?.to_string();
                (!["lib", "main", "cloth", "examples", "benches"].contains(&name.as_str()))
                    .then_some(name)
            })
            .collect()
    };
    let mut modules = entries(&src);
    modules.extend(entries(&src.join("cloth")));
    modules.sort();
    let mut listed: Vec<String> = ALLOWED.iter().map(|(m, _)| m.to_string()).collect();
    listed.sort();
    assert_eq!(modules, listed, "ALLOWED must list every module of src/");
    let mut report = Vec::new();
    for (module, _) in ALLOWED {
        let files = module_files(module);
        assert!(!files.is_empty(), "no source for {module}");
        for (file, depth) in files {
            let text = std::fs::read_to_string(&file).expect("a source file");
            for v in violations(&text, module, depth) {
                let rel = file.strip_prefix(&src).expect("under src");
                report.push(format!("src/{}:{}: `{}`", rel.display(), v.line, v.path));
            }
        }
    }
    assert!(
        report.is_empty(),
        "modules reach where their layer may not:\n{}",
        report.join("\n")
    );
}

/// The cloth library stands alone: none of the debugger's crates (Rerun,
/// egui, the command line, the fitting, the plots) nor `weft` itself among
/// its dependencies (so none in its tree: `cargo tree -p weft-cloth`).
#[test]
fn the_cloth_library_depends_on_nothing_of_the_application() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/cloth/Cargo.toml");
    let text = std::fs::read_to_string(&manifest).expect("src/cloth/Cargo.toml");
    let table: toml::Table = text.parse().expect("a manifest");
    let deps = table["dependencies"].as_table().expect("[dependencies]");
    let application = [
        "weft",
        "rerun",
        "re_log",
        "re_viewer",
        "egui",
        "eframe",
        "tokio",
        "image",
        "clap",
        "anyhow",
        "indicatif",
        "ctrlc",
        "serde_json",
        "argmin",
        "argmin-math",
        "rand_xoshiro",
        "plotters",
    ];
    let found: Vec<&String> = deps
        .keys()
        .filter(|d| application.contains(&d.as_str()) || d.starts_with("re_"))
        .collect();
    assert!(found.is_empty(), "weft-cloth depends on {found:?}");
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
    let found: Vec<(usize, String)> = violations(text, "solver", 2)
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
    // `super::super` from two modules deep stays inside the module.
    assert!(violations("use super::super::cloth::ClothSpec;", "solver", 2).is_empty());
    // A library below the command line may not use it, nor the window.
    let compare =
        "use crate::cli::output::out;\nuse crate::record::Figures;\nlet u = egui::Ui::new();";
    let found: Vec<usize> = violations(compare, "compare", 1)
        .into_iter()
        .map(|v| v.line)
        .collect();
    assert_eq!(found, [1, 3]);
    // The command line may use the libraries; the telemetry not the record.
    assert!(violations("use crate::compare::read_all;", "cli", 1).is_empty());
    assert_eq!(violations("$crate::record::Run", "telemetry", 0).len(), 1);
}
