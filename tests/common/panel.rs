//! The tuning panel beside a real session, driven with `egui_kittest` as a
//! user (or a screen reader) drives it.

use std::time::Duration;

use egui::accesskit::{Action, ActionData, ActionRequest};
use egui_kittest::{Harness, kittest::NodeT, kittest::Queryable};
use weft::app::{
    panel::Panel,
    session::{Command, Session},
};
use weft::scene::load;

/// What the harness holds: the panel and its session.
pub struct State {
    pub panel: Panel,
    pub session: Session,
}

/// How long a test waits for the session to get somewhere.
pub const WAIT: Duration = Duration::from_secs(20);

/// A session of `preset` with `--set` overrides such as
/// `expect.max_strain=0.1`, and its panel.
pub fn state_with(preset: &str, sets: &[&str]) -> State {
    let sets: Vec<_> = sets.iter().map(|s| s.parse().unwrap()).collect();
    let loaded = load::load(preset, &sets).unwrap();
    let session = Session::start(loaded, preset.into(), |_| {}).unwrap();
    let panel = Panel::new(&session.status());
    State { panel, session }
}

/// The panel of `state` in a harness the size of the panel's snapshot.
pub fn harness(state: State) -> Harness<'static, State> {
    Harness::builder()
        .with_size([360.0, 1400.0])
        .build_ui_state(|ui, s: &mut State| s.panel.ui(ui, &s.session), state)
}

/// Types a value into a slider, as a user (or screen reader) can.
pub fn set_slider(h: &mut Harness<'_, State>, label: &str, value: f64) {
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

/// Steps `session` to `frame` and returns its state's digest there.
pub fn step_to(session: &Session, frame: u64) -> String {
    let now = session.status().frame;
    for _ in now..frame {
        session.send(Command::Step);
    }
    assert!(
        session.wait_for(WAIT, |s| s.frame == frame),
        "{frame}: {:?} at {}",
        session.status().error,
        session.status().frame
    );
    session.status().digest
}

/// A recording's data message as its recording id, entity path and the
/// frames it was logged at (`None` for anything else: the blueprint, a
/// message without the frame timeline).
pub fn logged_frames(msg: &rerun::log::LogMsg) -> Option<(String, String, Vec<i64>)> {
    let rerun::log::LogMsg::ArrowMsg(store, arrow) = msg else {
        return None;
    };
    if !store.is_recording() {
        return None;
    }
    let chunk = rerun::log::Chunk::from_arrow_msg(arrow).unwrap();
    let frames = chunk
        .timelines()
        .get(&weft::telemetry::paths::FRAME.into())?;
    Some((
        store.recording_id().to_string(),
        chunk.entity_path().to_string(),
        frames.times_raw().to_vec(),
    ))
}
