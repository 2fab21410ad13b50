//! The solver's own layers, checked: each of its modules uses only the
//! modules below it (ARCHITECTURE.md, "Layers"), so the solver reads from
//! the bottom up and no two of its modules need each other.
//!
//! From the bottom: the leaves (the portable maths, the ranges, the
//! rotation maths, the threads, the frame, Eq. 3, the colliders); the cloth
//! and its grid; the SIMD kernels; the update phase, the pull and
//! self-collision's part; the constraint families (with their violation);
//! the parameters (one weight per family) and the diagnostics; and on top
//! the solver's own step (`mod.rs`, `step.rs`, `adjust.rs`, `measure.rs`:
//! one type's methods), which may use everything. This test reads every
//! source file of `src/cloth/solver/`, resolves each path that reaches
//! another of its modules (also through the names `solver/mod.rs`
//! re-exports, and inside `use` groups that span lines) and fails with the
//! file and line of each that reaches where its module may not.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[path = "source/mod.rs"]
mod source;
use source::{paths_in, rust_files};

/// The root's own items (`Solver`, `StepError`, …) are this module.
const ROOT: &str = "Solver";

/// Each module of the solver and the modules (and [`ROOT`]) it may use.
const LAYERS: [(&str, &[&str]); 20] = [
    ("portable", &[]),
    ("range", &[]),
    ("team", &[]),
    ("frame", &[]),
    ("rotation", &["portable"]),
    ("forced_rotation", &["portable"]),
    ("collision", &["portable"]),
    ("cloth", &["range", "rotation", "portable"]),
    ("topology", &["cloth"]),
    (
        "kernels",
        &["forced_rotation", "rotation", "team", "portable"],
    ),
    ("pull", &["range"]),
    (
        "update",
        &[
            "cloth",
            "collision",
            "kernels",
            "rotation",
            "team",
            "portable",
        ],
    ),
    (
        "self_collision",
        &[
            "cloth", "topology", "kernels", "rotation", "team", "portable",
        ],
    ),
    (
        "families",
        &[
            "self_collision",
            "cloth",
            "topology",
            "kernels",
            "forced_rotation",
            "team",
        ],
    ),
    (
        "params",
        &["families", "forced_rotation", "range", "portable"],
    ),
    (
        "diagnostics",
        &[
            "families",
            "self_collision",
            "cloth",
            "topology",
            "kernels",
            "team",
        ],
    ),
    ("adjust", ALL),
    ("measure", ALL),
    ("step", ALL),
    ("mod", ALL),
];

/// The solver's step: its files are the methods of one type, and use every
/// module below.
const ALL: &[&str] = &["*"];

fn may_use(module: &str, other: &str) -> bool {
    let (_, allowed) = LAYERS
        .iter()
        .find(|(m, _)| *m == module)
        .unwrap_or_else(|| panic!("LAYERS must list the solver's module {module}"));
    other == module || allowed.contains(&"*") || allowed.contains(&other)
}

fn solver_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src/cloth/solver")
}

/// The solver's top-level modules, from its folder.
fn modules() -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(solver_dir())
        .expect("the solver's folder")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
        .filter_map(|p| Some(p.file_stem()?.to_str()?.to_string()))
        .collect();
    out.sort();
    out
}

/// A file's module path under the solver: `self_collision/path/mod.rs`
/// is `[self_collision, offset]`, `step.rs` is `[step]`, `mod.rs` is `[]`.
fn module_path(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(solver_dir()).expect("under the solver");
    let mut parts: Vec<String> = rel
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The names `solver/mod.rs` re-exports, with the module each comes from.
fn reexports() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(solver_dir().join("mod.rs")).expect("solver/mod.rs");
    let mut out = BTreeMap::new();
    for (_, path) in use_paths(&code_of(&text)) {
        let segments: Vec<&str> = path.split("::").collect();
        if let [module, .., item] = segments[..] {
            out.insert(item.to_string(), module.to_string());
        }
    }
    out
}

/// The text without comments and without the test module at its end.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    text.lines()
        .map(|l| l.split("//").next().unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every path a `use` item names, with its line: `use a::{b, c::{d as e}};`
/// gives `a::b` and `a::c::d`.
fn use_paths(code: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut rest = code;
    let mut offset = 0;
    while let Some(at) = find_use(rest) {
        let start = at + "use ".len();
        let end = rest[start..].find(';').map_or(rest.len(), |e| start + e);
        let line = code[..offset + at].matches('\n').count() + 1;
        for path in expand(&rest[start..end]) {
            out.push((line, path));
        }
        offset += end;
        rest = &rest[end..];
    }
    out
}

/// Where the next `use` item starts (at a line's start, after `pub…`).
fn find_use(code: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(k) = code[from..].find("use ") {
        let at = from + k;
        let before = code[..at].rsplit('\n').next().unwrap_or_default().trim();
        if before.is_empty() || before.starts_with("pub") {
            return Some(at);
        }
        from = at + 4;
    }
    None
}

/// The paths of one use tree.
fn expand(tree: &str) -> Vec<String> {
    let tree: String = tree.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut out = Vec::new();
    expand_into("", tree.trim(), &mut out);
    out
}

fn expand_into(prefix: &str, tree: &str, out: &mut Vec<String>) {
    let join = |p: &str| {
        if prefix.is_empty() {
            p.to_string()
        } else {
            format!("{prefix}::{p}")
        }
    };
    match tree.find('{') {
        Some(open) => {
            let head = tree[..open].trim().trim_end_matches("::");
            let inner = &tree[open + 1..tree.rfind('}').expect("a closed group")];
            let prefix = join(head);
            for part in split_top(inner) {
                let part = part.trim();
                if part == "self" {
                    out.push(prefix.clone());
                } else if !part.is_empty() {
                    expand_into(&prefix, part, out);
                }
            }
        }
        None => {
            let path = tree.split(" as ").next().unwrap_or(tree).trim();
            out.push(join(path));
        }
    }
}

/// A group's items, split at the commas outside inner groups.
fn split_top(inner: &str) -> Vec<&str> {
    let (mut out, mut depth, mut from) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&inner[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    out.push(&inner[from..]);
    out
}

/// The code with its `use` items blanked out (their lines kept).
fn without_uses(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = find_use(rest) {
        let end = rest[at..].find(';').map_or(rest.len(), |e| at + e + 1);
        out.push_str(&rest[..at]);
        out.extend(rest[at..end].chars().filter(|c| *c == '\n'));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// Every `a::b` path outside `use` items, with its line.
fn code_paths(code: &str) -> Vec<(usize, String)> {
    let code = without_uses(code);
    let lines = code.lines().enumerate();
    lines
        .flat_map(|(i, line)| paths_in(line).into_iter().map(move |p| (i + 1, p)))
        .collect()
}

/// The solver module a path written in the module at `at` reaches, if it
/// reaches one of the solver's modules at all.
fn target(path: &str, at: &[String], names: &BTreeMap<String, String>) -> Option<String> {
    let segments: Vec<&str> = path.split("::").collect();
    let rest: Vec<&str> = match segments[..] {
        ["crate" | "$crate", "solver", ref rest @ ..] => rest.to_vec(),
        ["super", ..] => {
            let supers = segments.iter().take_while(|s| **s == "super").count();
            let base = &at[..at.len().saturating_sub(supers)];
            if let Some(top) = base.first() {
                return Some(top.clone());
            }
            segments[supers..].to_vec()
        }
        _ => return None,
    };
    let first = rest.first()?;
    let modules = modules();
    Some(if modules.iter().any(|m| m == first) {
        first.to_string()
    } else if let Some(module) = names.get(*first) {
        module.clone()
    } else {
        ROOT.to_string()
    })
}

/// Every path of the solver's files that reaches where its module may not,
/// as `file:line: path (module → other)`.
fn report() -> (Vec<String>, BTreeMap<String, Vec<String>>) {
    let names = reexports();
    let mut all = Vec::new();
    rust_files(&solver_dir(), &mut all);
    all.sort();
    let (mut bad, mut graph) = (Vec::new(), BTreeMap::<String, Vec<String>>::new());
    for file in all {
        let at = module_path(&file);
        let module = at.first().cloned().unwrap_or_else(|| "mod".to_string());
        let code = code_of(&std::fs::read_to_string(&file).expect("a source file"));
        let mut paths = use_paths(&code);
        paths.extend(code_paths(&code));
        for (line, path) in paths {
            let Some(other) = target(&path, &at, &names) else {
                continue;
            };
            if other == module {
                continue;
            }
            let uses = graph.entry(module.clone()).or_default();
            if !uses.contains(&other) {
                uses.push(other.clone());
            }
            if !may_use(&module, &other) {
                let rel = file.strip_prefix(solver_dir()).expect("under the solver");
                bad.push(format!(
                    "src/cloth/solver/{}:{line}: `{path}` ({module} uses {other})",
                    rel.display()
                ));
            }
        }
    }
    (bad, graph)
}

#[test]
fn every_solver_module_uses_only_the_modules_below_it() {
    let mut listed: Vec<String> = LAYERS.iter().map(|(m, _)| m.to_string()).collect();
    listed.sort();
    assert_eq!(
        modules(),
        listed,
        "LAYERS must list every module of the solver"
    );
    // The table is itself a layering: a module uses only modules listed
    // before it (so no two can need each other).
    for (k, (module, allowed)) in LAYERS.iter().enumerate() {
        for other in allowed.iter().filter(|o| **o != "*") {
            assert!(
                LAYERS[..k].iter().any(|(m, _)| m == other),
                "{module} may use {other}, which is not below it in LAYERS"
            );
        }
    }
    let (bad, graph) = report();
    assert!(
        bad.is_empty(),
        "solver modules reach where their layer may not:\n{}\n(what each uses: {graph:?})",
        bad.join("\n")
    );
}

/// The checker finds what it must (so the test above can fail).
#[test]
fn the_checker_resolves_groups_supers_and_reexports() {
    let code = code_of(
        "use super::{\n    cloth::ClothState,\n    rotation::{normal_of, rotate as r},\n};\n\
         // use super::step::X; a comment\n\
         let v = crate::solver::families::violation(m);\n\
         #[cfg(test)]\nmod tests {\n    use crate::solver::step;\n}\n",
    );
    let mut paths = use_paths(&code);
    paths.extend(code_paths(&code));
    assert_eq!(
        paths,
        vec![
            (1, "super::cloth::ClothState".to_string()),
            (1, "super::rotation::normal_of".to_string()),
            (1, "super::rotation::rotate".to_string()),
            (6, "crate::solver::families::violation".to_string()),
        ]
    );
    let names = BTreeMap::from([("Violation".to_string(), "families".to_string())]);
    let at = |p: &[&str]| p.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let from_kernels = at(&["kernels", "lanes", "math"]);
    assert_eq!(
        target("super::Lane", &from_kernels, &names).as_deref(),
        Some("kernels")
    );
    assert_eq!(
        target("super::super::super::Violation", &from_kernels, &names).as_deref(),
        Some("families")
    );
    assert_eq!(
        target("crate::solver::Solver", &from_kernels, &names).as_deref(),
        Some(ROOT)
    );
    assert_eq!(target("glam::Vec3", &from_kernels, &names), None);
    assert!(!may_use("kernels", "families"));
    assert!(may_use("step", ROOT));
}
