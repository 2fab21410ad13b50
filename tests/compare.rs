//! Comparing runs: the preset diff, tuning changes with their frame, figures
//! with deltas, the first frame at which particle states part, the
//! comparison recording (overlaid metrics, cloths side by side, a
//! blueprint), the `--fail-if` gate and its exit codes, and bad input.

use std::path::Path;
use std::process::Output;

use weft::compare::gate::{Bound, Limit, check};
use weft::compare::{RunData, read_all, state_diff};
use weft::record::Run;
use weft::scene::{Override, Scene, load};
use weft::solver::Family;
use weft::telemetry::{Telemetry, read};

mod common;
use common::weft;

fn compare(args: &[&str], files: &[&Path]) -> Output {
    weft()
        .arg("compare")
        .args(files)
        .args(args)
        .output()
        .unwrap()
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

/// Records `frames` frames of `name` in-process at level summary; at frame
/// `change.0` the curvature weight becomes `change.1`. `finish: false`
/// leaves the recording without its summary, like a killed run.
fn record(
    path: &Path,
    name: &str,
    sets: &[&str],
    frames: u64,
    change: Option<(u64, f32)>,
    finish: bool,
) {
    let mut overrides: Vec<Override> = sets.iter().map(|s| s.parse().unwrap()).collect();
    overrides.push("telemetry.level=\"summary\"".parse().unwrap());
    let loaded = load::load(name, &overrides).unwrap();
    let scene = Scene::new(&loaded.preset).unwrap();
    let rec = rerun::RecordingStreamBuilder::new("weft")
        .save(path)
        .unwrap();
    let mut run = Run::start(
        scene,
        Telemetry::new(rec.clone(), loaded.preset.telemetry),
        name,
        &loaded.resolved,
    )
    .unwrap();
    for _ in 0..frames {
        if let Some((at, curvature)) = change
            && run.scene.frame() + 1 == at
        {
            let mut p = *run.scene.solver().params();
            p.weights[Family::Curvature] = curvature;
            run.set_params(p).unwrap();
        }
        run.step().unwrap();
    }
    if finish {
        run.finish().unwrap();
    } else {
        run.telemetry.flush().unwrap();
    }
}

#[test]
fn two_runs_differing_in_tuning_are_compared_key_by_key_and_frame_by_frame() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("base.rrd");
    let b = dir.path().join("stiffer.rrd");
    let c = dir.path().join("tuned_later.rrd");
    record(&a, "hanging_sheet", &[], 12, None, true);
    record(
        &b,
        "hanging_sheet",
        &["solver.iterations=3"],
        12,
        None,
        true,
    );
    record(&c, "hanging_sheet", &[], 12, Some((7, 0.5)), true);

    let runs = read_all(&[a.clone(), b.clone(), c.clone()]).unwrap();
    // The change at frame 7 is the first frame whose particles differ.
    let d = state_diff(&runs[0], &runs[2]);
    assert_eq!(d.first_difference, Some(7));
    assert!(d.per_frame[..7].iter().all(|(_, x)| *x == 0.0));
    assert!(d.per_frame[7].1 > 0.0);
    assert_eq!(d.per_frame.len(), 13, "frames 0 to 12");
    assert_eq!(state_diff(&runs[0], &runs[1]).first_difference, Some(1));
    assert_eq!(state_diff(&runs[0], &runs[0]).first_difference, None);
    assert_eq!(runs[2].changes.len(), 1);
    assert_eq!(runs[2].changes[0].0, 7);

    let cmp = dir.path().join("cmp.rrd");
    let o = compare(&["--save", cmp.to_str().unwrap()], &[&a, &b, &c]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{err}");
    let row = |key: &str| -> Vec<String> {
        out.lines()
            .find(|l| l.trim_start().starts_with(key))
            .unwrap_or_else(|| panic!("no row {key}: {out}"))
            .split_whitespace()
            .map(String::from)
            .collect()
    };
    assert_eq!(
        row("solver.iterations"),
        ["solver.iterations", "1", "3", "1"]
    );
    assert_eq!(
        out.lines()
            .filter(|l| l.starts_with("  solver.") || l.starts_with("  cloth."))
            .count(),
        1,
        "only the key that differs: {out}"
    );
    assert!(out.contains("tuned_later  frame 7 ("), "{out}");
    assert!(out.contains("solver.weights.curvature 0.1 → 0.5"), "{out}");
    assert!(
        out.contains("stiffer      first differs at frame 1"),
        "{out}"
    );
    assert!(
        out.contains("tuned_later  first differs at frame 7"),
        "{out}"
    );
    assert!(out.contains("max strain"), "{out}");
    assert!(out.contains(" %)"), "deltas against A: {out}");

    // The comparison recording: one series per run in the same plots, the
    // cloths side by side, each run's events, and a blueprint.
    let rec = read::read(&cmp).unwrap();
    for run in ["base", "stiffer", "tuned_later"] {
        for path in [
            format!("metrics/strain/{run}"),
            format!("metrics/energy/{run}"),
            format!("metrics/flipped/{run}"),
            format!("metrics/violation/stretch/{run}"),
            format!("world/{run}/particles"),
            format!("world/{run}/mesh"),
        ] {
            assert_eq!(
                rec.frames(&path).len(),
                if path.contains("world") { 13 } else { 12 },
                "{path}"
            );
        }
    }
    assert_eq!(rec.frames("metrics/difference/stiffer").len(), 13);
    assert!(rec.entities["events/tuned_later"].frames.contains(&7));
    assert!(has_blueprint(&cmp), "the file carries its layout");

    // Overlaid: all cloths where they were recorded.
    let over = dir.path().join("over.rrd");
    let o = compare(&["--overlay", "--save", over.to_str().unwrap()], &[&a, &b]);
    assert_eq!(o.status.code(), Some(0));
}

/// Whether a `.rrd` holds a blueprint store (its default layout).
fn has_blueprint(path: &Path) -> bool {
    use rerun::external::re_log_encoding::DecoderApp;
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    DecoderApp::decode_eager(file)
        .unwrap()
        .filter_map(Result::ok)
        .any(|m| m.store_id().is_blueprint())
}

#[test]
fn fail_if_exits_1_with_a_table_of_what_regressed() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("good.rrd");
    let b = dir.path().join("worse.rrd");
    record(
        &a,
        "hanging_sheet",
        &["solver.iterations=3"],
        10,
        None,
        true,
    );
    record(
        &b,
        "hanging_sheet",
        &["solver.iterations=1"],
        10,
        None,
        true,
    );

    let o = compare(&["--fail-if", "max_strain > 1.1*A"], &[&a, &b]);
    let (out, _) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("regressed"), "{out}");
    assert!(
        out.contains("worse") && out.contains("max_strain > 1.1*A"),
        "{out}"
    );
    // The other way round nothing regressed.
    let o = compare(&["--fail-if", "max_strain > 1.1*A"], &[&b, &a]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).0);
    // An absolute bound checks every run, the baseline too.
    let o = compare(&["--fail-if", "max_violation.stretch >= 0"], &[&a, &b]);
    let (out, _) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(out.contains("good") && out.contains("worse"), "{out}");
    let o = compare(
        &["--fail-if", "frames < A", "--fail-if", "final_energy > 1e9"],
        &[&a, &b],
    );
    assert_eq!(o.status.code(), Some(0));

    for (bound, says) in [
        ("max_strane > A", "did you mean `max_strain`?"),
        ("max_strain 1.1*A", "no comparison"),
        ("max_strain > x*A", "`x` is not a number"),
        ("max_strain >", "no limit"),
        ("max_violation.wobble > 1", "unknown figure"),
    ] {
        let o = compare(&["--fail-if", bound], &[&a, &b]);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{bound}");
        assert!(err.contains(says), "{bound}: {err}");
    }

    // The parser, directly.
    let b: Bound = "steps_per_second < 0.8*A-1".parse().unwrap();
    assert_eq!(
        b.limit,
        Limit::Relative {
            scale: 0.8,
            offset: -1.0
        }
    );
    let b: Bound = "max_strain>A*1.5+0.01".parse().unwrap();
    assert_eq!(
        b.limit,
        Limit::Relative {
            scale: 1.5,
            offset: 0.01
        }
    );
    let b: Bound = "max_strain >= 0.05".parse().unwrap();
    assert_eq!(b.limit, Limit::Absolute(0.05));
    let runs: Vec<RunData> = read_all(&[a, dir.path().join("worse.rrd")]).unwrap();
    let r = check(&["max_strain > A".parse().unwrap()], &runs);
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].run, "worse");
    assert!(r[0].value > r[0].limit);
}

#[test]
fn bad_inputs_exit_2_after_comparing_what_can_be() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.rrd");
    record(&a, "hanging_sheet", &[], 8, None, true);

    // Not a recording at all.
    let junk = dir.path().join("junk.rrd");
    std::fs::write(&junk, "this is not a recording\n").unwrap();
    let o = compare(&[], &[&a, &junk]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).1.contains("junk.rrd: not a Rerun recording"),
        "{}",
        text(&o).1
    );

    // A Rerun recording, but not weft's (a comparison recording has no preset).
    let cmp = dir.path().join("cmp.rrd");
    assert!(
        compare(&["--save", cmp.to_str().unwrap()], &[&a])
            .status
            .success()
    );
    let o = compare(&[], &[&a, &cmp]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).1.contains("cmp.rrd: not a weft recording"),
        "{}",
        text(&o).1
    );

    // A run that never finished: compared up to where it stops.
    let cut = dir.path().join("cut.rrd");
    record(&cut, "hanging_sheet", &[], 5, None, false);
    let o = compare(&[], &[&a, &cut]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}{err}");
    assert!(out.contains("CUT SHORT"), "{out}");
    assert!(
        out.contains("cut          identical at all 6 frames both logged")
            || out.contains("identical at all 6 frames"),
        "{out}"
    );
    assert!(
        err.contains("cut.rrd is cut short (it holds frames up to 5"),
        "{err}"
    );

    // A file cut mid-message (a killed process, a full disk).
    let bytes = std::fs::read(&a).unwrap();
    let half = dir.path().join("half.rrd");
    std::fs::write(&half, &bytes[..bytes.len() * 3 / 4]).unwrap();
    let o = compare(&[], &[&a, &half]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}{err}");
    assert!(err.contains("half.rrd is cut short"), "{err}");

    // Different scenes: figures side by side, states not compared.
    let other = dir.path().join("other.rrd");
    record(&other, "stress_jerk", &[], 8, None, true);
    let o = compare(&[], &[&a, &other]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{out}{err}");
    assert!(out.contains("max strain"), "{out}");
    assert!(
        out.contains("other  not compared: their scenes differ beyond the tuning (attachments"),
        "{out}"
    );
    assert!(
        err.contains("a and other are runs of different scenes"),
        "{err}"
    );

    // A missing file.
    let o = compare(&[], &[&a, &dir.path().join("nope.rrd")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("nope.rrd"));
}

#[test]
fn sweep_points_and_record_files_compare_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    let o = weft()
        .args([
            "sweep",
            "hanging_sheet",
            "--set",
            "solver.weights.curvature=0.1,0.35",
            "--frames",
            "5",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let rec = dir.path().join("recorded.rrd");
    let o = weft()
        .args([
            "record",
            "hanging_sheet",
            "--frames",
            "5",
            "--level",
            "summary",
            "--save",
        ])
        .arg(&rec)
        .output()
        .unwrap();
    assert!(o.status.success());
    let p0 = out.join("0_curvature=0.1.rrd");
    let p1 = out.join("1_curvature=0.35.rrd");
    let o = compare(&[], &[&rec, &p0, &p1]);
    let (stdout, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{err}");
    // The recorded run has the same settings as point 0: identical states.
    assert!(
        stdout.contains("0_curvature=0.1   identical at all 6 frames"),
        "{stdout}"
    );
    assert!(stdout.contains("solver.weights.curvature  0.1"), "{stdout}");
    assert!(
        stdout.contains("1_curvature=0.35  first differs at frame"),
        "{stdout}"
    );
}
