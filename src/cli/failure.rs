//! A recording whose writing failed, told in weft's words.

/// What became of a recording to `path` whose writing failed by frame
/// `frame` (the writer reports it late), in weft's words: why (Rerun's file writer reports only that it
/// stopped, so a full disk is looked for beside the file) and how many
/// frames the file holds, read back (a file cut short reads up to its last
/// whole message).
pub(crate) fn write_failure(path: &std::path::Path, frame: u64) -> String {
    let why = if no_space_beside(path) {
        "no space left on device"
    } else {
        "the file writer stopped"
    };
    let saved = crate::telemetry::read::read(path)
        .map(|r| r.frames(crate::telemetry::paths::PARTICLES).len())
        .unwrap_or(0);
    format!(
        "writing {} failed: {why}; {saved} of {frame} frames saved, readable by `weft replay` and `weft compare` up to the cut",
        path.display()
    )
}

/// Whether the file system that holds `path` is full: a small file beside
/// it cannot be written.
fn no_space_beside(path: &std::path::Path) -> bool {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => std::path::Path::new("."),
    };
    let probe = dir.join(format!(".weft-space-{}", std::process::id()));
    let full = std::fs::write(&probe, [0u8; 4096])
        .is_err_and(|e| e.kind() == std::io::ErrorKind::StorageFull);
    let _ = std::fs::remove_file(&probe);
    full
}
