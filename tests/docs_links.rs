//! Every relative link in the documentation points at something that exists.
//!
//! Walks README.md, ARCHITECTURE.md, BENCHMARKS.md, docs/*.md and
//! presets/README.md, finds each markdown link or image `](target)` outside
//! code (fenced blocks and inline code spans), and checks that the target
//! file or directory exists, relative to the linking file. A `#anchor` into
//! a markdown file must name one of its headings, slugged as GitHub does
//! (lower case; letters, digits, spaces, `-` and `_` kept, the rest dropped;
//! spaces to `-`; a repeated heading gets `-1`, `-2`, …). Links with a scheme
//! (`https:`, `mailto:`) are not checked.
//!
//! Standard library only, so it also runs without cargo:
//! `rustc --edition 2024 --test tests/docs_links.rs -o /tmp/dl && /tmp/dl`
//! from the repository's root.

use std::collections::{BTreeSet, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

/// The repository's root: cargo's manifest directory, or the current one.
fn root() -> PathBuf {
    match option_env!("CARGO_MANIFEST_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => std::env::current_dir().expect("a current directory"),
    }
}

/// The documentation files, relative to the root.
fn documents(root: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = [
        "README.md",
        "ARCHITECTURE.md",
        "BENCHMARKS.md",
        "presets/README.md",
    ]
    .iter()
    .map(PathBuf::from)
    .collect();
    let mut docs: Vec<PathBuf> = fs::read_dir(root.join("docs"))
        .expect("docs/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .map(|p| p.strip_prefix(root).unwrap().to_path_buf())
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// The lines of `text` outside fenced code blocks, with their numbers (from 1).
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<String> = None;
    let mut lines = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let marker: String = trimmed
            .chars()
            .take_while(|&c| c == '`' || c == '~')
            .collect();
        if marker.len() >= 3 && marker.chars().all(|c| c == marker.chars().next().unwrap()) {
            match &fence {
                None => {
                    fence = Some(marker);
                    continue;
                }
                Some(open) if marker.starts_with(open.as_str()) && trimmed.trim() == marker => {
                    fence = None;
                    continue;
                }
                Some(_) => {}
            }
        }
        if fence.is_none() {
            lines.push((i + 1, line));
        }
    }
    lines
}

/// `line` with its inline code spans blanked (a run of n backticks up to the
/// next run of exactly n); an unclosed run stays as it is.
fn without_code(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let n = chars[i..].iter().take_while(|&&c| c == '`').count();
        let mut j = i + n;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let m = chars[j..].iter().take_while(|&&c| c == '`').count();
                if m == n {
                    close = Some(j);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match close {
            Some(j) => {
                out.push_str(&" ".repeat(j + n - i));
                i = j + n;
            }
            None => {
                out.extend(&chars[i..i + n]);
                i += n;
            }
        }
    }
    out
}

/// The targets of the links `](target)` in one line of prose.
fn link_targets(line: &str) -> Vec<String> {
    let line = without_code(line);
    let mut targets = Vec::new();
    let mut rest = line.as_str();
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let (target, after) = if let Some(inner) = rest.strip_prefix('<') {
            match inner.find('>') {
                Some(end) => (&inner[..end], &inner[end..]),
                None => continue,
            }
        } else {
            // Up to the closing parenthesis (balanced) or a title after a space.
            let mut depth = 0;
            let mut end = rest.len();
            for (k, c) in rest.char_indices() {
                match c {
                    '(' => depth += 1,
                    ')' if depth == 0 => {
                        end = k;
                        break;
                    }
                    ')' => depth -= 1,
                    c if c.is_whitespace() => {
                        end = k;
                        break;
                    }
                    _ => {}
                }
            }
            (&rest[..end], &rest[end..])
        };
        targets.push(target.to_string());
        rest = after;
    }
    targets
}

/// A heading's text as GitHub renders it for its anchor: links to their
/// text, code and emphasis marks dropped.
fn heading_text(raw: &str) -> String {
    let mut text = String::new();
    let mut rest = raw;
    // [text](url) -> text
    while let Some(open) = rest.find('[') {
        match rest[open..].find("](") {
            Some(mid) => {
                let mid = open + mid;
                match rest[mid..].find(')') {
                    Some(close) => {
                        text.push_str(&rest[..open]);
                        text.push_str(&rest[open + 1..mid]);
                        rest = &rest[mid + close + 1..];
                    }
                    None => break,
                }
            }
            None => break,
        }
    }
    text.push_str(rest);
    text.chars().filter(|&c| c != '`' && c != '*').collect()
}

/// GitHub's anchor for a heading's text.
fn slug(text: &str) -> String {
    heading_text(text)
        .trim()
        .to_lowercase()
        .chars()
        .filter(|&c| c.is_alphanumeric() || c == ' ' || c == '-' || c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor of a markdown text: its headings' slugs (repeats numbered as
/// GitHub does) and any explicit `id="…"` or `name="…"`.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut set = BTreeSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let mut heading = line[hashes..].trim();
            // An optional closing sequence of #s.
            let stripped = heading.trim_end_matches('#');
            if stripped.len() < heading.len() && (stripped.is_empty() || stripped.ends_with(' ')) {
                heading = stripped.trim_end();
            }
            let base = slug(heading);
            let n = seen.entry(base.clone()).or_insert(0);
            let anchor = if *n == 0 {
                base.clone()
            } else {
                format!("{base}-{n}")
            };
            *n += 1;
            set.insert(anchor);
        }
        for key in ["id=\"", "name=\""] {
            let mut rest = line;
            while let Some(at) = rest.find(key) {
                rest = &rest[at + key.len()..];
                if let Some(end) = rest.find('"') {
                    set.insert(rest[..end].to_string());
                    rest = &rest[end..];
                }
            }
        }
    }
    set
}

/// Every broken relative link in the documentation under `root`, one message each.
fn broken_links(root: &Path) -> Vec<String> {
    let mut cache: HashMap<PathBuf, BTreeSet<String>> = HashMap::new();
    let mut broken = Vec::new();
    for doc in documents(root) {
        let text = fs::read_to_string(root.join(&doc))
            .unwrap_or_else(|e| panic!("{}: {e}", doc.display()));
        let dir = doc.parent().unwrap_or(Path::new("")).to_path_buf();
        for (n, line) in prose_lines(&text) {
            for target in link_targets(line) {
                if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                let (path, anchor) = match target.split_once('#') {
                    Some((p, a)) => (p, Some(a)),
                    None => (target.as_str(), None),
                };
                let file = if path.is_empty() {
                    doc.clone()
                } else {
                    dir.join(path)
                };
                let full = root.join(&file);
                if !full.exists() {
                    broken.push(format!(
                        "{}:{n}: `{target}`: no such file {}",
                        doc.display(),
                        file.display()
                    ));
                    continue;
                }
                let Some(anchor) = anchor else { continue };
                if full.extension().is_none_or(|x| x != "md") {
                    continue;
                }
                let set = cache
                    .entry(full.clone())
                    .or_insert_with(|| anchors(&fs::read_to_string(&full).unwrap_or_default()));
                if !set.contains(anchor) {
                    broken.push(format!(
                        "{}:{n}: `{target}`: no heading with anchor #{anchor} in {}",
                        doc.display(),
                        file.display()
                    ));
                }
            }
        }
    }
    broken
}

#[test]
fn every_relative_link_in_the_docs_resolves() {
    let broken = broken_links(&root());
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn anchors_are_slugged_as_github_does() {
    assert_eq!(
        slug("`weft compare A.rrd B.rrd [C.rrd …]`"),
        "weft-compare-arrd-brrd-crrd-"
    );
    assert_eq!(
        slug("`weft sweep PRESET --set KEY=V1,V2,… [--set …] --out DIR`"),
        "weft-sweep-preset---set-keyv1v2---set----out-dir"
    );
    assert_eq!(
        slug("11b. Self-collision: the paper's future work"),
        "11b-self-collision-the-papers-future-work"
    );
    assert_eq!(slug("A [linked](x.md) *heading*"), "a-linked-heading");
    let set = anchors("# A\n\n```\n# not a heading\n```\n\n## A\n### B ##\n");
    assert_eq!(set.into_iter().collect::<Vec<_>>(), ["a", "a-1", "b"]);
}

#[test]
fn links_in_code_are_not_links() {
    assert_eq!(
        link_targets("see [x](a.md) and `[y](b.md)` and ``[z](c.md)``"),
        ["a.md"]
    );
    assert_eq!(
        link_targets("![pic](p.png \"title\") [q](<d e.md>)"),
        ["p.png", "d e.md"]
    );
    assert_eq!(prose_lines("a\n```sh\n[x](y)\n```\nb").len(), 2);
}

#[test]
fn a_broken_link_is_found() {
    let dir = std::env::temp_dir().join(format!("weft-docs-links-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("docs")).unwrap();
    fs::create_dir_all(dir.join("presets")).unwrap();
    fs::write(
        dir.join("README.md"),
        "# Weft\n\n[ok](docs/a.md#part-one) [gone](docs/b.md)\n",
    )
    .unwrap();
    fs::write(
        dir.join("ARCHITECTURE.md"),
        "[bad anchor](docs/a.md#part-two) [self](#map)\n\n## Map\n",
    )
    .unwrap();
    fs::write(dir.join("BENCHMARKS.md"), "`[code](nowhere.md)`\n").unwrap();
    fs::write(dir.join("presets/README.md"), "[up](../README.md#weft)\n").unwrap();
    fs::write(dir.join("docs/a.md"), "## Part one\n").unwrap();
    let broken = broken_links(&dir);
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(broken.len(), 2, "{broken:#?}");
    assert!(broken[0].contains("docs/b.md"), "{broken:#?}");
    assert!(broken[1].contains("#part-two"), "{broken:#?}");
}
