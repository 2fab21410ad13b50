//! Reading recordings back: each recording in a `.rrd` file on its own (by
//! its store id), with its entities, frames, array lengths, and the texts
//! weft stores (preset, parameters, summary, events).
//!
//! Used by `weft replay`, `weft compare` and by tests. The file is decoded with Rerun's
//! decoder into one chunk store per recording, and every question is a query
//! of Rerun's dataframe API (`rerun::dataframe`): which columns an entity
//! has (its schema), and its rows on the `frame` timeline. Texts are read on
//! the SDK's `log_time` timeline, which stamps every log call, so that two
//! events logged at the same frame both come back (a query on `frame` keeps
//! only the latest row per frame).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rerun::dataframe::{
    ChunkStoreConfig, ChunkStoreHandle, EntityPath, EntityPathFilter, QueryEngine, QueryExpression,
    StorageEngine, StoreKind, TimelineName, ViewContentsSelector,
    external::re_chunk_store::{ChunkStore, ColumnDescriptor, StaticColumnSelection},
};
use rerun::external::arrow::{
    array::{Array, ArrayRef, AsArray as _, ListArray},
    compute::cast,
    datatypes::{DataType, Float32Type, Float64Type, Int64Type, UInt32Type},
};
use rerun::external::re_log_encoding::DecoderApp;

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

/// The contents of one recording, as weft wrote them.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// The recording id (one per run).
    pub id: String,
    /// Whether the file ended inside this recording's data (a crash or a
    /// copy cut short): what is here is everything up to the cut.
    pub truncated: bool,
    /// Every entity, by path (without the leading `/`).
    pub entities: BTreeMap<String, EntityInfo>,
    /// The resolved preset.
    pub preset: Option<String>,
    /// The weft that made it (`weft 0.1.0 (solver revision 1)`).
    pub version: Option<String>,
    /// Parameter sets (TOML) by the frame they took effect.
    pub params: Vec<(i64, String)>,
    /// Event messages by frame.
    pub events: Vec<(i64, String)>,
    /// The end-of-run summary, if the run finished.
    pub summary: Option<String>,
    /// Particle positions at the last logged frame.
    pub last_positions: Option<(i64, Vec<[f32; 3]>)>,
    /// Whether the file carries a blueprint (a viewer layout).
    pub blueprint: bool,
    /// The recording's properties as text, by `entity:component` under
    /// `__properties` (`__properties:RecordingInfo:name`,
    /// `__properties/weft:preset`…).
    pub properties: BTreeMap<String, String>,
    /// Particle positions at every logged frame.
    pub positions: BTreeMap<i64, Vec<[f32; 3]>>,
    /// Every scalar series (`metrics/…`), by entity path: one sample per
    /// logged frame, in frame order.
    pub scalars: BTreeMap<String, Vec<Sample>>,
    /// The simulated time, in seconds, of each frame anything was logged at.
    pub sim_time: BTreeMap<i64, f64>,
    /// The cloth's triangles (static), if stored.
    pub triangles: Vec<[u32; 3]>,
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

    /// The solver revision that made it ([`crate::solver::REVISION`]), if
    /// its weft named one.
    pub fn solver_revision(&self) -> Option<u32> {
        crate::solver::revision_of(self.version.as_deref()?)
    }
}

/// The main array of an entity's rows: the first component whose name ends
/// in one of these, else its first component.
const MAIN: [&str; 6] = [
    ":positions",
    ":vectors",
    ":scalars",
    ":vertex_positions",
    ":strips",
    ":text",
];

/// The SDK's own timeline: when each log call was made.
const LOG_TIME: &str = "log_time";

/// Why a `.rrd` file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened.
    #[error("{}: {source}", path.display())]
    Open {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is not a Rerun recording (or not one this Rerun reads).
    #[error("{}: not a Rerun recording{}", path.display(), detail.as_deref().map(|d| format!(": {d}")).unwrap_or_else(|| " (no message could be decoded)".into()))]
    NotARecording {
        /// The file.
        path: PathBuf,
        /// What the decoder said, if anything.
        detail: Option<String>,
    },
    /// Its messages decode but do not make a recording.
    #[error("{}: bad recording: {detail}", path.display())]
    Bad {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        detail: String,
    },
    /// It holds no recording, only (say) a blueprint.
    #[error("{}: holds no recording", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// It holds several recordings where one was expected.
    #[error("{}: holds {} recordings ({}); weft expects one run per file", path.display(), ids.len(), ids.join(", "))]
    Several {
        /// The file.
        path: PathBuf,
        /// The recordings' ids.
        ids: Vec<String>,
    },
}

/// Checks that `path` is a Rerun recording by decoding its first message
/// only (as [`read_all`] would: a file none of whose messages decodes is
/// not one): what `weft view` asks before the window opens.
pub fn check(path: &Path) -> Result<(), ReadError> {
    let file = std::fs::File::open(path).map_err(|source| ReadError::Open {
        path: path.into(),
        source,
    })?;
    let not = |detail| ReadError::NotARecording {
        path: path.into(),
        detail,
    };
    let mut decoder = DecoderApp::decode_eager(std::io::BufReader::new(file))
        .map_err(|e| not(Some(e.to_string())))?;
    match decoder.next() {
        Some(Ok(_)) => Ok(()),
        Some(Err(e)) => Err(not(Some(e.to_string()))),
        None => Err(not(None)),
    }
}

/// Reads the one recording in a `.rrd` file. A file cut short (by a crash)
/// reads up to its last complete message. A file holding several
/// recordings is an error that says how many (use [`read_all`]).
pub fn read(path: &Path) -> Result<Recording, ReadError> {
    let mut all = read_all(path)?;
    match all.len() {
        0 => Err(ReadError::Empty { path: path.into() }),
        1 => Ok(all.remove(0)),
        _ => Err(ReadError::Several {
            path: path.into(),
            ids: all.into_iter().map(|r| r.id).collect(),
        }),
    }
}

/// Reads every recording in a `.rrd` file, in the order they start in it
/// (blueprints are skipped).
pub fn read_all(path: &Path) -> Result<Vec<Recording>, ReadError> {
    let file = std::fs::File::open(path).map_err(|source| ReadError::Open {
        path: path.into(),
        source,
    })?;
    let size = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut decoder = DecoderApp::decode_eager(std::io::BufReader::new(file)).map_err(|e| {
        ReadError::NotARecording {
            path: path.into(),
            detail: Some(e.to_string()),
        }
    })?;
    let mut messages = Vec::new();
    let mut order = Vec::new();
    let mut failed = false;
    let mut decoded = 0;
    let mut blueprint = false;
    for msg in decoder.by_ref() {
        let Ok(msg) = msg else {
            failed = true;
            break;
        };
        decoded += 1;
        let id = msg.store_id().clone();
        blueprint |= id.kind() == StoreKind::Blueprint;
        if id.kind() == StoreKind::Recording {
            if !order.contains(&id) {
                order.push(id);
            }
            messages.push(msg);
        }
    }
    // Cut short: a message that does not decode, bytes left over that make
    // no whole message, or no footer (a stream is closed by its footer).
    let truncated = failed
        || decoder.num_bytes_processed() < size
        || decoder.rrd_manifests().map_or(true, |m| m.is_empty());
    if decoded == 0 {
        return Err(ReadError::NotARecording {
            path: path.into(),
            detail: None,
        });
    }
    let last = order.last().cloned();
    let mut stores =
        ChunkStore::from_log_msgs(&ChunkStoreConfig::ALL_DISABLED, messages).map_err(|e| {
            ReadError::Bad {
                path: path.into(),
                detail: e.to_string(),
            }
        })?;
    order
        .into_iter()
        .filter_map(|id| {
            let store = stores.remove(&id)?;
            let engine = QueryEngine::from_store(ChunkStoreHandle::new(store));
            let mut rec = recording(&engine);
            rec.id = id.recording_id().to_string();
            rec.truncated = truncated && Some(&id) == last.as_ref();
            rec.blueprint = blueprint;
            Some(Ok(rec))
        })
        .collect()
}

/// Everything weft reads from one recording's store.
fn recording(engine: &QueryEngine<StorageEngine>) -> Recording {
    let mut out = Recording::default();
    for entity in
        engine.iter_entity_paths_sorted(&EntityPathFilter::parse_forgiving("+ /__properties/**"))
    {
        let path = entity.to_string().trim_start_matches('/').to_string();
        properties(engine, &entity, &path, &mut out.properties);
    }
    for entity in engine.iter_entity_paths_sorted(&EntityPathFilter::all()) {
        let path = entity.to_string().trim_start_matches('/').to_string();
        if path.starts_with("__") {
            continue; // the SDK's own
        }
        let info = entity_info(engine, &entity, &mut out.sim_time);
        match path.as_str() {
            paths::PRESET => out.preset = texts(engine, &entity, &info).pop().map(|(_, t)| t),
            paths::VERSION => out.version = texts(engine, &entity, &info).pop().map(|(_, t)| t),
            paths::SUMMARY => out.summary = texts(engine, &entity, &info).pop().map(|(_, t)| t),
            paths::PARAMS => out.params = texts(engine, &entity, &info),
            paths::EVENTS => out.events = texts(engine, &entity, &info),
            paths::PARTICLES => {
                out.positions = positions(engine, &entity, &info);
                out.last_positions = out.positions.last_key_value().map(|(f, x)| (*f, x.clone()));
            }
            paths::MESH => out.triangles = triangles(engine, &entity, &info),
            p if p.starts_with("metrics/") => {
                let series = scalars(engine, &entity, &info);
                if !series.is_empty() {
                    out.scalars.insert(path.clone(), series);
                }
            }
            _ => {}
        }
        out.entities.insert(path, info);
    }
    out
}

/// The text-valued recording properties of `entity` (the start time, a
/// timestamp, is left out).
fn properties(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    path: &str,
    out: &mut BTreeMap<String, String>,
) {
    let schema = engine.schema_for_query(&contents(entity));
    for c in &schema.components {
        let name = c.component.as_str();
        let text = static_value(engine, entity, name).and_then(|list| {
            let value = list.value(0);
            let s = value.as_string_opt::<i32>()?;
            (!s.is_empty()).then(|| s.value(0).to_string())
        });
        if let Some(text) = text {
            out.insert(format!("{path}:{name}"), text);
        }
    }
}

/// An entity's columns, and its rows on the `frame` timeline; notes the
/// simulated time of each of its frames in `sim_time`.
fn entity_info(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    sim_time: &mut BTreeMap<i64, f64>,
) -> EntityInfo {
    let mut info = EntityInfo::default();
    let schema = engine.schema_for_query(&contents(entity));
    for c in &schema.components {
        info.is_static |= c.is_static;
        info.components.insert(c.component.as_str().to_string());
    }
    let Some(main) = main_component(&info) else {
        return info;
    };
    let temporal = schema
        .components
        .iter()
        .any(|c| !c.is_static && c.component.as_str() == main);
    for row in rows(engine, entity, paths::FRAME, &[paths::SIM_TIME], &main) {
        info.frames.insert(row.index);
        if let Some(t) = row.times[0] {
            info.sim_times.insert(t);
            sim_time.insert(row.index, t as f64 * 1e-9);
        }
        if temporal && let Some(list) = &row.value {
            info.lengths.push(list.value_length(0) as usize);
        }
    }
    info
}

fn main_component(info: &EntityInfo) -> Option<String> {
    info.components
        .iter()
        .find(|c| MAIN.iter().any(|m| c.ends_with(m)))
        .or_else(|| info.components.first())
        .cloned()
}

/// The texts of a text entity (static, then by frame in logging order).
fn texts(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    info: &EntityInfo,
) -> Vec<(i64, String)> {
    let Some(main) = main_component(info) else {
        return Vec::new();
    };
    let text_of = |list: &ListArray| {
        let value = list.value(0);
        value
            .as_string_opt::<i32>()
            .filter(|s| !s.is_empty())
            .map(|s| s.value(0).to_string())
    };
    let mut out: Vec<(i64, String)> = static_value(engine, entity, &main)
        .and_then(|l| text_of(&l))
        .map(|t| (-1, t))
        .into_iter()
        .collect();
    out.extend(
        rows(engine, entity, LOG_TIME, &[paths::FRAME], &main)
            .into_iter()
            .filter_map(|row| Some((row.times[0].unwrap_or(-1), text_of(row.value.as_ref()?)?))),
    );
    out
}

/// The particle positions at every frame they were logged.
fn positions(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    info: &EntityInfo,
) -> BTreeMap<i64, Vec<[f32; 3]>> {
    let Some(component) = info.components.iter().find(|c| c.ends_with(":positions")) else {
        return BTreeMap::new();
    };
    rows(engine, entity, paths::FRAME, &[], component)
        .into_iter()
        .filter_map(|row| {
            let points = row.value?.value(0);
            let points = points.as_fixed_size_list_opt()?;
            let xyz = points.values().as_primitive_opt::<Float32Type>()?;
            let xyz = xyz.values();
            let positions = (0..points.len())
                .map(|i| [xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]])
                .collect();
            Some((row.index, positions))
        })
        .collect()
}

/// A scalar series: the first value of each row on the `frame` timeline.
fn scalars(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    info: &EntityInfo,
) -> Vec<Sample> {
    let Some(component) = info.components.iter().find(|c| c.ends_with(":scalars")) else {
        return Vec::new();
    };
    rows(engine, entity, paths::FRAME, &[], component)
        .into_iter()
        .filter_map(|row| {
            let values = row.value?.value(0);
            let values = values.as_primitive_opt::<Float64Type>()?;
            (!values.is_empty()).then(|| Sample {
                frame: row.index,
                value: values.value(0),
            })
        })
        .collect()
}

/// The static triangle indices of a mesh.
fn triangles(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    info: &EntityInfo,
) -> Vec<[u32; 3]> {
    let Some(component) = info
        .components
        .iter()
        .find(|c| c.ends_with(":triangle_indices"))
    else {
        return Vec::new();
    };
    let Some(list) = static_value(engine, entity, component) else {
        return Vec::new();
    };
    let value = list.value(0);
    let Some(triples) = value.as_fixed_size_list_opt() else {
        return Vec::new();
    };
    let Some(indices) = triples.values().as_primitive_opt::<UInt32Type>() else {
        return Vec::new();
    };
    let indices = indices.values();
    (0..triples.len())
        .map(|i| [indices[3 * i], indices[3 * i + 1], indices[3 * i + 2]])
        .collect()
}

/// One row of a query: its index value, the values of other timelines, and
/// the component's list (one element), when the row has it.
struct Row {
    index: i64,
    times: Vec<Option<i64>>,
    value: Option<ListArray>,
}

/// A query over one entity (all its components, or only `component`).
fn contents(entity: &EntityPath) -> QueryExpression {
    QueryExpression {
        view_contents: Some(ViewContentsSelector(
            std::iter::once((entity.clone(), None)).collect(),
        )),
        ..Default::default()
    }
}

fn only(entity: &EntityPath, component: &str) -> QueryExpression {
    let components = rerun::ComponentIdentifier::try_new(component)
        .ok()
        .map(|c| std::iter::once(c).collect());
    QueryExpression {
        view_contents: Some(ViewContentsSelector(
            std::iter::once((entity.clone(), components)).collect(),
        )),
        ..Default::default()
    }
}

/// Where the query's output has the timeline `name`.
fn time_column(columns: &[ColumnDescriptor], name: &str) -> Option<usize> {
    columns
        .iter()
        .position(|c| matches!(c, ColumnDescriptor::Time(t) if t.timeline_name().as_str() == name))
}

/// Where the query's output has a component column.
fn component_column(columns: &[ColumnDescriptor]) -> Option<usize> {
    columns
        .iter()
        .position(|c| matches!(c, ColumnDescriptor::Component(_)))
}

/// The entity's rows on the `index` timeline with the values of `also`
/// (other timelines) and of `component`.
fn rows(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    index: &str,
    also: &[&str],
    component: &str,
) -> Vec<Row> {
    let Ok(timeline) = TimelineName::try_new(index) else {
        return Vec::new();
    };
    let query = QueryExpression {
        filtered_index: Some(timeline),
        include_static_columns: StaticColumnSelection::NonStaticOnly,
        ..only(entity, component)
    };
    let columns = engine.selected_schema_for_query(&query);
    let (Some(at), Some(value_at)) = (time_column(&columns, index), component_column(&columns))
    else {
        return Vec::new();
    };
    let also_at: Vec<Option<usize>> = also.iter().map(|t| time_column(&columns, t)).collect();
    let mut out = Vec::new();
    for row in engine.query(query).into_iter() {
        let Some(index) = int64(&row[at]) else {
            continue;
        };
        let times = also_at
            .iter()
            .map(|i| i.and_then(|i| int64(&row[i])))
            .collect();
        let value = row[value_at]
            .as_list_opt::<i32>()
            .filter(|l| !l.is_empty() && !l.is_null(0))
            .cloned();
        out.push(Row {
            index,
            times,
            value,
        });
    }
    out
}

/// The static value of `component`, if it has one.
fn static_value(
    engine: &QueryEngine<StorageEngine>,
    entity: &EntityPath,
    component: &str,
) -> Option<ListArray> {
    let query = QueryExpression {
        include_static_columns: StaticColumnSelection::StaticOnly,
        ..only(entity, component)
    };
    let columns = engine.selected_schema_for_query(&query);
    let value_at = component_column(&columns)?;
    let row = engine.query(query).into_iter().next()?;
    let list = row.get(value_at)?.as_list_opt::<i32>()?;
    (!list.is_empty() && !list.is_null(0)).then(|| list.clone())
}

/// The single value of an index column, as a raw `i64`.
fn int64(column: &ArrayRef) -> Option<i64> {
    if column.is_empty() || column.is_null(0) {
        return None;
    }
    let raw = cast(column, &DataType::Int64).ok()?;
    Some(raw.as_primitive::<Int64Type>().value(0))
}
