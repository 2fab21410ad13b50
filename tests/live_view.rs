//! The live view from what a session sends the window: each frame's
//! drawing whole before the viewer's time cursor is put on it, the cursor
//! the user's once they move it back.
#![cfg(feature = "viewer")]

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use weft::app::session::{BranchAt, Command, Session};
use weft::scene::load;
use weft::telemetry::paths;

mod common;
use common::panel::{WAIT, logged_frames};

/// What reached the window, in order: a chunk of an entity at frames, or
/// the cursor put on a frame.
#[derive(Debug)]
enum Sent {
    Chunk(String, String, Vec<i64>),
    Cursor(String, u64),
}

/// A paced session of `preset` (with `set`) recording what it sends.
fn session(preset: &str, set: &[&str]) -> (Session, Arc<Mutex<Vec<Sent>>>) {
    let sent = Arc::new(Mutex::new(Vec::new()));
    let sink = sent.clone();
    let set: Vec<_> = set.iter().map(|s| s.parse().unwrap()).collect();
    let loaded = load::load(preset, &set).unwrap();
    let session = Session::start(loaded, preset.into(), move |msg: &rerun::log::LogMsg| {
        if let Some((recording, entity, frames)) = logged_frames(msg) {
            sink.lock()
                .unwrap()
                .push(Sent::Chunk(recording, entity, frames));
        }
    })
    .unwrap();
    let sink = sent.clone();
    session.on_whole_frame(move |f| {
        sink.lock()
            .unwrap()
            .push(Sent::Cursor(f.recording_id.clone(), f.frame));
    });
    session.pace_to_viewer();
    (session, sent)
}

/// Plays until `frame`, the window drawing (and the viewer reporting its
/// cursor where it was last put) every 20 ms.
fn play_to(session: &Session, sent: &Mutex<Vec<Sent>>, frame: u64) {
    session.send(Command::PlayTo(frame));
    let mut draws = 0;
    while !session.wait_for(Duration::from_millis(20), |s| {
        s.frame >= frame && !s.playing
    }) {
        session.window_drew();
        let last = sent.lock().unwrap().iter().rev().find_map(|s| match s {
            Sent::Cursor(id, f) => Some((id.clone(), *f)),
            Sent::Chunk(..) => None,
        });
        if let Some((id, f)) = last {
            session.viewer_shows(id, BranchAt::Frame(f));
        }
        draws += 1;
        assert!(draws < 3000, "the run did not reach frame {frame}");
    }
}

/// The entities drawn at every drawn frame.
const DRAWN: [&str; 4] = [paths::PARTICLES, paths::FRAMING, paths::MESH, paths::GHOST];

/// Checks that each cursor comes after all of its frame's drawing, and no
/// drawing of a later frame: at every cursor, each entity drawn at every
/// frame was last sent at the cursor's frame. Returns the cursors' frames
/// per recording.
fn cursors_on_whole_frames(sent: &[Sent]) -> BTreeMap<String, Vec<u64>> {
    let mut last: BTreeMap<(String, String), i64> = BTreeMap::new();
    let mut cursors: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for s in sent {
        match s {
            Sent::Chunk(id, entity, frames) => {
                let e = entity.trim_start_matches('/').to_string();
                if let Some(f) = frames.iter().max() {
                    last.insert((id.clone(), e), *f);
                }
            }
            Sent::Cursor(id, frame) => {
                for e in DRAWN {
                    if let Some(f) = last.get(&(id.clone(), e.to_string())) {
                        assert_eq!(
                            *f, *frame as i64,
                            "{e} last sent at frame {f} when the cursor went to {frame}"
                        );
                    }
                }
                assert!(
                    last.contains_key(&(id.clone(), paths::MESH.to_string())),
                    "a cursor before any mesh"
                );
                cursors.entry(id.clone()).or_default().push(*frame);
            }
        }
    }
    cursors
}

/// While a window plays, recording and branching, the viewer's cursor is
/// only ever put on a frame all of whose drawing (particles, framing
/// points, mesh, the parent's ghost) it has been sent, and each goes
/// forward, to the frame the run stops on.
#[test]
fn the_cursor_goes_only_to_whole_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (session, sent) = session("flag_on_car", &[]);
    play_to(&session, &sent, 60);
    let first = session.status().run.recording_id;
    // Record (a new run from frame 0), then branch it at frame 20.
    session.send(Command::StartRecording(dir.path().join("a.rrd")));
    assert!(session.wait_for(WAIT, |s| s.run.number == 2));
    play_to(&session, &sent, 40);
    let recorded = session.status().run.recording_id;
    session.send(Command::StopRecording);
    session.send(Command::Branch(BranchAt::Frame(20)));
    assert!(session.wait_for(WAIT, |s| s.run.number == 3));
    // Within the parent's 40 frames: the ghost is drawn at every frame.
    play_to(&session, &sent, 38);
    let branch = session.status().run.recording_id;
    drop(session);
    let sent = sent.lock().unwrap();
    let cursors = cursors_on_whole_frames(&sent);
    for (id, stop) in [(&first, 60), (&recorded, 40), (&branch, 38)] {
        let frames = &cursors[id];
        assert!(frames.len() > 3, "{frames:?}");
        assert!(frames.windows(2).all(|w| w[0] < w[1]), "{frames:?}");
        assert_eq!(frames.last(), Some(&stop), "{frames:?}");
    }
    // The branch drew its parent's ghost with its own frames.
    assert!(
        sent.iter().any(
            |s| matches!(s, Sent::Chunk(id, e, _) if *id == branch && e.ends_with(paths::GHOST))
        )
    );
}

/// Once the user moves the cursor back, the session stops moving it
/// (and runs free of it) until the next Play.
#[test]
fn a_cursor_moved_back_is_the_user_s() {
    let (session, sent) = session("hanging_sheet", &[]);
    let cursors = |sent: &Mutex<Vec<Sent>>| {
        sent.lock()
            .unwrap()
            .iter()
            .filter(|s| matches!(s, Sent::Cursor(..)))
            .count()
    };
    let dt = session.status().preset.unwrap().solver.dt as f64;
    let nanos = |f: u64| std::time::Duration::from_secs_f64(f as f64 * dt).as_nanos() as f64;
    // The window draws every 10 ms, and the viewer reports its cursor
    // when the session has put it on another frame (on `sim_time`).
    let reported = Mutex::new(None);
    let draw_while = |until: u64| {
        while !session.wait_for(Duration::from_millis(10), |s| s.frame >= until) {
            session.window_drew();
            let last = sent.lock().unwrap().iter().rev().find_map(|s| match s {
                Sent::Cursor(id, f) => Some((id.clone(), *f)),
                Sent::Chunk(..) => None,
            });
            let mut reported = reported.lock().unwrap();
            if let Some((id, f)) = last
                && *reported != Some(f)
            {
                *reported = Some(f);
                session.viewer_shows(id, BranchAt::Time(nanos(f) * 1e-9));
            }
        }
    };
    session.send(Command::Play);
    draw_while(20);
    let id = session.status().run.recording_id;
    assert!(cursors(&sent) > 2);
    // Scrubbed back while playing, between two frames.
    session.viewer_shows(id, BranchAt::Time(0.1234));
    // (A cursor being sent as the user moved it arrives.)
    std::thread::sleep(Duration::from_millis(100));
    let before = cursors(&sent);
    let frame = session.status().frame;
    draw_while(frame + 30);
    assert_eq!(cursors(&sent), before, "the cursor was moved from the user");
    // Play again: the cursor is the session's.
    session.send(Command::Pause);
    session.send(Command::Play);
    let frame = session.status().frame;
    draw_while(frame + 20);
    session.send(Command::Pause);
    assert!(cursors(&sent) > before);
}
