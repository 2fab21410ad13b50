//! Whether the 3D view draws one frame: what the viewer holds, at its time
//! cursor, of every entity drawn at each frame.
//!
//! The viewer draws each entity as it was last logged at or before its time
//! cursor. The cloth's particles, the points the camera frames, the mesh
//! and a branch's ghost are logged together at every frame that is drawn,
//! so at a cursor where all of that frame has reached the viewer they were
//! all last logged at the same time; one last logged earlier than another
//! means the view mixes two frames.

use re_viewer::external::re_log_channel::{DataSourceMessage, DataSourceUiCommand};
use re_viewer::external::re_log_types::{EntityPath, TimeCell};

use crate::app::session::follow::WholeFrame;
use crate::telemetry::paths;

/// The viewer command that puts its time cursor on `frame`, on `timeline`
/// (the viewer's active one; `sim_time` if it has not said) and pauses its
/// own playing there: the frame shown until the next is whole.
pub fn cursor_command(frame: &WholeFrame, timeline: Option<&str>) -> DataSourceMessage {
    let (timeline, cell) = match timeline {
        Some(paths::FRAME) => (paths::FRAME, TimeCell::from_sequence(frame.frame as i64)),
        _ => (
            paths::SIM_TIME,
            TimeCell::from_duration_nanos(frame.sim_time_ns),
        ),
    };
    struct Url(TimeCell);
    impl std::fmt::Display for Url {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            self.0.format_url(f)
        }
    }
    DataSourceMessage::UiCommand(DataSourceUiCommand::SetUrlFragment {
        store_id: frame.store_id.clone(),
        fragment: format!("when={timeline}@{}", Url(cell)),
    })
}

/// The entities drawn at every drawn frame, and the component that each
/// frame logs for each.
fn drawn_every_frame() -> [(&'static str, rerun::ComponentDescriptor); 4] {
    [
        (paths::PARTICLES, rerun::Points3D::descriptor_positions()),
        (paths::FRAMING, rerun::Points3D::descriptor_positions()),
        (paths::MESH, rerun::Mesh3D::descriptor_vertex_positions()),
        (paths::GHOST, rerun::Mesh3D::descriptor_vertex_positions()),
    ]
}

/// When (on the viewer's active timeline) each entity drawn at every frame
/// was last logged at or before the viewer's time cursor, for the entities
/// that have been logged; `None` without a recording shown.
pub fn last_logged(viewer: &re_viewer::App) -> Option<Vec<(&'static str, i64)>> {
    let db = viewer.recording_db()?;
    let query = viewer.current_query()?;
    let mut times = Vec::new();
    for (path, descriptor) in drawn_every_frame() {
        let results = db.latest_at(&query, &EntityPath::from(path), [descriptor.component]);
        if results.is_empty() {
            continue;
        }
        let (time, _) = results.max_index();
        if !time.is_static() {
            times.push((path, time.as_i64()));
        }
    }
    Some(times)
}

/// Whether entities last logged at these times show two frames or more.
pub fn mixed(times: &[(&'static str, i64)]) -> bool {
    times.windows(2).any(|w| w[0].1 != w[1].1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_time_is_one_frame() {
        assert!(!mixed(&[]));
        assert!(!mixed(&[(paths::PARTICLES, 5)]));
        assert!(!mixed(&[(paths::PARTICLES, 5), (paths::MESH, 5)]));
        assert!(mixed(&[(paths::PARTICLES, 5), (paths::MESH, 4)]));
    }
}
