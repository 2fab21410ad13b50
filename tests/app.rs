//! The tuning panel driven with egui_kittest: transport, sliders reaching
//! the solver and the recording, validation messages, saving presets, and an
//! off-screen snapshot (wgpu; lavapipe on CI).
#![cfg(feature = "viewer")]

use std::time::Duration;

use egui::accesskit::{Action, ActionData, ActionRequest};
use egui_kittest::{Harness, kittest::NodeT, kittest::Queryable};
use weft::app::{
    panel::Panel,
    session::{Command, Session},
};
use weft::scene::load;
use weft::solver::Family;
use weft::telemetry::{paths, read};

struct State {
    panel: Panel,
    session: Session,
}

const WAIT: Duration = Duration::from_secs(20);

fn state(preset: &str) -> State {
    let loaded = load::load(preset, &[]).unwrap();
    let session = Session::start(loaded, preset.into(), |_| {}).unwrap();
    let panel = Panel::new(&session.status());
    State { panel, session }
}

fn harness(state: State) -> Harness<'static, State> {
    Harness::builder()
        .with_size([360.0, 1250.0])
        .build_ui_state(|ui, s: &mut State| s.panel.ui(ui, &s.session), state)
}

/// Types a value into a slider, as a user (or screen reader) can.
fn set_slider(h: &mut Harness<'_, State>, label: &str, value: f64) {
    let (target_node, target_tree) = h
        .get_by_role_and_label(egui::accesskit::Role::Slider, label)
        .accesskit_node()
        .locate();
    h.event(egui::Event::AccessKitActionRequest(ActionRequest {
        target_node,
        target_tree,
        action: Action::SetValue,
        data: Some(ActionData::NumericValue(value)),
    }));
    h.run();
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
    h.get_by_label_contains("did you mean `curvature`");
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
        .with_size([360.0, 1250.0])
        .wgpu()
        .build_ui_state(
            |ui, s: &mut State| s.panel.ui(ui, &s.session),
            state("flag_on_car"),
        );
    h.run();
    h.snapshot("panel");
}

/// A session opened at level `summary` and switched to `full` from the
/// panel draws the corrections from then on: the app keeps every particle's
/// corrections whatever level it starts at.
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
    for frame in 1..=3 {
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
