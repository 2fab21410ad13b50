//! Reading a recording back: entity paths, frames, array lengths, and the
//! texts weft stores (preset, parameters, summary, events).
//!
//! Used by `weft replay`, `weft compare` and by tests, with Rerun's own
//! decoder.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use rerun::external::re_log_encoding::DecoderApp;
use rerun::log::{Chunk, LogMsg};

use super::paths;

/// What one entity holds in a recording.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EntityInfo {
    /// Whether any of it is static.
    pub is_static: bool,
    /// Component names (e.g. `Points3D:positions`).
    pub components: BTreeSet<String>,
    /// Values on the `frame` timeline at which it was logged.
    pub frames: BTreeSet<i64>,
    /// Values on the `sim_time` timeline, in nanoseconds.
    pub sim_times: BTreeSet<i64>,
    /// Length of each temporal row's main array (positions, vectors, scalars…), in frame order.
    pub lengths: Vec<usize>,
}

/// The contents of a recording, as weft wrote them.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// Every entity, by path (without the leading `/`).
    pub entities: BTreeMap<String, EntityInfo>,
    /// The resolved preset.
    pub preset: Option<String>,
    /// Parameter sets (TOML) by the frame they took effect.
    pub params: Vec<(i64, String)>,
    /// Event messages by frame.
    pub events: Vec<(i64, String)>,
    /// The end-of-run summary, if the run finished.
    pub summary: Option<String>,
    /// Particle positions at the last logged frame.
    pub last_positions: Option<(i64, Vec<[f32; 3]>)>,
    /// Particle positions at every logged frame.
    pub positions: BTreeMap<i64, Vec<[f32; 3]>>,
    /// Every scalar series (`metrics/…`), by entity path: one sample per
    /// logged frame, in frame order.
    pub scalars: BTreeMap<String, Vec<Sample>>,
    /// The simulated time of each frame any entity was logged at, in seconds.
    pub sim_time: BTreeMap<i64, f64>,
    /// The cloth's triangles (static), if stored.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the file ends in the middle of a message (cut short by a crash
    /// or a kill): everything before it was read.
    pub truncated: bool,
}

/// One value of a scalar series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The frame it was logged at.
    pub frame: i64,
    /// The value.
    pub value: f64,
}

impl Recording {
    /// The frames at which `path` was logged, in order (empty if never).
    pub fn frames(&self, path: &str) -> Vec<i64> {
        self.entities
            .get(path)
            .map(|e| e.frames.iter().copied().collect())
            .unwrap_or_default()
    }
}

/// The main array of a chunk's rows: the first component whose name is one
/// of these, else the first component.
const MAIN: [&str; 5] = [
    ":positions",
    ":vectors",
    ":scalars",
    ":vertex_positions",
    ":text",
];

/// Reads a `.rrd` file. A file cut short (by a crash) reads up to its last
/// complete message.
pub fn read(path: &Path) -> Result<Recording, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut decoder = DecoderApp::decode_eager(std::io::BufReader::new(file))
        .map_err(|e| format!("{}: not a Rerun recording: {e}", path.display()))?;
    let mut out = Recording::default();
    let mut any = false;
    for msg in decoder.by_ref() {
        let msg = match msg {
            Ok(m) => m,
            // A truncated tail: keep what was read.
            Err(_) => {
                out.truncated = true;
                break;
            }
        };
        any = true;
        let LogMsg::ArrowMsg(store, arrow) = msg else {
            continue;
        };
        if !store.is_recording() {
            continue;
        }
        let chunk = Chunk::from_arrow_msg(&arrow)
            .map_err(|e| format!("{}: bad chunk: {e}", path.display()))?;
        absorb(&mut out, &chunk);
    }
    // A file closed properly ends with a footer; one cut short has none.
    if decoder.rrd_manifests().map_or(true, |m| m.is_empty()) {
        out.truncated = true;
    }
    if !any {
        return Err(format!(
            "{}: not a Rerun recording (no message could be decoded)",
            path.display()
        ));
    }
    for series in out.scalars.values_mut() {
        series.sort_by_key(|s| s.frame);
    }
    Ok(out)
}

fn absorb(out: &mut Recording, chunk: &Chunk) {
    let path = chunk
        .entity_path()
        .to_string()
        .trim_start_matches('/')
        .to_string();
    let rows = chunk.num_rows();
    let frames: Vec<i64> = chunk
        .timelines()
        .get(&paths::FRAME.into())
        .map(|c| c.times_raw().to_vec())
        .unwrap_or_else(|| vec![-1; rows]);
    let info = out.entities.entry(path.clone()).or_default();
    info.is_static |= chunk.is_static();
    info.frames.extend(frames.iter().filter(|f| **f >= 0));
    if let Some(c) = chunk.timelines().get(&paths::SIM_TIME.into()) {
        info.sim_times.extend(c.times_raw().iter().copied());
        for (frame, t) in frames.iter().zip(c.times_raw()) {
            if *frame >= 0 {
                out.sim_time.insert(*frame, *t as f64 * 1e-9);
            }
        }
    }
    let components = chunk.components();
    let mut main = None;
    for (ident, col) in components.iter() {
        let name = ident.as_str().to_string();
        let preferred = MAIN.iter().any(|m| name.ends_with(m));
        if main.is_none() || preferred {
            main = Some(col);
        }
        info.components.insert(name);
        if preferred {
            break;
        }
    }
    if let Some(col) = main.filter(|_| !chunk.is_static()) {
        use rerun::external::arrow::array::Array as _;
        let offsets = col.list_array.offsets();
        for r in 0..col.list_array.len() {
            info.lengths.push((offsets[r + 1] - offsets[r]) as usize);
        }
    }
    for (ident, _) in components.iter() {
        info.components.insert(ident.as_str().to_string());
    }

    let texts = |descriptor: rerun::ComponentIdentifier| -> Vec<String> {
        chunk
            .iter_component::<rerun::components::Text>(descriptor)
            .map(|row| {
                row.first()
                    .map(|t| t.as_str().to_string())
                    .unwrap_or_default()
            })
            .collect()
    };
    match path.as_str() {
        paths::PRESET => out.preset = texts(rerun::TextDocument::descriptor_text().component).pop(),
        paths::SUMMARY => {
            out.summary = texts(rerun::TextDocument::descriptor_text().component).pop()
        }
        paths::PARAMS => out.params.extend(
            frames
                .iter()
                .copied()
                .zip(texts(rerun::TextDocument::descriptor_text().component)),
        ),
        paths::EVENTS => out.events.extend(
            frames
                .iter()
                .copied()
                .zip(texts(rerun::TextLog::descriptor_text().component)),
        ),
        paths::PARTICLES => {
            let positions = chunk.iter_component::<rerun::components::Position3D>(
                rerun::Points3D::descriptor_positions().component,
            );
            for (frame, row) in frames.iter().zip(positions) {
                let row: Vec<[f32; 3]> = row.iter().map(|p| [p.x(), p.y(), p.z()]).collect();
                if out
                    .last_positions
                    .as_ref()
                    .is_none_or(|(f, _)| *frame >= *f)
                {
                    out.last_positions = Some((*frame, row.clone()));
                }
                if *frame >= 0 {
                    out.positions.insert(*frame, row);
                }
            }
        }
        paths::MESH if chunk.is_static() => {
            let rows = chunk.iter_component::<rerun::components::TriangleIndices>(
                rerun::Mesh3D::descriptor_triangle_indices().component,
            );
            for row in rows.filter(|r| !r.is_empty()) {
                out.triangles = row.iter().map(|t| t.0.0).collect();
            }
        }
        p if p.starts_with("metrics/") && !chunk.is_static() => {
            let values = chunk.iter_component::<rerun::components::Scalar>(
                rerun::Scalars::descriptor_scalars().component,
            );
            let series = out.scalars.entry(path.clone()).or_default();
            for (frame, row) in frames.iter().zip(values) {
                if let Some(v) = row.first() {
                    series.push(Sample {
                        frame: *frame,
                        value: v.0.0,
                    });
                }
            }
        }
        _ => {}
    }
}
