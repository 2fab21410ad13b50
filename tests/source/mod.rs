//! Reading weft's source as text, for the layering tests: the `.rs` files
//! under a folder, and the paths a line of code names.

use std::path::{Path, PathBuf};

/// Every `a::b::c` path in a line of code (identifiers joined by `::`).
pub fn paths_in(code: &str) -> Vec<String> {
    let bytes = code.as_bytes();
    let ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'$';
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

/// Every `.rs` file under `dir`, into `out`.
pub fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source directory is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}
