//! Recording: every preset recorded and read back with Rerun's own decoder;
//! levels and `--log-every`; verdicts; nothing lost on Ctrl-C or failure;
//! bit-for-bit replay.

// Tests and benchmarks set their scenes up with glam's rotations and
// compare with the standard library: they run on one machine, so the
// platform's math library is fine here (see `solver::portable`).
#![allow(clippy::disallowed_methods)]

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use weft::record::{Figures, Run};
use weft::scene::preset::{Level, TelemetrySettings};
use weft::scene::{Override, Scene, load, shipped};
use weft::solver::Family;
use weft::telemetry::{Telemetry, paths, read};

mod common;
use common::weft;

fn sets(s: &[&str]) -> Vec<Override> {
    s.iter().map(|s| s.parse().unwrap()).collect()
}

/// A run of preset `name` with `--set` overrides, streaming to `rec`.
fn start_run(name: &str, overrides: &[&str], rec: rerun::RecordingStream) -> Run {
    let loaded = load::load(name, &sets(overrides)).unwrap();
    let scene = Scene::new(&loaded.preset).unwrap();
    let telemetry = Telemetry::new(rec, loaded.preset.telemetry);
    Run::start(scene, telemetry, name, &loaded.resolved).unwrap()
}

/// Records `frames` frames of `name` into `path` in-process; `between` runs
/// before every step (to change parameters, say).
fn record_to(
    path: &Path,
    name: &str,
    overrides: &[&str],
    frames: u64,
    mut between: impl FnMut(&mut Run),
) -> Figures {
    let rec = rerun::RecordingStreamBuilder::new("weft-test")
        .save(path)
        .unwrap();
    let mut run = start_run(name, overrides, rec);
    for _ in 0..frames {
        between(&mut run);
        run.step().unwrap();
    }
    run.finish().unwrap()
}

/// `frames` frames of `name` recorded at level summary, read back.
fn summary_of(name: &str, frames: u64) -> read::Recording {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{name}.rrd"));
    record_to(
        &path,
        name,
        &["telemetry.level=\"summary\""],
        frames,
        |_| {},
    );
    read::read(&path).unwrap()
}

#[test]
fn every_preset_records_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    for p in shipped::ALL {
        let path = dir.path().join(format!("{}.rrd", p.name));
        let frames = 4;
        record_to(&path, p.name, &["telemetry.level=\"full\""], frames, |_| {});
        let rec = read::read(&path).unwrap();
        let loaded = load::load(p.name, &sets(&["telemetry.level=\"full\""])).unwrap();
        let n = loaded.preset.cloth.weft as usize * loaded.preset.cloth.warp as usize;
        let dt = loaded.preset.solver.dt as f64;
        let all_frames: Vec<i64> = (0..=frames as i64).collect();

        for path in [paths::PARTICLES, paths::MESH, paths::NORMALS] {
            let e = rec
                .entities
                .get(path)
                .unwrap_or_else(|| panic!("{}: no {path}", p.name));
            assert_eq!(
                e.frames.iter().copied().collect::<Vec<_>>(),
                all_frames,
                "{}: {path} frames",
                p.name
            );
            // Every logged row holds one value per particle.
            let rows: Vec<usize> = e.lengths.iter().copied().filter(|l| *l > 0).collect();
            assert!(
                rows.len() > frames as usize && rows.iter().all(|l| *l == n),
                "{}: {path} lengths {rows:?}",
                p.name
            );
        }
        let particles = &rec.entities[paths::PARTICLES];
        let expected_times: Vec<i64> = all_frames
            .iter()
            .map(|f| (*f as f64 * dt * 1e9).round() as i64)
            .collect();
        let times: Vec<i64> = particles.sim_times.iter().copied().collect();
        for (t, e) in times.iter().zip(&expected_times) {
            assert!(
                (t - e).abs() <= 1_000,
                "{}: sim_time {t} ns, expected {e} ns",
                p.name
            );
        }
        for f in Family::ALL {
            for stat in ["max", "rms"] {
                let path = paths::violation(f, stat);
                assert_eq!(
                    rec.entities[&path].frames.len(),
                    frames as usize,
                    "{}: {path}",
                    p.name
                );
            }
            // A family's arrows are logged from the first frame that has
            // some to draw.
            for kind in ["dx", "dtheta"] {
                if let Some(e) = rec.entities.get(&paths::correction(f, kind)) {
                    assert!(e.lengths[0] > 0, "{}: {f:?} {kind} {:?}", p.name, e.lengths);
                }
            }
            if !f.turns() {
                assert!(
                    !rec.entities.contains_key(&paths::correction(f, "dtheta")),
                    "{}: δθ for {f:?}, which never turns",
                    p.name
                );
            }
            assert!(rec.entities.contains_key(&paths::adjust_time(f)));
        }
        for path in [
            paths::STRAIN,
            paths::NORMALS_FLIPPED,
            paths::NORMALS_OFFSET,
            paths::ENERGY,
            paths::TIME_TOTAL,
            paths::TIME_UPDATE,
            paths::TIME_TELEMETRY,
        ] {
            assert_eq!(
                rec.entities[path].frames.len(),
                frames as usize,
                "{}: {path}",
                p.name
            );
        }
        for body in &loaded.preset.bodies {
            assert!(
                rec.entities.contains_key(&paths::body(&body.name)),
                "{}: no body {}",
                p.name,
                body.name
            );
        }
        for path in [paths::PRESET, paths::VERSION, paths::TOPOLOGY] {
            assert!(
                rec.entities[path].is_static,
                "{}: {path} not static",
                p.name
            );
        }
        // The stored preset is the resolved one and loads back to the same scene.
        let stored = rec.preset.as_deref().unwrap();
        assert_eq!(stored, loaded.resolved);
        assert_eq!(load::parse("stored", stored).unwrap(), loaded.preset);
        assert_eq!(rec.params.len(), 1, "{}: parameters logged once", p.name);
        assert!(rec.summary.is_some());
    }
}

/// The figures that verdicts are judged on are the same at every level of
/// `weft record`: `off` measures the state itself, `summary` takes the
/// solver's diagnostics. Both report self-collision as 0 while the family
/// is off (even on a fold whose layers pass through each other), and alike
/// while it is on.
#[test]
fn figures_do_not_depend_on_the_telemetry_level() {
    let dir = tempfile::tempdir().unwrap();
    for weight in ["0", "1"] {
        let [off, summary] = ["off", "summary"].map(|level| {
            let path = dir.path().join(format!("{weight}-{level}.json"));
            let out = weft()
                .args(["record", "folding_sheet", "--level", level, "--summary"])
                .arg(&path)
                .args(["--set", &format!("solver.weights.self={weight}")])
                // The preset bounds its crossings at 0, for self-collision
                // on; off, its fold crosses.
                .args(["--set", "expect.max_crossings=100"])
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(0), "{level}: {out:?}");
            let json: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            json["figures"].clone()
        });
        for key in ["final_state", "max_strain", "max_violation"] {
            assert_eq!(off[key], summary[key], "self = {weight}: {key}");
        }
        let self_collision = off["max_violation"]["self"].as_f64().unwrap();
        match weight {
            "0" => assert_eq!(self_collision, 0.0, "the family is off"),
            _ => assert!(self_collision > 0.0, "the fold presses the layers"),
        }
    }
}

/// The plot of the normals against the surface carries, at every frame,
/// what the solver measures; colouring by the offset shows a flipped
/// element at the top of the ramp and the rest at its bottom.
#[test]
fn normals_against_the_surface_are_plotted_and_coloured() {
    use weft::scene::preset::ColorBy;
    let frames = 6;
    let rec = summary_of("windy_flag", frames);
    let loaded = load::load("windy_flag", &[]).unwrap();
    let mut scene = Scene::new(&loaded.preset).unwrap();
    let (mut flipped, mut offset) = (Vec::new(), Vec::new());
    for frame in 1..=frames as i64 {
        scene.step().unwrap();
        let o = scene.solver().orientation();
        flipped.push((frame, o.flipped as f64));
        offset.push((frame, o.offset_rms as f64));
    }
    let plotted = |path: &str| -> Vec<(i64, f64)> {
        rec.scalars[path]
            .iter()
            .map(|s| (s.frame, s.value))
            .collect()
    };
    assert_eq!(plotted(paths::NORMALS_FLIPPED), flipped);
    assert_eq!(plotted(paths::NORMALS_OFFSET), offset);
    assert!(offset.iter().all(|&(_, v)| v > 0.0), "{offset:?}");

    let flip = 7;
    let st = scene.solver_mut().state_mut();
    st.orientation[flip] = glam::Quat::from_rotation_x(std::f32::consts::PI) * st.orientation[flip];
    let offsets = scene.solver().normal_offsets();
    let colours = weft::telemetry::color::particles(ColorBy::NormalOffset, &scene);
    for (i, (c, a)) in colours.iter().zip(&offsets).enumerate() {
        assert_eq!(*c, weft::telemetry::color::ramp(a / std::f32::consts::PI));
        if i != flip {
            assert!(*a < 0.5, "{i}: {a}");
        }
    }
    assert!(offsets[flip] > 2.6, "{}", offsets[flip]);
}

#[test]
fn level_off_logs_no_frames_and_log_every_thins_them() {
    let dir = tempfile::tempdir().unwrap();
    let off = dir.path().join("off.rrd");
    record_to(
        &off,
        "hanging_sheet",
        &["telemetry.level=\"off\""],
        6,
        |_| {},
    );
    let rec = read::read(&off).unwrap();
    for (path, e) in &rec.entities {
        let per_frame = e.frames.iter().any(|f| *f > 0);
        assert!(
            !per_frame,
            "level off logged {path} at frames {:?}",
            e.frames
        );
    }
    assert!(rec.preset.is_some() && rec.summary.is_some());

    let thin = dir.path().join("thin.rrd");
    record_to(
        &thin,
        "hanging_sheet",
        &["telemetry.level=\"summary\"", "telemetry.log_every=3"],
        10,
        |_| {},
    );
    let rec = read::read(&thin).unwrap();
    let frames: Vec<i64> = rec.frames(paths::PARTICLES);
    assert_eq!(frames, vec![0, 3, 6, 9]);
    assert_eq!(rec.frames(paths::STRAIN), vec![3, 6, 9]);
    // Summary level has no normals, mesh positions or corrections.
    assert!(!rec.entities.contains_key(paths::NORMALS));
    assert!(
        !rec.entities
            .contains_key(&paths::correction(Family::Stretch, "dx"))
    );
}

/// The viewer shows each entity's latest data, so what level full drew is
/// blanked once when a frame stops drawing it (a switch to summary, a
/// family switched off), rather than left standing while the cloth moves
/// on; and drawn again when full comes back.
#[test]
fn what_a_frame_no_longer_draws_is_blanked_once() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("switch.rrd");
    let set = |run: &mut Run, change: &dyn Fn(&mut TelemetrySettings)| {
        let mut t = *run.telemetry.settings();
        change(&mut t);
        run.telemetry.set_settings(t);
    };
    record_to(
        &path,
        "hanging_sheet",
        &["telemetry.level=\"full\""],
        10,
        |run| match run.scene.frame() + 1 {
            6 => set(run, &|t| t.level = Level::Summary),
            9 => set(run, &|t| t.level = Level::Full),
            _ => {}
        },
    );
    let rec = read::read(&path).unwrap();
    let stretch = paths::correction(Family::Stretch, "dx");
    let drawn = |rec: &read::Recording, entity: &str| -> Vec<bool> {
        rec.entities[entity]
            .lengths
            .iter()
            .map(|n| *n > 0)
            .collect()
    };
    for entity in [paths::MESH, paths::NORMALS, stretch.as_str()] {
        // Frame 0 has no corrections yet: nothing to draw or blank.
        let frames = if entity == stretch {
            vec![1, 2, 3, 4, 5, 6, 9, 10]
        } else {
            vec![0, 1, 2, 3, 4, 5, 6, 9, 10]
        };
        assert_eq!(rec.frames(entity), frames, "{entity}");
        let mut expected = vec![true; frames.len()];
        expected[frames.len() - 3] = false;
        assert_eq!(drawn(&rec, entity), expected, "{entity}");
    }
    // The points go on at every frame.
    assert_eq!(rec.frames(paths::PARTICLES), (0..=10).collect::<Vec<_>>());

    // A family switched off blanks its arrows once, and logs nothing after.
    let path = dir.path().join("family.rrd");
    record_to(
        &path,
        "hanging_sheet",
        &["telemetry.level=\"full\""],
        6,
        |run| {
            if run.scene.frame() + 1 == 4 {
                set(run, &|t| t.corrections[Family::Stretch] = false);
            }
        },
    );
    let rec = read::read(&path).unwrap();
    assert_eq!(rec.frames(&stretch), vec![1, 2, 3, 4]);
    assert_eq!(drawn(&rec, &stretch), vec![true, true, true, false]);
}

/// At level summary the scene around the cloth moves with it, so the
/// viewer's camera (which frames what is drawn at the current frame)
/// follows the car down the road: a moving body's pose and the road's patch
/// (four corners, its triangles static) are logged at every frame.
#[test]
fn summary_frames_carry_the_bodies_and_the_ground_under_the_cloth() {
    let frames = 8;
    let rec = summary_of("flag_on_car", frames);
    let every: Vec<i64> = (0..=frames as i64).collect();
    assert_eq!(rec.frames(&paths::body("car")), every);
    // flag_on_car's colliders: the car's box (0), then the road (1).
    let road = &rec.entities[&paths::world_collider(1)];
    assert_eq!(road.frames.iter().copied().collect::<Vec<_>>(), every);
    assert!(road.is_static, "the road's triangles are static");
    assert!(road.lengths.iter().all(|l| *l == 4), "{:?}", road.lengths);
    // The car's box is static, in the car's frame.
    assert!(rec.entities[&paths::body_collider("car", 0)].is_static);

    // A body that does not move has its pose logged once.
    let rec = summary_of("hanging_sheet", frames);
    assert_eq!(rec.frames(&paths::body("rail")), vec![0]);
}

/// With `log_every = N`, only the steps that produce a logged frame track
/// every particle's corrections (they cost the step time), and what a logged
/// frame holds is the same bit for bit as with every frame logged.
#[test]
fn log_every_tracks_corrections_only_for_the_frames_it_logs() {
    // Into memory: a disabled stream logs no frame at all.
    let start = |every: &str| {
        let overrides = ["telemetry.level=\"full\"", every];
        let (rec, _storage) = rerun::RecordingStreamBuilder::new("weft-test")
            .memory()
            .unwrap();
        start_run("windy_flag", &overrides, rec)
    };
    let (mut all, mut thin) = (
        start("telemetry.log_every=1"),
        start("telemetry.log_every=3"),
    );
    let bits = |v: &[glam::Vec3]| -> Vec<[u32; 3]> {
        v.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
    };
    let mut moved = false;
    for frame in 1..=9u64 {
        all.step().unwrap();
        thin.step().unwrap();
        let (a, b) = (
            all.scene.solver().diagnostics().unwrap(),
            thin.scene.solver().diagnostics().unwrap(),
        );
        assert!(a.corrections);
        assert_eq!(b.corrections, frame % 3 == 0, "frame {frame}");
        assert_eq!(
            bits(&all.scene.solver().state().position),
            bits(&thin.scene.solver().state().position),
            "frame {frame}"
        );
        if frame % 3 == 0 {
            for f in Family::ALL {
                let (fa, fb) = (a.family(f), b.family(f));
                assert_eq!(bits(&fa.dx), bits(&fb.dx), "{f:?} δx, frame {frame}");
                assert_eq!(
                    bits(&fa.dtheta),
                    bits(&fb.dtheta),
                    "{f:?} δθ, frame {frame}"
                );
                assert_eq!(fa.max_rotation.to_bits(), fb.max_rotation.to_bits());
                moved |= fa.dx.iter().any(|v| *v != glam::Vec3::ZERO);
            }
        }
    }
    assert!(moved, "the flag's families move it");
}

/// Without an output nothing is logged (nor tracked for logging), and Rerun
/// has nothing to warn about: the report and the note alone.
#[test]
fn a_run_without_an_output_logs_nothing_and_says_so() {
    let out = weft()
        .args(["record", "windy_flag", "--frames", "5", "--level", "full"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("the telemetry is not kept"), "{err}");
    assert!(!err.contains("WARN"), "{err}");
    assert!(out.stdout.is_empty());

    let mut run = start_run(
        "windy_flag",
        &["telemetry.level=\"full\""],
        rerun::RecordingStream::disabled(),
    );
    run.step().unwrap();
    let d = run.scene.solver().diagnostics().unwrap();
    assert!(
        !d.corrections,
        "corrections tracked for a stream that keeps nothing"
    );
    assert!(
        d.max_strain > 0.0,
        "the figures are measured for the verdict"
    );
}

#[test]
fn failing_expectation_exits_non_zero_and_names_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let summary = dir.path().join("s.json");
    let out = weft()
        .args([
            "record",
            "hanging_sheet",
            "--frames",
            "5",
            "--level",
            "off",
            "--set",
            "expect.max_strain=1e-9",
            "--summary",
        ])
        .arg(&summary)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("expect.max_strain") && stderr.contains("FAIL"),
        "{stderr}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    let check = json["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["bound"] == "expect.max_strain")
        .unwrap();
    assert_eq!(check["ok"], false);
    assert!(json["figures"]["steps_per_second"].as_f64().unwrap() > 0.0);

    // The same run within its bounds passes.
    let ok = weft()
        .args(["record", "windy_flag", "--frames", "5", "--level", "off"])
        .output()
        .unwrap();
    assert_eq!(
        ok.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
}

#[test]
fn ctrl_c_closes_the_file_with_every_frame_logged() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.rrd");
    let mut child = weft()
        .args([
            "record",
            "hanging_sheet",
            "--frames",
            "1000000",
            "--level",
            "summary",
            "--save",
        ])
        .arg(&path)
        .spawn()
        .unwrap();
    // Wait until frames are being written, then interrupt.
    let grown = || std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0) >= 200_000;
    let code = common::interrupt_when(&mut child, "the recording never grew", grown);
    assert_eq!(code, Some(130));

    let rec = read::read(&path).unwrap();
    let summary: toml::Table = rec
        .summary
        .as_deref()
        .expect("summary written on Ctrl-C")
        .parse()
        .unwrap();
    assert_eq!(summary["interrupted"].as_bool(), Some(true));
    let stepped = summary["frames"].as_integer().unwrap();
    assert!(stepped > 0);
    let frames: Vec<i64> = rec.frames(paths::PARTICLES);
    assert_eq!(
        frames,
        (0..=stepped).collect::<Vec<_>>(),
        "every frame up to the interruption"
    );
}

#[test]
fn solver_failure_is_logged_at_its_frame_and_the_file_closed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fail.rrd");
    let rec = rerun::RecordingStreamBuilder::new("weft-test")
        .save(&path)
        .unwrap();
    let mut run = start_run("hanging_sheet", &["telemetry.level=\"summary\""], rec);
    run.run(3, &AtomicBool::new(false), |_| {}).unwrap();
    // Poison one free particle: its next update is not finite.
    run.scene.solver_mut().state_mut().prev_position[40].x = f32::NAN;
    let err = run.step().unwrap_err().to_string();
    assert!(err.contains("frame 4") && err.contains("particle"), "{err}");
    let figures = run.finish().unwrap();
    assert!(!figures.finite && figures.failure.is_some());

    let rec = read::read(&path).unwrap();
    let failure = rec
        .events
        .iter()
        .find(|(_, m)| m.contains("non-finite"))
        .expect("failure event");
    assert_eq!(failure.0, 4);
    assert!(failure.1.contains("particle 40"), "{}", failure.1);
    let frames: Vec<i64> = rec.frames(paths::PARTICLES);
    assert_eq!(frames, vec![0, 1, 2, 3]);
}

#[test]
fn replay_reproduces_the_final_state_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("tuned.rrd");
    let figures = record_to(
        &path,
        "windy_flag",
        &["telemetry.level=\"summary\""],
        30,
        |run| {
            let frame = run.scene.frame();
            let mut p = *run.scene.solver().params();
            if frame == 10 {
                p.weights[Family::Curvature] = 0.4;
            }
            if frame == 20 {
                p.iterations = 6;
                p.damping = 0.95;
            }
            run.set_params(p).unwrap();
        },
    );
    let replayed = weft::replay::replay(&path).unwrap();
    assert_eq!(replayed.frames, 30);
    assert_eq!(replayed.changes, 2);
    assert_eq!(replayed.digest, figures.final_state);
    assert_eq!(replayed.positions_match, Some(true));
    assert!(replayed.reproduced());
    assert_eq!(replayed.solver_revision, Some(weft::solver::REVISION));
    assert_eq!(replayed.why_not(), None);

    // The changes matter: without them the run ends elsewhere.
    let plain = record_to(
        &dir.path().join("plain.rrd"),
        "windy_flag",
        &["telemetry.level=\"off\""],
        30,
        |_| {},
    );
    assert_ne!(plain.final_state, figures.final_state);

    // And the command line agrees.
    let out = weft().arg("replay").arg(&path).output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("reproduced bit for bit"));
}

#[test]
fn bad_outputs_fail_before_simulating_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let summary = dir.path().join("s.json");
    let out = weft()
        .args([
            "record",
            "flag_on_car",
            "--save",
            "/nonexistent-dir/x.rrd",
            "--summary",
        ])
        .arg(&summary)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot write the recording to /nonexistent-dir/x.rrd"),
        "{stderr}"
    );
    assert!(!summary.exists(), "nothing was simulated");

    let out = weft()
        .args([
            "record",
            "hanging_sheet",
            "--frames",
            "2",
            "--connect",
            "rerun+http://127.0.0.1:9/proxy",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("could not reach a Rerun viewer at rerun+http://127.0.0.1:9/proxy"),
        "{stderr}"
    );
}

#[test]
fn each_recording_in_a_file_is_read_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.rrd"), dir.path().join("b.rrd"));
    record_to(
        &a,
        "hanging_sheet",
        &["telemetry.level=\"summary\""],
        3,
        |_| {},
    );
    record_to(
        &b,
        "hanging_sheet",
        &[
            "telemetry.level=\"summary\"",
            "solver.weights.curvature=0.35",
        ],
        5,
        |_| {},
    );
    let (one, two) = (read::read(&a).unwrap(), read::read(&b).unwrap());
    assert!(!one.truncated && !two.truncated);
    assert_ne!(one.id, two.id, "every run has its own recording id");

    // Two runs in one file (as `cat a.rrd b.rrd` makes) stay two runs.
    let both = dir.path().join("both.rrd");
    let mut bytes = std::fs::read(&a).unwrap();
    bytes.extend(std::fs::read(&b).unwrap());
    std::fs::write(&both, &bytes).unwrap();
    let all = read::read_all(&both).unwrap();
    assert_eq!(all.len(), 2);
    assert_eq!(
        (all[0].id.as_str(), all[1].id.as_str()),
        (one.id.as_str(), two.id.as_str())
    );
    assert_eq!(
        all[0].frames(paths::PARTICLES),
        one.frames(paths::PARTICLES)
    );
    assert_eq!(
        all[1].frames(paths::PARTICLES),
        (0..=5).collect::<Vec<i64>>()
    );
    assert_eq!(all[1].params, two.params);
    assert_eq!(all[1].last_positions, two.last_positions);
    let e = read::read(&both).unwrap_err();
    assert!(e.to_string().contains("holds 2 recordings"), "{e}");

    // A file cut short says so, and keeps what it holds.
    let cut = dir.path().join("cut.rrd");
    let len = std::fs::read(&b).unwrap().len();
    std::fs::write(&cut, &std::fs::read(&b).unwrap()[..len * 3 / 4]).unwrap();
    let partial = read::read(&cut).unwrap();
    assert!(partial.truncated);
    assert!(partial.preset.is_some());
    let frames = partial.frames(paths::PARTICLES);
    assert!(
        two.frames(paths::PARTICLES).starts_with(&frames),
        "{frames:?}"
    );
}

#[test]
fn the_avx2_and_the_baseline_kernels_give_the_same_bits() {
    // Where the processor has no AVX2 both runs take the baseline kernels
    // and this checks nothing more than determinism.
    let dir = tempfile::tempdir().unwrap();
    let final_state = |preset: &str, extra: &[&str], simd: Option<&str>| {
        let summary = dir
            .path()
            .join(format!("{preset}-{}.json", simd.unwrap_or("any")));
        let mut cmd = weft();
        cmd.args(["record", preset, "--frames", "40", "--level", "summary"])
            .args(extra)
            .arg("--summary")
            .arg(&summary);
        if let Some(v) = simd {
            cmd.env("WEFT_SIMD", v);
        }
        // The verdicts do not matter here (a 64 × 64 sheet strains more
        // than the preset's bound): only the final state does.
        let out = cmd.output().unwrap();
        let text = std::fs::read_to_string(&summary)
            .unwrap_or_else(|_| panic!("{}", String::from_utf8_lossy(&out.stderr)));
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        json["figures"]["final_state"].as_str().unwrap().to_string()
    };
    // A violent jerk (steep angles, Eq. 3 cutting turns) and a sheet big
    // enough for both threads.
    let big = ["--set", "cloth.weft=64", "--set", "cloth.warp=64"];
    for (preset, extra) in [("stress_jerk", &[][..]), ("hanging_sheet", &big[..])] {
        assert_eq!(
            final_state(preset, extra, None),
            final_state(preset, extra, Some("baseline")),
            "{preset}"
        );
    }
}

/// A cloth that passes through itself is shown whatever self-collision's
/// weight: at level summary the crossings are plotted at every frame,
/// marked in the 3D view where they are, counted in the figures, and an
/// `[expect] max_crossings` bound fails the run.
#[test]
fn crossings_are_measured_and_drawn_with_self_collision_off() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("windy_flag.rrd");
    let overrides = ["telemetry.level=\"summary\"", "solver.weights.self=0"];
    let frames = 360;
    let figures = record_to(&path, "windy_flag", &overrides, frames, |_| {});
    let rec = read::read(&path).unwrap();
    let counts = &rec.scalars[paths::SELF_CROSSINGS];
    assert_eq!(counts.len(), frames as usize, "one count per frame");
    let most = counts.iter().map(|s| s.value).fold(0.0, f64::max);
    assert!(
        most > 0.0,
        "the flag never crossed itself in {frames} frames"
    );
    assert_eq!(figures.max_crossings as f64, most);
    let frames_crossing = counts.iter().filter(|s| s.value > 0.0).count() as u64;
    assert_eq!(figures.crossing_frames, frames_crossing);
    let marked = rec.frames(paths::CROSSINGS);
    let crossing = counts.iter().filter(|s| s.value > 0.0).map(|s| s.frame);
    for frame in crossing {
        assert!(marked.contains(&frame), "frame {frame} crosses, unmarked");
    }
    let loaded = load::load("windy_flag", &sets(&["expect.max_crossings=0"])).unwrap();
    let checks = weft::record::verdict(loaded.preset.expect.as_ref(), &figures);
    let check = checks.iter().find(|c| c.bound == "expect.max_crossings");
    assert!(check.is_some_and(|c| !c.ok), "{checks:?}");
}

#[test]
fn a_bad_crossing_bound_is_refused_with_its_range() {
    for (set, says) in [
        ("expect.max_crossings=-1", "allowed"),
        ("expect.max_crossings=1.5", "whole number"),
    ] {
        let err = load::load("windy_flag", &sets(&[set]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("expect.max_crossings"), "{set}: {err}");
        assert!(err.contains(says), "{set}: {err}");
    }
}

/// A recording opens with weft's layout as its default, the plots without
/// legends (Rerun's builder cannot hide them; the layout is sent as
/// messages), six of them: the crossing count has a plot of its own.
#[test]
fn a_recording_carries_its_layout() {
    use rerun::external::re_log_encoding::DecoderApp;
    use rerun::log::LogMsg;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("r.rrd");
    let out = weft()
        .args(["record", "hanging_sheet", "--frames", "2", "--save"])
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let reader = std::io::BufReader::new(std::fs::File::open(&file).unwrap());
    let mut legends = 0;
    let mut activation = None;
    for msg in DecoderApp::decode_eager(reader).unwrap() {
        match msg.unwrap() {
            LogMsg::ArrowMsg(id, arrow) if id.is_blueprint() => {
                let chunk = rerun::log::Chunk::from_arrow_msg(&arrow).unwrap();
                legends += chunk.entity_path().to_string().ends_with("/PlotLegend") as usize;
            }
            LogMsg::BlueprintActivationCommand(cmd) => activation = Some(cmd),
            _ => {}
        }
    }
    assert_eq!(legends, 6, "one legend setting per plot");
    let activation = activation.expect("the layout is activated");
    assert!(activation.make_default && !activation.make_active);
}

/// The solver's results at [`weft::solver::REVISION`]: a shipped preset with
/// self-collision on, and a pulled sheet folding over itself. A change that
/// moves either must raise the revision (and pin these again), so that
/// `weft replay` can tell a recording made by another solver from a fault.
#[test]
fn the_solver_revision_names_its_results() {
    let pinned = (2, "11f9c09d625edd9a", "4e75395cb6629b15");
    let preset = load::load("windy_flag", &[]).unwrap().preset;
    let mut scene = Scene::new(&preset).unwrap();
    for _ in 0..60 {
        scene.step().unwrap();
    }
    let flag = format!("{:016x}", scene.solver().state().digest());
    let spec = weft::solver::ClothSpec {
        weft: 8,
        warp: 8,
        imperfection: 0.01,
        ..weft::solver::ClothSpec::default()
    };
    let mut sheet = weft::solver::Solver::new(spec, weft::solver::Params::default(), &[]).unwrap();
    let corner = sheet.state().position[7].as_dvec3();
    let pull = weft::solver::Pull {
        particle: 7,
        target: corner + glam::DVec3::new(0.0, 0.8, 0.1),
        stiffness: 20.0,
    };
    sheet.set_pull(Some(pull)).unwrap();
    for _ in 0..30 {
        sheet.step(&common::calm(), &[]).unwrap();
    }
    let folded = format!("{:016x}", sheet.state().digest());
    assert_eq!(
        (weft::solver::REVISION, flag.as_str(), folded.as_str()),
        pinned,
        "the results changed: raise weft::solver::REVISION and pin the new digests"
    );
}
