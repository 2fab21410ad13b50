//! One run, one Rerun recording: the stream that feeds the viewer (and a
//! file, for a recorded run), opening a run with its name and properties,
//! and a branch's view of its parent.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use rerun::log::LogMsg;
use rerun::sink::FileSink;

use crate::app::history::History;
use crate::app::preset_diff;
use crate::record::{Run, Snapshot};
use crate::scene::{Loaded, Preset, Scene, Tuning, load, preset::TelemetrySettings};
use crate::solver::Family;
use crate::telemetry::{self, Telemetry, blueprint};

use super::{RunInfo, SessionError};

pub(super) type Forward = Arc<dyn Fn(&LogMsg) + Send + Sync>;

/// Forwards every message to `forward`, and to a file while recording.
pub struct Tee {
    forward: Forward,
    file: Mutex<Option<FileSink>>,
}

impl Tee {
    pub(super) fn send(&self, msg: &LogMsg) {
        (self.forward)(msg);
        if let Some(file) = self.file.lock().expect("not poisoned").as_ref() {
            file.send(msg.clone());
        }
    }

    /// Writes the footer and closes the file, if there is one.
    pub(super) fn stop(&self) -> Result<(), SessionError> {
        let file = self.file.lock().expect("not poisoned").take();
        match file {
            Some(f) => f
                .flush_blocking(Duration::from_secs(10))
                .map_err(SessionError::File),
            None => Ok(()),
        }
    }
}

/// A new recording named `name`, whose messages go to `forward` and, from
/// the first one, to `file`. Its blueprint is sent by [`send_blueprint`]
/// once the run's first frame is in.
pub fn stream(
    forward: Forward,
    name: &str,
    file: Option<FileSink>,
) -> (rerun::RecordingStream, Arc<Tee>) {
    let tee = Arc::new(Tee {
        forward,
        file: Mutex::new(file),
    });
    let sink_tee = tee.clone();
    let rec = rerun::RecordingStreamBuilder::new("weft")
        .recording_name(name)
        .batcher_config(telemetry::whole_frames())
        .buffered()
        .expect("a buffered stream always opens");
    rec.set_sink(Box::new(rerun::sink::CallbackSink::new(move |msgs| {
        for m in msgs {
            sink_tee.send(m);
        }
    })));
    (rec, tee)
}

/// Sends weft's layout for `rec`, after what has been logged so far: sent
/// before the first frame, its time panel would name the `sim_time`
/// timeline before the recording has it, and the viewer would warn. The
/// first run's layout is made active; later runs' is the default, so a
/// layout the user has changed stays.
fn send_blueprint(rec: &rerun::RecordingStream, first: bool) -> Result<(), SessionError> {
    rec.flush_blocking()?;
    let activation = rerun::blueprint::BlueprintActivation {
        make_active: first,
        make_default: true,
    };
    Ok(blueprint::send_desktop(rec, activation)?)
}

/// How a new run starts.
pub(super) enum Start {
    /// From frame 0 of this preset (the tuning already in it).
    Fresh(Box<Loaded>),
    /// From a frame of the current run.
    Branch {
        snapshot: Box<Snapshot>,
        history: Box<History>,
        tuning: Tuning,
        /// The parent's plotted values, drawn beside the branch's.
        parent_series: Series,
    },
}

/// A run's plotted values per frame (from frame 1): simulated time, max
/// strain, kinetic energy, each family's max violation (in
/// [`Family::index`] order) and the share of elements turned over.
pub type Series = Vec<(u64, f64, [f32; SERIES_VALUES])>;

/// What a [`Series`] keeps of each frame: max strain, kinetic energy, each
/// family's max violation, and the share of elements turned over.
pub const SERIES_VALUES: usize = 3 + Family::COUNT;

/// A new run of `scene` (or `snapshot`) into a new recording.
pub(super) struct Opened {
    pub(super) run: Run,
    pub(super) history: History,
    pub(super) info: RunInfo,
    pub(super) rec: rerun::RecordingStream,
    pub(super) tee: Arc<Tee>,
}

/// Opens a new recording and starts (or resumes) a run in it.
pub(super) fn open(
    forward: &Forward,
    start: Start,
    preset_name: &str,
    mut info: RunInfo,
    settings: TelemetrySettings,
    base: Option<Preset>,
    file: Option<FileSink>,
) -> Result<Opened, SessionError> {
    let mut parent_series = Series::new();
    let (scene, history, tuning, snapshot) = match start {
        Start::Fresh(loaded) => {
            let scene = Scene::new(&loaded.preset)?;
            (Some((scene, loaded.resolved)), None, None, None)
        }
        Start::Branch {
            snapshot,
            history,
            tuning,
            parent_series: series,
        } => {
            parent_series = series;
            (None, Some(*history), Some(tuning), Some(*snapshot))
        }
    };
    // What the run is, for its name: the preset with the tuning it runs.
    let mut current = match (&scene, &snapshot) {
        (Some((s, _)), _) => s.preset().clone(),
        (_, Some(s)) => s.scene.preset().clone(),
        _ => unreachable!("a run starts from a scene or a snapshot"),
    };
    if let Some(t) = tuning {
        t.apply_to(&mut current);
    }
    let changes = base
        .as_ref()
        .map(|b| preset_diff::describe(b, &current))
        .unwrap_or_default();
    let stem = preset_name
        .trim_end_matches(".toml")
        .rsplit('/')
        .next()
        .unwrap_or(preset_name);
    let mut name = format!("#{} {stem}", info.number);
    if !changes.is_empty() {
        name += &format!(" · {changes}");
    }
    if let Some((parent, _, frame)) = &info.parent {
        name += &format!(" · branch of #{parent} at frame {frame}");
    }
    let (rec, tee) = stream(forward.clone(), &name, file);
    let mut telemetry = Telemetry::new(rec.clone(), settings);
    telemetry.forget();
    // For hovering a particle in the viewer (at level full).
    telemetry.set_particle_values(true);
    // For the camera, which frames the cloth by tracking them.
    telemetry.set_framing(true);
    // The correction arrows cover the cloth: the panel turns them on.
    telemetry.set_arrows(false);
    let mut run = match (scene, snapshot) {
        (Some((scene, resolved)), _) => Run::start(scene, telemetry, preset_name, &resolved),
        (_, Some(snapshot)) => {
            let resolved = load::to_toml(snapshot.scene.preset());
            Run::resume(snapshot, telemetry, preset_name, &resolved)
        }
        _ => unreachable!("a run starts from a scene or a snapshot"),
    }?;
    send_blueprint(&rec, info.number == 1)?;
    if let Some(t) = tuning {
        run.set_tuning(&t)?;
    }
    let history = match history {
        Some(h) => h,
        None => History::new(run.snapshot(), run.scene.tuning()),
    };
    info.recording_id = rec
        .store_info()
        .map(|i| i.store_id.recording_id().to_string())
        .unwrap_or_default();
    info.name = name.clone();
    let mut props = rerun::AnyValues::default()
        .with_component::<rerun::components::Text>("version", [crate::solver::version()])
        .with_component::<rerun::components::Text>("preset", [preset_name.to_string()])
        .with_component::<rerun::components::Text>("run", [info.number.to_string()])
        .with_component::<rerun::components::Text>("changes", [changes]);
    if let Some((number, id, frame)) = &info.parent {
        props = props
            .with_component::<rerun::components::Text>("parent", [id.clone()])
            .with_component::<rerun::components::Text>("parent_run", [number.to_string()])
            .with_component::<rerun::components::Text>("parent_frame", [frame.to_string()]);
    }
    rec.send_property("weft", &props)?;
    if let Some((number, _, _)) = &info.parent {
        log_parent_series(&rec, *number, &parent_series)?;
    }
    Ok(Opened {
        run,
        history,
        info,
        rec,
        tee,
    })
}

/// Logs a parent run's plotted values into a branch's recording, beside the
/// branch's own in the same plots: `metrics/strain/parent`,
/// `metrics/energy/parent`, `metrics/violation/{family}/parent`,
/// `metrics/normals/parent` (the share turned over), thin and grey, named
/// after the parent run.
fn log_parent_series(
    rec: &rerun::RecordingStream,
    parent: u32,
    series: &Series,
) -> rerun::RecordingStreamResult<()> {
    use crate::telemetry::paths;
    let frames: Vec<i64> = series.iter().map(|(f, _, _)| *f as i64).collect();
    let times: Vec<f64> = series.iter().map(|(_, t, _)| *t).collect();
    let mut plots = vec![
        (
            paths::STRAIN.replace("/max", "/parent"),
            0,
            "max".to_string(),
        ),
        (
            paths::ENERGY.replace("/kinetic", "/parent"),
            1,
            "kinetic".to_string(),
        ),
    ];
    for f in Family::ALL {
        plots.push((
            paths::violation(f, "parent"),
            2 + f.index(),
            format!("{} max", f.name()),
        ));
    }
    plots.push((
        paths::NORMALS_FLIPPED.replace("/flipped", "/parent"),
        2 + Family::COUNT,
        "flipped".to_string(),
    ));
    for (path, k, label) in plots {
        rec.log_static(
            path.as_str(),
            &rerun::SeriesLines::new()
                .with_colors([rerun::Color::from_rgb(150, 150, 150)])
                .with_widths([0.75])
                .with_names([format!("{label}, run #{parent}")]),
        )?;
        let values: Vec<f64> = series.iter().map(|(_, _, v)| v[k] as f64).collect();
        rec.send_columns(
            path.as_str(),
            [
                rerun::TimeColumn::new_sequence(paths::FRAME, frames.clone()),
                rerun::TimeColumn::new_duration_secs(paths::SIM_TIME, times.clone()),
            ],
            rerun::Scalars::new(values).columns_of_unit_batches()?,
        )?;
    }
    Ok(())
}
