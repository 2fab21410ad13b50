//! The cloth library steps a preset to the same bits as the debugger: each
//! shipped preset, stepped through `weft_cloth`'s public API from a plain
//! host loop on 1 and on 2 threads, ends in the final state `weft record`
//! reports. And a preset file written out (as the window's Save or `weft
//! fit` write one) loads in the library and runs the same.

mod common;

use common::weft;
use weft_cloth::scene::{Scene, load, shipped};

/// Frames stepped: two simulated seconds, past every preset's first jolt.
const FRAMES: u64 = 120;

/// The final-state digest `weft record` reports for `preset`.
fn recorded(preset: &str, dir: &std::path::Path) -> String {
    let summary = dir.join(format!("{}.json", preset.replace('/', "_")));
    let out = weft()
        .args([
            "record",
            preset,
            "--frames",
            &FRAMES.to_string(),
            "--level",
            "off",
        ])
        .arg("--summary")
        .arg(&summary)
        .output()
        .unwrap();
    let text = std::fs::read_to_string(&summary)
        .unwrap_or_else(|_| panic!("{preset}: {}", String::from_utf8_lossy(&out.stderr)));
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["figures"]["final_state"].as_str().unwrap().to_string()
}

/// The digest after a host's plain loop over the library on `threads` threads.
fn hosted(preset: &str, threads: usize) -> String {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let loaded = load::load(preset, &[]).unwrap();
        let mut scene = Scene::new(&loaded.preset).unwrap();
        for _ in 0..FRAMES {
            scene.step().unwrap();
        }
        format!("{:016x}", scene.solver().state().digest())
    })
}

#[test]
fn every_shipped_preset_steps_to_the_recorded_bits_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    for p in shipped::ALL {
        let expected = recorded(p.name, dir.path());
        for threads in [1, 2] {
            assert_eq!(
                hosted(p.name, threads),
                expected,
                "{} on {threads} thread(s)",
                p.name
            );
        }
    }
}

#[test]
fn a_preset_written_out_loads_in_the_library_and_runs_the_same() {
    let dir = tempfile::tempdir().unwrap();
    // What the window's Save and `weft fit` write: the resolved preset.
    let shown = weft()
        .args([
            "show",
            "cape_runner",
            "--set",
            "solver.weights.curvature=0.2",
        ])
        .output()
        .unwrap();
    assert!(shown.status.success(), "{shown:?}");
    let file = dir.path().join("tuned.toml");
    std::fs::write(&file, &shown.stdout).unwrap();
    let path = file.to_str().unwrap();
    assert_eq!(hosted(path, 1), recorded(path, dir.path()));
}

#[test]
fn a_preset_names_its_format_and_one_from_a_newer_weft_is_refused() {
    let shown = weft().args(["show", "hanging_sheet"]).output().unwrap();
    let text = String::from_utf8(shown.stdout).unwrap();
    let line = format!("format = {}", weft_cloth::scene::FORMAT);
    assert!(text.lines().any(|l| l == line), "{text}");
    assert!(load::parse("saved", &text).is_ok());
    let later = text.replace(
        &line,
        &format!("format = {}", weft_cloth::scene::FORMAT + 1),
    );
    let e = load::parse("later.toml", &later).unwrap_err().to_string();
    assert!(e.contains("later.toml") && e.contains("format"), "{e}");
    assert!(e.contains("update weft"), "{e}");
}
