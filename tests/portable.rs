//! The same bits with another C math library: `weft` runs every shipped
//! preset to the same final state with a math library preloaded whose
//! single-precision functions differ from the platform's in the last bit
//! (`tests/other-libm.c`), so a recording replays on a machine with another
//! C library. A step that called the platform's `sinf`, `atan2f` or `powf`
//! would fail here: weft before `solver::portable` moved every preset's
//! final state under it (docs/method.md, "The same bits on another machine").

#![cfg(target_os = "linux")]

use std::path::Path;
use std::process::Command;

/// Builds `tests/other-libm.c` into `dir` with the C compiler (`cc`).
fn other_libm(dir: &Path) -> std::path::PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/other-libm.c");
    let library = dir.join("other-libm.so");
    let out = Command::new("cc")
        .args(["-shared", "-fPIC", "-O2", "-fno-builtin", "-o"])
        .arg(&library)
        .arg(&source)
        .arg("-lm")
        .output()
        .expect("a C compiler (cc) to build tests/other-libm.c");
    assert!(
        out.status.success(),
        "cc failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    library
}

/// `weft record PRESET --level off` for `frames` frames, with `preload`
/// preloaded if given; the final state's digest.
fn final_state(preset: &str, frames: u32, preload: Option<&Path>, summary: &Path) -> String {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_weft"));
    cmd.args(["record", preset, "--level", "off", "--frames"])
        .arg(frames.to_string())
        .arg("--summary")
        .arg(summary);
    if let Some(library) = preload {
        cmd.env("LD_PRELOAD", library);
    }
    let out = cmd.output().expect("weft runs");
    assert!(
        out.status.success(),
        "{preset} (preloaded: {}): {}",
        preload.is_some(),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(summary).expect("the summary");
    let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    json["figures"]["final_state"]
        .as_str()
        .expect("a final state")
        .to_string()
}

#[test]
fn another_c_math_library_changes_no_result() {
    let dir = tempfile::tempdir().unwrap();
    let library = other_libm(dir.path());
    let summary = dir.path().join("summary.json");
    // Each preset's scene exercises its own functions: the car's path, pitch
    // and roll, the wind's gusts and sway, the runner's stride and the
    // cloth's placement by Euler angles; the update's arctangent and the
    // damping's power run in all.
    for (preset, frames) in [
        ("flag_on_car", 240),
        ("windy_flag", 240),
        ("cape_runner", 240),
        ("sphere_drape", 120),
    ] {
        let own = final_state(preset, frames, None, &summary);
        let other = final_state(preset, frames, Some(&library), &summary);
        assert_eq!(
            own, other,
            "{preset}: another C math library changed the final state"
        );
    }
}
