//! The tuning panel driven with egui_kittest: transport, sliders reaching
//! the solver and the recording, validation messages, saving presets, and an
//! off-screen snapshot (wgpu; lavapipe on CI).
#![cfg(feature = "viewer")]

use std::time::Duration;

use egui_kittest::{Harness, kittest::NodeT, kittest::Queryable};
use weft::app::{
    panel::Panel,
    session::{BranchAt, Command, Session},
};
use weft::scene::load;
use weft::solver::Family;
use weft::telemetry::{paths, read};

mod common;
use common::panel::{State, WAIT, harness, logged_frames, set_slider, state_with};

fn state(preset: &str) -> State {
    state_with(preset, &[])
}

fn click(h: &mut Harness<'_, State>, label: &str) {
    h.get_by_label(label).click();
    h.run();
}

#[test]
fn play_pause_and_step_drive_the_simulation() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    assert_eq!(h.state().session.status().frame, 0);

    click(&mut h, "Step");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 1));

    click(&mut h, "Play");
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.playing && s.frame > 5)
    );
    h.run();
    click(&mut h, "Pause");
    assert!(h.state().session.wait_for(WAIT, |s| !s.playing));
    let paused = h.state().session.status().frame;
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        h.state().session.status().frame,
        paused,
        "paused, yet stepping"
    );

    h.run();
    click(&mut h, "Step");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == paused + 1));

    click(&mut h, "Reset");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 0));
}

#[test]
fn a_slider_changes_the_solver_and_the_recording() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("session.rrd");
    let mut s = state("hanging_sheet");
    s.panel.set_record_path(file.to_str().unwrap());
    let mut h = harness(s);
    h.run();

    click(&mut h, "Record");
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_some()));
    click(&mut h, "Step");
    click(&mut h, "Step");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 2));

    set_slider(&mut h, "λ curvature", 0.35);
    click(&mut h, "Step");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 3));
    let status = h.state().session.status();
    assert_eq!(
        status.preset.unwrap().solver.weights[Family::Curvature],
        0.35
    );

    h.run();
    click(&mut h, "Stop recording");
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_none()));

    let rec = read::read(&file).unwrap();
    // The change is logged at frame 3, the first step that used it.
    let change = rec
        .params
        .iter()
        .find(|(_, t)| t.contains("curvature = 0.35"))
        .unwrap_or_else(|| {
            panic!(
                "change not recorded: {:?} {:?}",
                rec.params,
                rec.entities.keys().collect::<Vec<_>>()
            )
        });
    assert_eq!(change.0, 3);
    assert!(
        rec.events
            .iter()
            .any(|(f, m)| *f == 3 && m.contains("solver.weights.curvature 0.1 → 0.35")),
        "{:?}",
        rec.events
    );
    assert!(rec.preset.is_some(), "the file starts with the static data");
    let frames: Vec<i64> = rec.frames(paths::PARTICLES);
    assert_eq!(
        frames,
        vec![0, 1, 2, 3],
        "a recording starts the scene over"
    );
    // The session replays bit for bit, tuning change included.
    let replayed = weft::replay::replay(&file).unwrap();
    assert_eq!((replayed.frames, replayed.changes), (3, 1));
    assert!(replayed.reproduced(), "{replayed:?}");
}

#[test]
fn a_rejected_value_shows_its_message_and_changes_nothing() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    set_slider(&mut h, "λ curvature", 1.5);
    h.get_by_label_contains("solver.weights.curvature");
    h.get_by_label_contains("out of range");
    let status = h.state().session.status();
    assert_eq!(
        status.preset.unwrap().solver.weights[Family::Curvature],
        0.1
    );

    // The free-form field validates like --set, suggesting the nearest key.
    let field = h
        .query_all_by_role(egui::accesskit::Role::TextInput)
        .find(|n| n.value().unwrap_or_default().is_empty())
        .expect("the empty key=value field");
    field.focus();
    field.type_text("solver.weights.curvatre=0.3");
    h.run();
    click(&mut h, "Apply");
    let message = h.get_by_label_contains("did you mean `curvature`");
    // Said once, without the `--set` of the command line.
    let text = message.value().unwrap_or_default();
    assert!(!text.contains("--set"), "{text}");
    assert_eq!(text.matches("solver.weights.curvatre").count(), 1, "{text}");
    // Out of range: the key once too.
    let preset = load::load("hanging_sheet", &[]).unwrap().preset;
    let e = load::with_overrides(&preset, &["solver.weights.curvature=1.5".parse().unwrap()])
        .unwrap_err();
    let text = weft::app::panel::error_text(&e);
    assert!(!text.contains("--set"), "{text}");
    assert_eq!(
        text.matches("solver.weights.curvature").count(),
        1,
        "{text}"
    );
    assert!(text.contains("out of range"), "{text}");
    assert_eq!(
        h.state().session.status().preset.unwrap().solver.weights[Family::Curvature],
        0.1
    );
}

#[test]
fn saving_a_preset_loads_back_identically() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tuned.toml");
    let mut s = state("windy_flag");
    s.panel.set_save_path(path.to_str().unwrap());
    let mut h = harness(s);
    h.run();
    set_slider(&mut h, "λ normality", 0.45);
    set_slider(&mut h, "iterations", 7.0);
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.preset.as_ref().unwrap().solver.iterations == 7)
    );
    click(&mut h, "Save preset");
    h.get_by_label_contains("saved");
    let saved = load::load(path.to_str().unwrap(), &[]).unwrap().preset;
    let live = h.state().session.status().preset.unwrap();
    assert_eq!(saved, live);
    assert_eq!(saved.solver.weights[Family::Normality], 0.45);
    assert_eq!(saved.solver.iterations, 7);
}

#[test]
fn panel_snapshot() {
    let mut h = Harness::builder()
        .with_size([360.0, 1400.0])
        .wgpu()
        .build_ui_state(
            |ui, s: &mut State| s.panel.ui(ui, &s.session),
            state("flag_on_car"),
        );
    h.run();
    h.snapshot("panel");
}

/// A session opened at level `summary` and switched to `full` from the
/// panel draws the corrections once its arrows are turned on (they start
/// off in the window): the app keeps every particle's corrections whatever
/// level it starts at.
#[test]
fn switching_to_level_full_draws_the_corrections() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("session.rrd");
    let overrides = ["telemetry.level=summary".parse().unwrap()];
    let loaded = load::load("hanging_sheet", &overrides).unwrap();
    let mut full = loaded.preset.telemetry;
    full.level = weft::scene::preset::Level::Full;
    let session = Session::start(loaded, "hanging_sheet".into(), |_| {}).unwrap();
    session.send(Command::StartRecording(file.clone()));
    assert!(session.wait_for(WAIT, |s| s.recording.is_some()));
    session.send(Command::Telemetry(full));
    // The window starts with the arrows off: frame 1 draws none.
    session.send(Command::Step);
    assert!(session.wait_for(WAIT, |s| s.frame == 1));
    session.send(Command::Arrows(true));
    for frame in 2..=3 {
        session.send(Command::Step);
        assert!(session.wait_for(WAIT, |s| s.frame == frame));
    }
    session.send(Command::StopRecording);
    assert!(session.wait_for(WAIT, |s| s.recording.is_none()));

    let rec = read::read(&file).unwrap();
    let path = paths::correction(weft::solver::Family::Stretch, "dx");
    let arrows = &rec.entities[&path].lengths;
    assert!(
        arrows.last().is_some_and(|&n| n > 0),
        "no stretch corrections drawn after switching to full: {arrows:?}"
    );
}

/// Every start (open, Reset, Record, Branch) is a new Rerun recording with
/// its own id, a readable name and properties; a session file holds
/// exactly one run, with weft's blueprint, and replays bit for bit.
#[test]
fn each_run_is_its_own_recording() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("session.rrd");
    let seen = std::sync::Arc::new(std::sync::Mutex::new(std::collections::BTreeSet::new()));
    let sink = seen.clone();
    let overrides = ["solver.weights.curvature=0.35".parse().unwrap()];
    let loaded = load::load("hanging_sheet", &overrides).unwrap();
    let session = Session::start(
        loaded,
        "hanging_sheet".into(),
        move |msg: &rerun::log::LogMsg| {
            let id = msg.store_id();
            if id.is_recording() {
                sink.lock().unwrap().insert(id.recording_id().to_string());
            }
        },
    )
    .unwrap();
    let first = session.status().run;
    assert_eq!(first.number, 1);
    assert_eq!(first.name, "#1 hanging_sheet · curvature 0.1→0.35");
    session.send(Command::Step);
    assert!(session.wait_for(WAIT, |s| s.frame == 1));
    session.send(Command::Reset);
    assert!(session.wait_for(WAIT, |s| s.run.number == 2 && s.frame == 0));
    session.send(Command::StartRecording(file.clone()));
    assert!(session.wait_for(WAIT, |s| s.recording.is_some()));
    let recorded = session.status().run;
    assert_eq!(recorded.number, 3);
    for frame in 1..=3 {
        session.send(Command::Step);
        assert!(session.wait_for(WAIT, |s| s.frame == frame));
    }
    // A reset while recording ends the file: it holds one run.
    session.send(Command::Reset);
    assert!(session.wait_for(WAIT, |s| s.run.number == 4 && s.recording.is_none()));
    let status = session.status();
    let ids: Vec<&str> = status
        .runs
        .iter()
        .map(|r| r.recording_id.as_str())
        .collect();
    assert_eq!(ids.len(), 4);
    assert_eq!(
        ids.iter().collect::<std::collections::BTreeSet<_>>().len(),
        4,
        "each run has its own recording id: {ids:?}"
    );
    drop(session);
    // The viewer got all four recordings.
    assert_eq!(seen.lock().unwrap().len(), 4);

    let all = read::read_all(&file).unwrap();
    assert_eq!(all.len(), 1, "one run per file");
    let rec = all.into_iter().next().unwrap();
    assert_eq!(rec.id, recorded.recording_id);
    assert!(!rec.truncated);
    assert!(rec.blueprint, "the file carries weft's blueprint");
    assert_eq!(rec.frames(paths::PARTICLES), vec![0, 1, 2, 3]);
    let prop = |k: &str| rec.properties.get(k).cloned().unwrap_or_default();
    assert_eq!(
        prop("__properties:RecordingInfo:name"),
        recorded.name,
        "{:?}",
        rec.properties
    );
    assert_eq!(prop("__properties/weft:preset"), "hanging_sheet");
    assert_eq!(prop("__properties/weft:version"), weft::solver::version());
    assert_eq!(prop("__properties/weft:changes"), "curvature 0.1→0.35");
    assert_eq!(prop("__properties/result:frames"), "3");
    assert_eq!(prop("__properties/result:verdict"), "ok");
    let replayed = weft::replay::replay(&file).unwrap();
    assert!(replayed.reproduced(), "{replayed:?}");
    assert_eq!(
        prop("__properties/result:final_state"),
        replayed.digest,
        "{:?}",
        rec.properties
    );
}

/// Branching resumes from the nearest checkpoint and steps silently to the
/// frame: bit-identical to the parent there, and after it as long as the
/// tuning is the same; a new recording names its parent and frame.
#[test]
fn a_branch_is_bit_identical_up_to_its_frame() {
    let loaded = load::load("hanging_sheet", &[]).unwrap();
    let session = Session::start(loaded, "hanging_sheet".into(), |_| {}).unwrap();
    let step_to = |frame: u64| common::panel::step_to(&session, frame);
    let at_45 = step_to(45);
    let tuning =
        |s: &weft::app::session::Status| weft::scene::Tuning::of(s.preset.as_ref().unwrap());
    // A change at frame 50 is part of the parent's story, replayed too.
    step_to(49);
    let mut t = tuning(&session.status());
    t.solver.weights[Family::Normality] = 0.4;
    session.send(Command::Tune(t));
    let at_55 = step_to(55);
    let at_100 = step_to(100);
    let parent = session.status().run;
    assert_eq!(session.status().checkpoints, (4, 30));

    // From checkpoint 30 through the change at 50 to 55.
    session.send(Command::Branch(BranchAt::Frame(55)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    let s = session.status();
    assert_eq!((s.frame, &s.digest), (55, &at_55), "the state at frame 55");
    assert_eq!(
        s.run.parent,
        Some((1, parent.recording_id.clone(), 55)),
        "{:?}",
        s.run
    );
    assert!(
        s.run.name.ends_with("branch of #1 at frame 55"),
        "{}",
        s.run.name
    );
    assert_eq!(step_to(100), at_100, "the same tuning gives the same run");

    // A branch of the branch, before the tuning change.
    session.send(Command::Branch(BranchAt::Frame(45)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 3 && s.frame == 45));
    assert_eq!(session.status().digest, at_45);

    // Higher curvature from frame 60: a different run after it.
    step_to(60);
    let mut t = tuning(&session.status());
    t.solver.weights[Family::Curvature] = 0.35;
    session.send(Command::Tune(t));
    session.send(Command::Branch(BranchAt::Frame(60)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 4 && s.frame == 60));
    assert!(
        session.status().run.name.contains("curvature 0.1→0.35"),
        "{}",
        session.status().run.name
    );
    assert_ne!(step_to(100), at_100);

    // Past the run's last frame: refused, with the reason.
    session.send(Command::Branch(BranchAt::Frame(5000)));
    assert!(session.wait_for(WAIT, |s| {
        s.error
            .as_deref()
            .is_some_and(|e| e.contains("cannot branch at frame 5000"))
    }));
    assert_eq!(session.status().run.number, 4);
}

/// Checkpoints stay bounded however long the run: at most `MAX`, the
/// interval doubling, and any frame reachable.
#[test]
fn checkpoints_are_bounded() {
    use weft::app::history::{EVERY, History, MAX};
    let overrides = [
        "cloth.weft=4".parse().unwrap(),
        "cloth.warp=4".parse().unwrap(),
    ];
    let loaded = load::load("hanging_sheet", &overrides).unwrap();
    let scene = weft::scene::Scene::new(&loaded.preset).unwrap();
    let telemetry = weft::telemetry::Telemetry::new(
        rerun::RecordingStream::disabled(),
        loaded.preset.telemetry,
    );
    let mut run = weft::record::Run::start(scene, telemetry, "x", &loaded.resolved).unwrap();
    let mut history = History::new(run.snapshot(), run.scene.tuning());
    let frames = EVERY * MAX as u64 * 3;
    let mut digests = vec![run.scene.solver().state().digest()];
    for frame in 1..=frames {
        run.step().unwrap();
        history.stepped(frame, run.scene.time(), || run.snapshot());
        digests.push(run.scene.solver().state().digest());
        assert!(history.checkpoints().0 <= MAX);
    }
    let (count, every) = history.checkpoints();
    assert_eq!(every, EVERY * 4);
    assert!(count > MAX / 2, "{count}");
    for frame in [0, 1, 59, 777, frames - 1, frames] {
        let s = history.state_at(frame).unwrap();
        assert_eq!(s.scene.frame(), frame);
        assert_eq!(s.scene.solver().state().digest(), digests[frame as usize]);
    }
    assert_eq!(history.frame_at(run.scene.time()), frames);
}

fn press(h: &mut Harness<'_, State>, key: egui::Key) {
    h.key_press(key);
    h.run();
}

/// F6 play/pause, F7 step, F8 branch, F9 reset; the buttons' tooltips say so.
#[test]
fn shortcuts_drive_the_simulation() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    press(&mut h, egui::Key::F7);
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 1));
    press(&mut h, egui::Key::F6);
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.playing && s.frame > 3)
    );
    h.run();
    press(&mut h, egui::Key::F6);
    assert!(h.state().session.wait_for(WAIT, |s| !s.playing));
    press(&mut h, egui::Key::F8);
    assert!(h.state().session.wait_for(WAIT, |s| s.run.number == 2));
    press(&mut h, egui::Key::F9);
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 3 && s.frame == 0)
    );
    h.run();
    h.get_by_label("Step").hover();
    h.run();
    h.get_by_label_contains("(F7 or Right arrow)");
}

/// The viewer's time cursor on the current run is the branch point.
#[test]
fn the_viewer_time_cursor_picks_the_branch_frame() {
    let s = state("hanging_sheet");
    let link = s.panel.link();
    let mut h = harness(s);
    h.run();
    for _ in 0..30 {
        h.state().session.send(Command::Step);
    }
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 30));
    h.run();
    let id = h.state().session.status().run.recording_id;
    let dt = h.state().session.status().preset.unwrap().solver.dt as f64;
    // The viewer reports sim_time in nanoseconds.
    link.lock().unwrap().time(id, 12.0 * dt * 1e9);
    h.run();
    click(&mut h, "Branch");
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 2 && s.frame == 12),
        "{:?}",
        h.state().session.status().frame
    );
}

/// At level summary the session has the solver track every particle's
/// corrections only while the inspector follows a particle (they cost about
/// an eighth of a step): picked while paused, the particle's δx and δθ read
/// "–" until the next step records them, and a step taken with the inspector
/// off records none.
#[test]
fn the_inspector_asks_for_corrections_only_while_it_follows_a_particle() {
    let mut h = harness(state_with(
        "hanging_sheet",
        &["telemetry.level=\"summary\""],
    ));
    h.run();
    let step_to = |h: &mut Harness<'_, State>, frame: u64| {
        h.state().session.send(Command::Step);
        assert!(h.state().session.wait_for(WAIT, |s| s.frame == frame));
    };
    let inspected = |h: &mut Harness<'_, State>, on: bool| {
        assert!(
            h.state()
                .session
                .wait_for(WAIT, |s| s.particle.is_some() == on)
        );
        h.run();
        h.state().session.status().particle
    };
    step_to(&mut h, 1);
    // The panel's checkbox follows particle 0, the sheet's free bottom-left
    // corner.
    click(&mut h, "inspect particle");
    let p = inspected(&mut h, true).unwrap();
    assert_eq!(p.index, 0);
    assert!(
        !p.corrections,
        "frame 1 was stepped before the particle was picked"
    );
    assert_eq!(h.query_all_by_label("–").count(), 2 * Family::ALL.len());

    step_to(&mut h, 2);
    h.run();
    let p = h.state().session.status().particle.unwrap();
    assert!(p.corrections, "{p:?}");
    assert!(p.dx[Family::Stretch].length() > 0.0, "{p:?}");
    assert!(h.query_all_by_label("–").next().is_none());

    click(&mut h, "inspect particle");
    inspected(&mut h, false);
    step_to(&mut h, 3);
    click(&mut h, "inspect particle");
    let p = inspected(&mut h, true).unwrap();
    assert!(!p.corrections, "frame 3 was stepped with the inspector off");
}

/// Selecting a particle in the 3D view shows its numbers in the panel; the
/// same numbers are logged per particle on the particles entity.
#[test]
fn the_inspector_shows_the_selected_particle() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("session.rrd");
    let s = state("flag_on_car");
    let link = s.panel.link();
    let mut h = harness(s);
    h.run();
    h.state()
        .session
        .send(Command::StartRecording(file.clone()));
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_some()));
    for _ in 0..5 {
        h.state().session.send(Command::Step);
    }
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 5));
    let status = h.state().session.status();
    let weft_n = status.preset.as_ref().unwrap().cloth.weft as usize;
    // The flag's free tip: the last particle of the first row.
    let tip = weft_n - 1;
    link.lock().unwrap().select(status.run.recording_id, tip);
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.particle.as_ref().is_some_and(|p| p.index == tip)
    }));
    h.run();
    let p = h.state().session.status().particle.unwrap();
    assert_eq!(p.cell, (tip as u32, 0));
    assert!(p.dx.iter().any(|(_, d)| d.length() > 0.0), "{p:?}");
    h.get_by_label_contains(&format!("(i, j) = ({tip}, 0)"));
    h.get_by_label("|δx| (mm)");
    h.get_by_label_contains("° off the surface's");
    h.state().session.send(Command::StopRecording);
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_none()));

    let rec = read::read(&file).unwrap();
    let components = &rec.entities[paths::PARTICLES].components;
    for c in [
        "i",
        "j",
        "strain",
        "normal_offset",
        "violation_planarity",
        "dx_curvature",
        "dtheta_normality",
    ] {
        assert!(components.contains(c), "{c} not in {components:?}");
    }
    // Stretch never turns an element: it has no δθ to show.
    assert!(!components.contains("dtheta_stretch"), "{components:?}");
}

/// A click on the cloth's mesh (not on a particle) inspects the particle
/// nearest the clicked point, and the panel's particle field follows.
#[test]
fn a_click_on_the_mesh_inspects_the_nearest_particle() {
    let s = state("flag_on_car");
    let link = s.panel.link();
    let mut h = harness(s);
    h.run();
    let status = h.state().session.status();
    let preset = status.preset.clone().unwrap();
    let weft_n = preset.cloth.weft as usize;
    // At frame 0 the cloth is where the preset places it.
    let scene = weft::scene::Scene::new(&preset).unwrap();
    let x = scene.world_positions();
    // A point on the mesh a third of the way from the free tip (the last
    // particle of the first row) to its neighbour along the row.
    let tip = weft_n - 1;
    let at = x[tip] + (x[tip - 1] - x[tip]) / 3.0;
    link.lock()
        .unwrap()
        .pick(status.run.recording_id.clone(), at.to_array());
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.particle.as_ref().is_some_and(|p| p.index == tip)
    }));
    h.run();
    h.run();
    h.get_by_label_contains(&format!("(i, j) = ({tip}, 0)"));
    // The other neighbour's side picks it.
    let next = tip - 1;
    let at = x[next] + (x[next - 1] - x[next]) / 3.0;
    link.lock()
        .unwrap()
        .pick(status.run.recording_id, at.to_array());
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.particle.as_ref().is_some_and(|p| p.index == next)
    }));
    h.run();
    h.run();
    h.get_by_label_contains(&format!("(i, j) = ({next}, 0)"));
}

/// The panel shows each [expect] bound with the run's value and ok/FAIL,
/// live, and starts over with the run.
#[test]
fn live_verdicts() {
    let mut h = harness(state_with("flag_on_car", &["expect.max_strain=0.0001"]));
    h.run();
    h.get_by_label("max_strain");
    assert!(h.query_all_by_label("FAIL").next().is_none());
    for _ in 0..30 {
        h.state().session.send(Command::Step);
    }
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 30));
    h.run();
    let checks = h.state().session.status().checks;
    let strain = checks
        .iter()
        .find(|c| c.bound == "expect.max_strain")
        .unwrap();
    assert!(!strain.ok && strain.value > 1e-4, "{strain:?}");
    h.get_by_label("FAIL");
    click(&mut h, "Reset");
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 2 && s.checks.iter().all(|c| c.ok))
    );
}

/// "Save preset" writes `extend` plus only what changed, and it loads back
/// identical to the running preset.
#[test]
fn saving_writes_a_small_preset_that_extends_the_shipped_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tuned.toml");
    let mut s = state("flag_on_car");
    s.panel.set_save_path(path.to_str().unwrap());
    let mut h = harness(s);
    h.run();
    set_slider(&mut h, "λ curvature", 0.35);
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.preset.as_ref().unwrap().solver.weights[Family::Curvature] == 0.35
    }));
    click(&mut h, "Save preset");
    h.get_by_label_contains("saved");
    let text = std::fs::read_to_string(&path).unwrap();
    let body: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .collect();
    assert_eq!(
        body,
        vec![
            "extend = \"flag_on_car\"",
            "[solver.weights]",
            "curvature = 0.35"
        ],
        "{text}"
    );
    let saved = load::load(path.to_str().unwrap(), &[]).unwrap().preset;
    assert_eq!(saved, h.state().session.status().preset.unwrap());
}

/// `color_by = "correction.<family>"` colours by that family alone.
#[test]
fn colour_by_one_family() {
    use weft::scene::preset::ColorBy;
    let set = |v: &str| vec![format!("telemetry.color_by={v}").parse().unwrap()];
    let loaded = load::load("flag_on_car", &set("correction.planarity")).unwrap();
    assert_eq!(
        loaded.preset.telemetry.color_by,
        ColorBy::CorrectionOf(Family::Planarity)
    );
    let mut scene = weft::scene::Scene::new(&loaded.preset).unwrap();
    scene.solver_mut().set_diagnostics(true);
    for _ in 0..10 {
        scene.step().unwrap();
    }
    let colours = |by| weft::telemetry::color::particles(by, &scene);
    let all = colours(ColorBy::Correction);
    let families: Vec<_> = [
        Family::Stretch,
        Family::Planarity,
        Family::Normality,
        Family::Curvature,
    ]
    .map(ColorBy::CorrectionOf)
    .into_iter()
    .map(colours)
    .collect();
    for f in &families {
        assert_ne!(f, &all);
    }
    assert_ne!(families[1], families[3]);
    let err = load::load("flag_on_car", &set("correction.twist")).unwrap_err();
    assert!(err.to_string().contains("correction.planarity"), "{err}");
}

/// A branch's plots show its parent's curves beside its own.
#[test]
fn a_branch_draws_its_parent_beside_it() {
    type Rows = std::collections::BTreeMap<(String, String), usize>;
    let rows = std::sync::Arc::new(std::sync::Mutex::new(Rows::new()));
    let sink = rows.clone();
    let loaded = load::load("hanging_sheet", &[]).unwrap();
    let session = Session::start(
        loaded,
        "hanging_sheet".into(),
        move |msg: &rerun::log::LogMsg| {
            if let rerun::log::LogMsg::ArrowMsg(store, arrow) = msg
                && store.is_recording()
            {
                let chunk = rerun::log::Chunk::from_arrow_msg(arrow).unwrap();
                let key = (
                    store.recording_id().to_string(),
                    chunk.entity_path().to_string(),
                );
                *sink.lock().unwrap().entry(key).or_default() += chunk.num_rows();
            }
        },
    )
    .unwrap();
    for _ in 0..10 {
        session.send(Command::Step);
    }
    assert!(session.wait_for(WAIT, |s| s.frame == 10));
    session.send(Command::Branch(BranchAt::Frame(5)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    let branch = session.status().run.recording_id;
    drop(session);
    let rows = rows.lock().unwrap();
    let count = |path: &str| rows.get(&(branch.clone(), path.to_string())).copied();
    // The series style (static) and the parent's ten frames.
    assert_eq!(count("/metrics/strain/parent"), Some(11), "{rows:?}");
    assert_eq!(count("/metrics/violation/curvature/parent"), Some(11));
    assert_eq!(count("/metrics/normals/parent"), Some(11));
}

/// What a session logged of one entity, per recording: each row's frame
/// and 3-vectors (a mesh's vertex positions, or points).
type Logged = std::collections::BTreeMap<String, Vec<(i64, Vec<[f32; 3]>)>>;

/// A session of `preset` that keeps, per recording, the ghost's vertex
/// positions and the particles' positions at each logged frame.
fn session_logging_the_ghost(
    preset: &str,
) -> (Session, std::sync::Arc<std::sync::Mutex<[Logged; 2]>>) {
    let logged = std::sync::Arc::new(std::sync::Mutex::new([Logged::new(), Logged::new()]));
    let sink = logged.clone();
    let loaded = load::load(preset, &[]).unwrap();
    let session = Session::start(loaded, preset.into(), move |msg: &rerun::log::LogMsg| {
        let rerun::log::LogMsg::ArrowMsg(store, arrow) = msg else {
            return;
        };
        let chunk = rerun::log::Chunk::from_arrow_msg(arrow).unwrap();
        let entity = chunk.entity_path().to_string();
        let (k, component) = if entity == format!("/{}", paths::GHOST) {
            (0, rerun::Mesh3D::descriptor_vertex_positions().component)
        } else if entity == format!("/{}", paths::PARTICLES) {
            (1, rerun::Points3D::descriptor_positions().component)
        } else {
            return;
        };
        if chunk.is_static() {
            return;
        }
        let frames = chunk.iter_component_indices(paths::FRAME.into(), component);
        let values = chunk.iter_slices::<[f32; 3]>(component);
        let mut logged = sink.lock().unwrap();
        let rows = logged[k]
            .entry(store.recording_id().to_string())
            .or_default();
        for ((frame, _), x) in frames.zip(values) {
            rows.push((frame.as_i64(), x.to_vec()));
        }
    })
    .unwrap();
    (session, logged)
}

/// A branch draws its parent's cloth, faint, in its 3D view: at every
/// frame it logs, the parent's positions at that frame, where its own
/// cloth, with another curvature weight, has moved elsewhere. The panel's
/// "parent as a ghost" box (on) turns it off (the ghost is cleared at
/// once and no longer drawn) and on again.
#[test]
fn a_branch_draws_its_parent_as_a_ghost() {
    let (session, logged) = session_logging_the_ghost("hanging_sheet");
    for _ in 0..10 {
        session.send(Command::Step);
    }
    assert!(session.wait_for(WAIT, |s| s.frame == 10));
    let parent = session.status().run.recording_id;
    let mut tuning = weft::scene::Tuning::of(session.status().preset.as_ref().unwrap());
    tuning.solver.weights[Family::Curvature] = 0.35;
    session.send(Command::Tune(tuning));
    session.send(Command::Branch(BranchAt::Frame(5)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    for frame in 6..=8 {
        session.send(Command::Step);
        assert!(session.wait_for(WAIT, |s| s.frame == frame));
    }
    let branch = session.status().run.recording_id;
    // The streams send what was logged in batches, every few milliseconds.
    let arrived = |n: usize| {
        session.wait_for(WAIT, |_| {
            let logged = logged.lock().unwrap();
            let last = |k: usize| {
                logged[k]
                    .get(&branch)
                    .and_then(|rows| rows.last().map(|r| r.0))
            };
            logged[0].get(&branch).is_some_and(|rows| rows.len() >= n) && last(1) == Some(8)
        })
    };
    assert!(arrived(4));
    {
        let [ghost, particles] = &*logged.lock().unwrap();
        assert!(!ghost.contains_key(&parent), "the first run has no parent");
        let drawn = &ghost[&branch];
        assert_eq!(
            drawn.iter().map(|(f, _)| *f).collect::<Vec<_>>(),
            vec![5, 6, 7, 8]
        );
        let at = |rows: &[(i64, Vec<[f32; 3]>)], frame: i64| {
            rows.iter().rfind(|(f, _)| *f == frame).unwrap().1.clone()
        };
        for frame in 5..=8 {
            assert_eq!(
                at(drawn, frame),
                at(&particles[&parent], frame),
                "the ghost at frame {frame} is the parent's cloth"
            );
        }
        assert_ne!(
            at(&particles[&branch], 8),
            at(&particles[&parent], 8),
            "the branch's own cloth has moved elsewhere"
        );
    }

    let mut h = harness(State {
        panel: Panel::new(&session.status()),
        session,
    });
    h.run();
    let ghost_rows = |logged: &std::sync::Mutex<[Logged; 2]>| {
        logged.lock().unwrap()[0][&branch]
            .iter()
            .map(|(f, x)| (*f, x.len()))
            .collect::<Vec<_>>()
    };
    let n = ghost_rows(&logged)[0].1;
    assert!(n > 0);
    let checked = |h: &Harness<'_, State>| {
        h.get_by_label("parent as a ghost")
            .accesskit_node()
            .toggled()
            == Some(egui::accesskit::Toggled::True)
    };
    assert!(checked(&h), "on for a branch");
    click(&mut h, "parent as a ghost");
    assert!(!checked(&h));
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |_| ghost_rows(&logged).len() == 5),
        "turned off, the ghost is cleared at once"
    );
    assert_eq!(ghost_rows(&logged)[4], (8, 0));
    click(&mut h, "Step");
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 9));
    assert_eq!(ghost_rows(&logged).len(), 5, "and no longer drawn");
    click(&mut h, "parent as a ghost");
    assert!(checked(&h));
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |_| ghost_rows(&logged).len() == 6),
        "turned on, it is drawn at once"
    );
    assert_eq!(ghost_rows(&logged)[5], (9, n));
}

/// A run that is not a branch has no ghost to draw, and no box for it.
#[test]
fn only_a_branch_offers_the_ghost() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    assert!(h.query_by_label("parent as a ghost").is_none());
}

/// A preset file as the base: named relative to the saved file when they
/// share a directory, else by its absolute path; both load back.
#[test]
fn saving_as_a_diff_of_a_preset_file() {
    use weft::app::preset_diff::as_extension;
    let dir = tempfile::tempdir().unwrap();
    let base_path = dir.path().join("base.toml");
    std::fs::write(
        &base_path,
        "extend = \"hanging_sheet\"\ndescription = \"mine\"\n",
    )
    .unwrap();
    let base_arg = base_path.to_str().unwrap();
    let base = load::load(base_arg, &[]).unwrap().preset;
    let tuned = load::load(base_arg, &["solver.iterations=7".parse().unwrap()])
        .unwrap()
        .preset;
    let near = dir.path().join("tuned.toml");
    let text = as_extension("saved", base_arg, &base, &tuned, &near).unwrap();
    assert!(text.contains("extend = \"base.toml\""), "{text}");
    std::fs::write(&near, &text).unwrap();
    assert_eq!(
        load::load(near.to_str().unwrap(), &[]).unwrap().preset,
        tuned
    );

    let other = tempfile::tempdir().unwrap();
    let far = other.path().join("tuned.toml");
    let text = as_extension("saved", base_arg, &base, &tuned, &far).unwrap();
    let abs = std::fs::canonicalize(&base_path).unwrap();
    assert!(
        text.contains(&format!("extend = \"{}\"", abs.display())),
        "{text}"
    );
    std::fs::write(&far, &text).unwrap();
    assert_eq!(
        load::load(far.to_str().unwrap(), &[]).unwrap().preset,
        tuned
    );
}

/// The viewer's events reach the panel: a particle clicked in the 3D view,
/// the time cursor on `sim_time` (nanoseconds) and on `frame`.
#[test]
fn viewer_events_reach_the_panel() {
    use re_viewer::external::re_log_types::{EntityPath, Instance, TimeReal};
    use re_viewer::{SelectionChangeItem, ViewerEvent, ViewerEventKind};
    let link = std::sync::Mutex::new(weft::app::panel::ViewerLink::default());
    let event = |kind| ViewerEvent {
        application_id: "weft".into(),
        recording_id: "rec_1".into(),
        segment_id: None,
        kind,
    };
    let click = |path: &str, instance: u64| {
        event(ViewerEventKind::SelectionChange {
            items: vec![SelectionChangeItem::Entity {
                entity_path: EntityPath::from(path),
                instance_id: Instance::from(instance),
                view_name: Some("Cloth".into()),
                position: None,
            }],
        })
    };
    weft::app::on_viewer_event(&link, click(paths::MESH, 3));
    assert_eq!(link.lock().unwrap().selected, None, "not a particle");
    assert_eq!(link.lock().unwrap().picked_at, None, "no point");
    // A click on the mesh where the viewer knows the point: the panel
    // picks the particle nearest it.
    weft::app::on_viewer_event(
        &link,
        event(ViewerEventKind::SelectionChange {
            items: vec![SelectionChangeItem::Entity {
                entity_path: EntityPath::from(paths::MESH),
                instance_id: Instance::ALL,
                view_name: Some("Cloth".into()),
                position: Some(glam::Vec3::new(1.0, 2.0, 3.0)),
            }],
        }),
    );
    assert_eq!(
        link.lock().unwrap().picked_at,
        Some(("rec_1".to_string(), [1.0, 2.0, 3.0]))
    );
    weft::app::on_viewer_event(&link, click(paths::PARTICLES, 23));
    assert_eq!(
        link.lock().unwrap().selected,
        Some(("rec_1".to_string(), 23))
    );
    let time = |t: f64| {
        event(ViewerEventKind::TimeUpdate {
            time: TimeReal::from(t),
        })
    };
    weft::app::on_viewer_event(&link, time(2.5e9));
    assert_eq!(
        link.lock().unwrap().cursor,
        Some(("rec_1".to_string(), BranchAt::Time(2.5)))
    );
    weft::app::on_viewer_event(
        &link,
        event(ViewerEventKind::TimelineChange {
            timeline_name: "frame".into(),
            time: TimeReal::from(120.0),
        }),
    );
    assert_eq!(
        link.lock().unwrap().cursor,
        Some(("rec_1".to_string(), BranchAt::Frame(120)))
    );
}

/// The number field beside a slider, or the `nth` field on the row of the
/// label `row` (found by where they are drawn).
fn field_on_row<'h>(
    h: &'h Harness<'_, State>,
    row: egui_kittest::Node<'h>,
    nth: usize,
) -> egui_kittest::Node<'h> {
    let row = row.rect();
    h.query_all_by_role(egui::accesskit::Role::SpinButton)
        .filter(|n| {
            let y = n.rect().center().y;
            y > row.min.y && y < row.max.y
        })
        .nth(nth)
        .expect("a number field on the row")
}

/// Clicks a number field (it becomes a text field) and types `text` into
/// it key by key, running the panel after each; `check` runs after each key.
fn type_into(
    h: &mut Harness<'_, State>,
    find: impl Fn(&Harness<'_, State>) -> (egui::Rect, usize),
    text: &str,
    check: impl Fn(&Harness<'_, State>),
) {
    let (rect, nth) = find(h);
    let field = h
        .query_all_by_role(egui::accesskit::Role::SpinButton)
        .filter(|n| {
            let y = n.rect().center().y;
            y > rect.min.y && y < rect.max.y
        })
        .nth(nth)
        .expect("a number field on the row");
    field.click();
    h.run();
    for c in text.chars() {
        h.event(egui::Event::Text(c.to_string()));
        h.run();
        std::thread::sleep(Duration::from_millis(50));
        check(h);
    }
}

fn curvature(h: &Harness<'_, State>) -> f32 {
    h.state().session.status().preset.unwrap().solver.weights[Family::Curvature]
}

/// A value typed into a slider's field is taken on Enter, not keystroke by
/// keystroke: the simulation never sees 0, 0.3 on the way to 0.35.
#[test]
fn a_typed_value_applies_on_enter() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    let slider = |h: &Harness<'_, State>| {
        let r = h
            .get_by_role_and_label(egui::accesskit::Role::Slider, "λ curvature")
            .rect();
        (r, 0)
    };
    type_into(&mut h, slider, "0.35", |h| {
        assert_eq!(curvature(h), 0.1, "applied while typing");
    });
    press(&mut h, egui::Key::Enter);
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.preset.as_ref().unwrap().solver.weights[Family::Curvature] == 0.35
    }));
    // A slider's value field, then another field: leaving it applies too.
    type_into(&mut h, slider, "0.2", |h| assert_eq!(curvature(h), 0.35));
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "λ stretch")
        .click();
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.preset.as_ref().unwrap().solver.weights[Family::Curvature] == 0.2
    }));
}

/// A rejected typed value changes nothing (no value on the way to it
/// either), and the reason shows in the status line at the top.
#[test]
fn a_rejected_typed_value_changes_nothing() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    let wind_x = |h: &Harness<'_, State>| {
        h.state()
            .session
            .status()
            .preset
            .unwrap()
            .environment
            .wind
            .velocity
            .x
    };
    let before = wind_x(&h);
    let row = |h: &Harness<'_, State>| (h.get_by_label("velocity").rect(), 0);
    type_into(&mut h, row, "2000", |h| {
        assert_eq!(wind_x(h), before, "applied while typing");
    });
    press(&mut h, egui::Key::Enter);
    std::thread::sleep(Duration::from_millis(200));
    h.run();
    assert_eq!(wind_x(&h), before);
    let message = h.get_by_label_contains("environment.wind.velocity");
    let text = message.value().unwrap_or_default();
    assert!(text.contains("out of range"), "{text}");
    // Beside the wind's controls, under them, not at the top of the panel.
    let velocity = h.get_by_label("velocity").rect();
    let telemetry = h.get_by_label("Telemetry").rect();
    assert!(
        message.rect().min.y > velocity.max.y
            && message.rect().max.y < telemetry.min.y
            && message.rect().min.y - velocity.max.y < 120.0,
        "{text}: at {:?}, the wind's velocity at {velocity:?}",
        message.rect()
    );
    // The next valid input clears it.
    set_slider(&mut h, "λ curvature", 0.3);
    assert!(
        h.query_by_label_contains("environment.wind.velocity")
            .is_none(),
        "the refusal stays after a valid input"
    );
    // The field shows the value in force again.
    let row = h.get_by_label("velocity");
    let x = field_on_row(&h, row, 0);
    assert!(
        !x.value().unwrap_or_default().contains("2000"),
        "{:?}",
        x.value()
    );
}

/// Space plays and pauses, → steps, Backspace resets (as F6, F7, F9 do),
/// unless a text field is being typed in; the panel names them.
#[test]
fn space_arrow_and_backspace_drive_the_simulation() {
    let mut h = harness(state("hanging_sheet"));
    h.run();
    h.get_by_label_contains("Space play/pause");
    press(&mut h, egui::Key::ArrowRight);
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 1));
    press(&mut h, egui::Key::Space);
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.playing && s.frame > 3)
    );
    h.run();
    press(&mut h, egui::Key::Space);
    assert!(h.state().session.wait_for(WAIT, |s| !s.playing));
    press(&mut h, egui::Key::Backspace);
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 2 && s.frame == 0)
    );
    h.run();
    h.get_by_label("Play").hover();
    h.run();
    h.get_by_label_contains("F6 or Space");

    // Typing in a field: the keys are the field's.
    let field = h
        .query_all_by_role(egui::accesskit::Role::TextInput)
        .find(|n| n.value().as_deref() == Some("hanging_sheet"))
        .expect("the preset file field");
    field.click();
    h.run();
    for key in [
        egui::Key::Space,
        egui::Key::ArrowRight,
        egui::Key::Backspace,
    ] {
        press(&mut h, key);
    }
    std::thread::sleep(Duration::from_millis(200));
    let s = h.state().session.status();
    assert_eq!((s.playing, s.frame, s.run.number), (false, 0, 2));
}

/// A frame past the run's last is refused with the reason, not clamped;
/// a typed frame is not overwritten while the simulation plays.
#[test]
fn the_branch_field_is_the_users() {
    let s = state("hanging_sheet");
    let link = s.panel.link();
    let mut h = harness(s);
    h.run();
    for _ in 0..10 {
        h.state().session.send(Command::Step);
    }
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 10));
    h.run();
    let row = |h: &Harness<'_, State>| (h.get_by_label("at frame").rect(), 0);
    type_into(&mut h, row, "99999", |_| {});
    press(&mut h, egui::Key::Enter);
    click(&mut h, "Branch");
    assert!(h.state().session.wait_for(WAIT, |s| {
        s.error
            .as_deref()
            .is_some_and(|e| e.contains("cannot branch at frame 99999"))
    }));
    h.run();
    h.get_by_label_contains("cannot branch at frame 99999");
    assert_eq!(h.state().session.status().run.number, 1);

    // Typed while playing: the frame moves on, the text stays; then the
    // viewer's time cursor moves, and the typed frame still stays.
    h.state().session.send(Command::Play);
    type_into(&mut h, row, "7", |_| {});
    assert!(h.state().session.wait_for(WAIT, |s| s.frame > 20));
    h.run();
    press(&mut h, egui::Key::Enter);
    let id = h.state().session.status().run.recording_id;
    link.lock().unwrap().time(id.clone(), 0.25e9);
    h.run();
    h.state().session.send(Command::Pause);
    assert!(h.state().session.wait_for(WAIT, |s| !s.playing));
    h.run();
    click(&mut h, "Branch");
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 2 && s.frame == 7),
        "{:?}",
        h.state().session.status().frame
    );

    // Cleared, the field follows the time cursor again.
    type_into(&mut h, row, "3", |_| {});
    press(&mut h, egui::Key::Enter);
    click(&mut h, "clear");
    let id = h.state().session.status().run.recording_id;
    let dt = h.state().session.status().preset.unwrap().solver.dt as f64;
    link.lock().unwrap().time(id, 5.0 * dt * 1e9);
    h.run();
    h.get_by_label_contains("(time cursor");
    click(&mut h, "Branch");
    assert!(
        h.state()
            .session
            .wait_for(WAIT, |s| s.run.number == 3 && s.frame == 5)
    );
}

/// The branch field follows the run: after Reset it reads the new run's
/// frame, not the old run's time cursor. (After a pause, the session puts
/// the viewer's cursor on the frame it stopped on, which the field then
/// reads: `tests/live_view.rs`.)
#[test]
fn the_branch_field_follows_the_run() {
    let s = state("hanging_sheet");
    let link = s.panel.link();
    let mut h = harness(s);
    h.run();
    for _ in 0..12 {
        h.state().session.send(Command::Step);
    }
    assert!(h.state().session.wait_for(WAIT, |s| s.frame == 12));
    let id = h.state().session.status().run.recording_id;
    let dt = h.state().session.status().preset.unwrap().solver.dt as f64;
    link.lock().unwrap().time(id, 9.0 * dt * 1e9);
    h.run();
    h.get_by_label_contains("(time cursor");
    press(&mut h, egui::Key::Backspace);
    assert!(h.state().session.wait_for(WAIT, |s| s.run.number == 2));
    h.run();
    h.run();
    assert!(h.query_by_label_contains("(time cursor").is_none());
    let row = h.get_by_label("at frame");
    assert_eq!(field_on_row(&h, row, 0).value().as_deref(), Some("0"));
}

/// While the viewer follows the run, the simulation keeps no more than
/// `MAX_LEAD` ahead of the frame it shows; a cursor that stands still (the
/// user scrubbed) does not hold it back.
#[test]
fn the_simulation_waits_for_the_viewer() {
    use weft::app::session::{FOLLOWING, MAX_LEAD};
    let session = state("hanging_sheet").session;
    let id = session.status().run.recording_id;
    let dt = session.status().preset.unwrap().solver.dt as f64;
    let lead = (MAX_LEAD / dt).ceil() as u64;
    session.pace_to_viewer();
    // Before the viewer's first report, the simulation waits for it.
    session.send(Command::Play);
    assert!(session.wait_for(WAIT, |s| s.frame >= lead));
    std::thread::sleep(FOLLOWING / 4);
    assert!(
        session.status().frame <= lead + 1,
        "{}",
        session.status().frame
    );
    // The viewer catches up: the simulation goes on, and waits again.
    session.viewer_shows(id.clone(), BranchAt::Time(lead as f64 * dt));
    assert!(session.wait_for(WAIT, |s| s.frame >= 2 * lead));
    std::thread::sleep(FOLLOWING / 4);
    assert!(
        session.status().frame <= 2 * lead + 1,
        "{}",
        session.status().frame
    );
    // The user scrubs back: the simulation runs free.
    session.viewer_shows(id.clone(), BranchAt::Time(0.0));
    assert!(session.wait_for(WAIT, |s| s.frame > 4 * lead));
    session.send(Command::Pause);
}

/// A new run (Reset, Load) starts its speed readouts from nothing.
#[test]
fn a_new_run_clears_the_speed_readouts() {
    let session = state("hanging_sheet").session;
    session.send(Command::Play);
    assert!(session.wait_for(WAIT, |s| s.frame > 20 && s.steps_per_second > 0.0));
    session.send(Command::Pause);
    session.send(Command::Reset);
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    let s = session.status();
    assert_eq!((s.steps_per_second, s.step_ms), (0.0, 0.0));
}

/// `PlayTo` (what `weft gui --screenshot --frames N` sends) stops at N.
#[test]
fn play_to_stops_at_its_frame() {
    let session = state("hanging_sheet").session;
    session.send(Command::PlayTo(40));
    assert!(session.wait_for(WAIT, |s| s.frame >= 40 && !s.playing));
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(session.status().frame, 40);
}

/// Paced to a window, a playing session sends a frame's drawing only once
/// the window has drawn since the last one (the frames in between send
/// their scalars), and each drawing is whole: particles and mesh of the
/// same frame. Stopped, the frame it stopped on is drawn.
#[test]
fn a_paced_window_is_sent_a_drawing_per_frame_it_draws() {
    use std::collections::{BTreeMap, BTreeSet};
    type Frames = BTreeMap<String, BTreeSet<i64>>;
    let logged = std::sync::Arc::new(std::sync::Mutex::new(Frames::new()));
    let sink = logged.clone();
    let set = ["telemetry.level=full".parse().unwrap()];
    let loaded = load::load("hanging_sheet", &set).unwrap();
    let session = Session::start(
        loaded,
        "hanging_sheet".into(),
        move |msg: &rerun::log::LogMsg| {
            if let Some((_, entity, frames)) = logged_frames(msg) {
                let mut logged = sink.lock().unwrap();
                logged.entry(entity).or_default().extend(frames);
            }
        },
    )
    .unwrap();
    session.pace_to_viewer();
    session.send(Command::PlayTo(60));
    let mut draws = 0;
    while !session.wait_for(Duration::from_millis(100), |s| s.frame >= 60 && !s.playing) {
        session.window_drew();
        draws += 1;
        assert!(draws < 2000, "the run did not reach frame 60");
    }
    drop(session);
    let logged = logged.lock().unwrap();
    let frames = |path: &str| logged.get(&format!("/{path}")).cloned().unwrap_or_default();
    let (strain, particles, mesh) = (
        frames(paths::STRAIN),
        frames(paths::PARTICLES),
        frames(paths::MESH),
    );
    // Every frame's scalars.
    assert_eq!(strain, (1..=60).collect(), "{strain:?}");
    // A drawing per frame the window drew, whole; and the last frame's.
    assert_eq!(particles, mesh, "a drawing sent in part");
    assert!(
        particles.contains(&0) && particles.contains(&60),
        "{particles:?}"
    );
    assert!(
        particles.len() <= draws + 2 && particles.len() < 60,
        "{} drawings for {draws} draws: {particles:?}",
        particles.len()
    );
}
