//! Grabbing the cloth in the debugger (Ctrl-drag): the session's grab,
//! move and release, driven as the window drives them, beside the panel
//! run with egui_kittest. The grabbed particle follows its target; the
//! pull is drawn while it lasts; a slider moved meanwhile does not let go;
//! and a recording of the session replays bit for bit, the drag included.
#![cfg(feature = "viewer")]

use egui_kittest::{Harness, kittest::Queryable};
use glam::DVec3;
use weft::app::session::{Command, Session};
use weft::scene::load;
use weft::telemetry::{paths, read};

mod common;
use common::panel::{State, WAIT, set_slider, state_with};

fn harness(preset: &str) -> Harness<'static, State> {
    common::panel::harness(state_with(preset, &[]))
}

/// Steps `n` frames through the panel's Step button.
fn step(h: &mut Harness<'_, State>, n: u64) {
    for _ in 0..n {
        let next = h.state().session.status().frame + 1;
        h.get_by_label("Step").click();
        h.run();
        assert!(h.state().session.wait_for(WAIT, |s| s.frame == next));
    }
}

#[test]
fn a_drag_pulls_the_particle_and_replays_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drag.rrd");
    let mut h = harness("hanging_sheet");
    h.state_mut().panel.set_record_path(file.to_str().unwrap());
    h.run();
    h.get_by_label("Record").click();
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_some()));
    step(&mut h, 5);

    // Grab beside the lowest particle (a free one: the sheet hangs from
    // its top row): the particle nearest the point is taken.
    let preset = h.state().session.status().preset.unwrap();
    let mut scene = weft::scene::Scene::new(&preset).unwrap();
    for _ in 0..5 {
        scene.step().unwrap();
    }
    let x = scene.world_positions();
    let corner = (0..x.len())
        .min_by(|&a, &b| x[a].z.total_cmp(&x[b].z))
        .unwrap();
    let near = x[corner] + glam::Vec3::new(0.0, 0.0, 0.01);
    let session = &h.state().session;
    session.send(Command::Grab(near.to_array()));
    assert!(session.wait_for(WAIT, |s| s.pull.is_some_and(|p| p.particle == corner)));
    let grabbed = session.status().pull.unwrap();
    assert_eq!(grabbed.target, grabbed.at, "held where it is");

    // Move the target 30 cm sideways and up, in steps, as a drag does.
    let target = grabbed.at + DVec3::new(0.3, 0.0, 0.3);
    for k in 1..=3 {
        let to = grabbed.at + (target - grabbed.at) * (k as f64 / 3.0);
        h.state().session.send(Command::PullTo(to.to_array()));
        step(&mut h, 4);
    }
    // A slider moved during the drag does not let go.
    set_slider(&mut h, "λ curvature", 0.3);
    step(&mut h, 8);
    let pulled = h.state().session.status().pull.unwrap();
    assert_eq!(pulled.target, target);
    assert!(
        pulled.at.distance(target) < 0.5 * grabbed.at.distance(target),
        "the particle follows: {} → {}, target {target}",
        grabbed.at,
        pulled.at
    );

    h.state().session.send(Command::Release);
    step(&mut h, 3);
    assert_eq!(h.state().session.status().pull, None);
    h.get_by_label("Stop recording").click();
    h.run();
    assert!(h.state().session.wait_for(WAIT, |s| s.recording.is_none()));
    let digest = h.state().session.status().digest;

    let rec = read::read(&file).unwrap();
    // Grabbed and first moved for frame 6 (one change: both came before
    // that step), moved for 10 and 14, the slider for 18 (the pull kept),
    // let go for frame 26.
    let pulls: Vec<i64> = rec
        .params
        .iter()
        .filter(|(_, t)| t.contains("[pull]"))
        .map(|(f, _)| *f)
        .collect();
    assert_eq!(pulls, vec![6, 10, 14, 18], "{:?}", rec.params);
    let events = |needle: &str| -> Vec<i64> {
        rec.events
            .iter()
            .filter(|(_, m)| m.contains(needle))
            .map(|(f, _)| *f)
            .collect()
    };
    // The drag is two events, its start and its end (with its path), in
    // millimetres.
    assert_eq!(events("grabbed particle"), vec![6]);
    assert_eq!(events("let go of particle"), vec![26]);
    assert!(
        !rec.events.iter().any(|(_, m)| m.contains("pull.target")),
        "{:?}",
        rec.events
    );
    let (_, end) = rec.events.iter().find(|(f, _)| *f == 26).unwrap();
    // The grab and the first move were one change; two moves followed.
    assert!(end.contains("in 2 moves, along"), "{end}");
    assert!(!end.contains("0000"), "{end}");
    // Drawn from the grab to the frame before the release, blanked at it.
    assert_eq!(
        rec.frames(paths::PULL),
        (6..=26).collect::<Vec<i64>>(),
        "{:?}",
        rec.entities.keys().collect::<Vec<_>>()
    );

    let replayed = weft::replay::replay(&file).unwrap();
    assert!(replayed.reproduced(), "{replayed:?}");
    assert_eq!(replayed.digest, digest);
    assert_eq!(replayed.frames, 28);
}

/// A branch from a frame in the middle of a drag starts from the state
/// the run had there, bit for bit: the session re-applies the grab and the
/// moves to reach it. From there it goes on with the current tuning, which
/// no longer pulls.
#[test]
fn a_branch_in_the_middle_of_a_drag_is_bit_identical() {
    let loaded = load::load("hanging_sheet", &[]).unwrap();
    let session = Session::start(loaded, "hanging_sheet".into(), |_| {}).unwrap();
    let step_to = |frame: u64| common::panel::step_to(&session, frame);
    step_to(40);
    let preset = session.status().preset.unwrap();
    let mut scene = weft::scene::Scene::new(&preset).unwrap();
    for _ in 0..40 {
        scene.step().unwrap();
    }
    let x = scene.world_positions();
    let low = (0..x.len())
        .min_by(|&a, &b| x[a].z.total_cmp(&x[b].z))
        .unwrap();
    session.send(Command::Grab(x[low].to_array()));
    let from = x[low].as_dvec3();
    for k in 1..=3 {
        session.send(Command::PullTo(
            (from + DVec3::new(0.1 * k as f64, -0.1, 0.1)).to_array(),
        ));
        step_to(40 + 6 * k);
    }
    // Grabbed for frame 41, moved for 41, 47 and 53.
    let at_58 = step_to(58);
    step_to(70);
    session.send(Command::Release);
    let at_100 = step_to(100);

    // From checkpoint 30, through the grab and the moves, to 58.
    session.send(Command::Branch(weft::app::session::BranchAt::Frame(58)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    let s = session.status();
    assert_eq!((s.frame, &s.digest), (58, &at_58));
    assert_eq!(s.pull, None, "the branch goes on with the current tuning");
    assert_ne!(step_to(100), at_100, "let go at 58, not at 70");
}

/// On the car flag, which the camera follows down the road, the viewer
/// may show a frame a little behind the simulation: what is grabbed and
/// where it is pulled to are the points seen there, carried with the car
/// to the simulation's frame.
#[test]
fn a_point_seen_behind_the_simulation_is_carried_with_the_car() {
    let loaded = load::load("flag_on_car", &[]).unwrap();
    let preset = loaded.preset.clone();
    let session = Session::start(loaded, "flag_on_car".into(), |_| {}).unwrap();
    for _ in 0..120 {
        session.send(Command::Step);
    }
    assert!(session.wait_for(WAIT, |s| s.frame == 120));
    // The scene at frame 105 (what the viewer shows) and at 120.
    let mut scene = weft::scene::Scene::new(&preset).unwrap();
    for _ in 0..105 {
        scene.step().unwrap();
    }
    let seen = scene.world_positions().into_owned();
    let seen_origin = scene.solver().frame().origin;
    for _ in 105..120 {
        scene.step().unwrap();
    }
    let moved = scene.solver().frame().origin - seen_origin;
    assert!(moved.length() > 1.0, "the car drove on: {moved}");
    let now = scene.world_positions().into_owned();
    let nearest = |p: DVec3| {
        (0..now.len())
            .min_by(|&a, &b| {
                (now[a].as_dvec3().distance(p)).total_cmp(&now[b].as_dvec3().distance(p))
            })
            .unwrap()
    };

    let id = session.status().run.recording_id;
    session.viewer_shows(id, weft::app::session::BranchAt::Frame(105));
    let tip = preset.cloth.weft as usize - 1;
    session.send(Command::Grab(seen[tip].to_array()));
    assert!(session.wait_for(WAIT, |s| s.pull.is_some()));
    // The particle nearest the seen point carried with the car; not the
    // one nearest it where it was seen, metres behind.
    let grabbed = nearest(seen[tip].as_dvec3() + moved);
    assert_eq!(session.status().pull.unwrap().particle, grabbed);
    let far = now[nearest(seen[tip].as_dvec3())].as_dvec3();
    assert!(far.distance(seen[tip].as_dvec3()) > 0.5, "{far}");
    let to = seen[tip].as_dvec3() + DVec3::new(0.0, 0.0, 0.3);
    session.send(Command::PullTo(to.to_array()));
    assert!(session.wait_for(WAIT, |s| s.pull.is_some_and(|p| p.target != p.at)));
    assert_eq!(session.status().pull.unwrap().target, to + moved);
}
