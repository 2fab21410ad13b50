//! The comparison recording: every run's metrics overlaid in the same plots
//! (one colour per run, each series named after its run), and the cloths in
//! one 3D view, side by side along an axis or overlaid, on the shared
//! `frame` and `sim_time` timelines.
//!
//! | path | what |
//! |---|---|
//! | `world/{run}/particles`, `world/{run}/mesh` | each run's cloth, the `k`-th offset by `k · spacing` along the axis (0 with `--overlay`) |
//! | `metrics/strain/{run}` | largest edge strain |
//! | `metrics/energy/{run}` | kinetic energy |
//! | `metrics/flipped/{run}` | the share of elements facing against the surface |
//! | `metrics/violation/{family}/{run}` | largest violation per family |
//! | `metrics/difference/{run}` | largest particle distance to the first run (m) |
//! | `events/{run}` | each run's events: tuning changes, failures |
//! | `runs` | the text report of `weft compare` (static) |

use glam::Vec3;
use rerun::RecordingStream;
use rerun::blueprint::{
    Blueprint, Grid, Horizontal, Spatial3DView, TextDocumentView, TextLogView, TimePanel,
    TimeSeriesView, Vertical,
};

use super::{RunData, incomparable, state_diff};
use crate::solver::Family;
use crate::telemetry::paths;

/// A colour per run, in order (repeats after ten).
const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// The colour of the `k`-th run.
pub fn colour(k: usize) -> rerun::Color {
    let [r, g, b] = PALETTE[k % PALETTE.len()];
    rerun::Color::from_rgb(r, g, b)
}

/// A run's name as one entity-path part: letters, digits, `_` and `-`.
pub fn entity_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// How the cloths are placed in the 3D view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// Side by side along this unit axis (`None`: [`auto_axis`]), spaced by
    /// the largest extent any run's cloth reaches along it.
    SideBySide(Option<Vec3>),
    /// On top of each other.
    Overlay,
}

/// The largest extent along `axis` of any run's particles, at its first
/// logged frame (`first`) or over all its logged frames.
fn extent(runs: &[RunData], axis: Vec3, first: bool) -> f32 {
    runs.iter()
        .map(|r| {
            let frames = r
                .rec
                .positions
                .values()
                .take(if first { 1 } else { usize::MAX });
            let (lo, hi) = frames
                .flatten()
                .map(|p| Vec3::from(*p).dot(axis))
                .fold((f32::MAX, f32::MIN), |(l, h), v| (l.min(v), h.max(v)));
            if hi >= lo { hi - lo } else { 0.0 }
        })
        .fold(0.0, f32::max)
}

/// The axis the cloths are set apart along by default: of the two axes the
/// cloth spans at its start (the third being closest to its normal), the one
/// along which the cloths move least over the run, so that they stay apart
/// at every frame (a flag on a car driving along x is set apart along z).
pub fn auto_axis(runs: &[RunData]) -> Vec3 {
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let normal = axes
        .iter()
        .copied()
        .min_by(|a, b| extent(runs, *a, true).total_cmp(&extent(runs, *b, true)))
        .unwrap_or(Vec3::Z);
    axes.into_iter()
        .filter(|a| *a != normal)
        .min_by(|a, b| extent(runs, *a, false).total_cmp(&extent(runs, *b, false)))
        .unwrap_or(Vec3::Y)
}

/// The layout the comparison opens with.
pub fn blueprint(runs: &[RunData]) -> Blueprint {
    let mut plots = vec![
        TimeSeriesView::new("Max strain")
            .with_origin("metrics/strain")
            .into(),
        TimeSeriesView::new("Kinetic energy (J)")
            .with_origin("metrics/energy")
            .into(),
        TimeSeriesView::new("Elements facing against the surface (share)")
            .with_origin("metrics/flipped")
            .into(),
    ];
    for f in Family::ALL {
        plots.push(
            TimeSeriesView::new(format!("Max violation: {}", f.name()))
                .with_origin(format!("metrics/violation/{}", f.name()))
                .into(),
        );
    }
    if runs.len() > 1 {
        plots.push(
            TimeSeriesView::new(format!("Largest particle distance to {} (m)", runs[0].name))
                .with_origin("metrics/difference")
                .into(),
        );
    }
    Blueprint::new(
        Horizontal::new([
            Vertical::new([
                Spatial3DView::new("Cloths")
                    .with_origin(paths::WORLD)
                    .into(),
                Horizontal::new([
                    TextLogView::new("Events").with_origin(paths::EVENTS).into(),
                    TextDocumentView::new("Comparison")
                        .with_origin("runs")
                        .into(),
                ])
                .into(),
            ])
            .with_row_shares([3.0, 1.0])
            .into(),
            Grid::new(plots).with_grid_columns(2).into(),
        ])
        .with_column_shares([1.0, 1.0]),
    )
    .with_time_panel(TimePanel::new().with_timeline(paths::SIM_TIME))
    .with_auto_views(false)
}

/// Opens the comparison's stream: a file, or a viewer.
pub fn open(
    runs: &[RunData],
    save: Option<&std::path::Path>,
    connect: Option<&str>,
) -> anyhow::Result<RecordingStream> {
    let builder =
        rerun::RecordingStreamBuilder::new("weft-compare").with_default_blueprint(blueprint(runs));
    if let Some(path) = save {
        return builder.save(path).map_err(|e| {
            anyhow::anyhow!("cannot write the comparison to {}: {e}", path.display())
        });
    }
    let url = connect.unwrap_or(crate::telemetry::DEFAULT_VIEWER);
    let rec = builder
        .connect_grpc_opts(url.to_string())
        .map_err(|e| anyhow::anyhow!("cannot connect to a Rerun viewer at {url}: {e}"))?;
    rec.flush_with_timeout(std::time::Duration::from_secs(10))
        .map_err(|e| anyhow::anyhow!("could not reach a Rerun viewer at {url} ({e}); start one with `rerun`, or write a file with --save FILE.rrd"))?;
    Ok(rec)
}

fn set_time(rec: &RecordingStream, run: &RunData, frame: i64) {
    rec.set_time_sequence(paths::FRAME, frame);
    if let Some(t) = run.rec.sim_time.get(&frame) {
        rec.set_duration_secs(paths::SIM_TIME, *t);
    }
}

/// Logs the comparison of `runs` into `rec`, with `report` as its text.
pub fn write(
    rec: &RecordingStream,
    runs: &[RunData],
    placement: Placement,
    report: &str,
) -> anyhow::Result<()> {
    rec.log_static(paths::WORLD, &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
    rec.log_static(
        "runs",
        &rerun::TextDocument::new(report).with_media_type(rerun::MediaType::plain_text()),
    )?;
    let names = unique_entity_names(runs);
    let spacing = match placement {
        Placement::Overlay => Vec3::ZERO,
        Placement::SideBySide(axis) => {
            let axis = axis.unwrap_or_else(|| auto_axis(runs));
            axis * (extent(runs, axis, false) * 1.1 + 0.2)
        }
    };
    for (k, (run, name)) in runs.iter().zip(&names).enumerate() {
        let c = colour(k);
        let offset = spacing * k as f32;
        let style = |series: String| {
            rec.log_static(
                series,
                &rerun::SeriesLines::new()
                    .with_colors([c])
                    .with_names([run.name.clone()]),
            )
        };
        style(format!("metrics/strain/{name}"))?;
        style(format!("metrics/energy/{name}"))?;
        style(format!("metrics/flipped/{name}"))?;
        for f in Family::ALL {
            style(format!("metrics/violation/{}/{name}", f.name()))?;
        }
        let series = [
            (paths::STRAIN.to_string(), format!("metrics/strain/{name}")),
            (paths::ENERGY.to_string(), format!("metrics/energy/{name}")),
            (
                paths::NORMALS_FLIPPED.to_string(),
                format!("metrics/flipped/{name}"),
            ),
        ]
        .into_iter()
        .chain(Family::ALL.iter().map(|f| {
            (
                paths::violation(*f, "max"),
                format!("metrics/violation/{}/{name}", f.name()),
            )
        }));
        for (from, to) in series {
            for s in run.rec.scalars.get(&from).into_iter().flatten() {
                set_time(rec, run, s.frame);
                rec.log(to.as_str(), &rerun::Scalars::single(s.value))?;
            }
        }
        for (frame, x) in &run.rec.positions {
            set_time(rec, run, *frame);
            let moved: Vec<Vec3> = x.iter().map(|p| Vec3::from(*p) + offset).collect();
            rec.log(
                format!("world/{name}/particles"),
                &rerun::Points3D::new(moved.iter().copied())
                    .with_colors([c])
                    .with_radii([0.006]),
            )?;
            if !run.rec.triangles.is_empty() {
                rec.log(
                    format!("world/{name}/mesh"),
                    &rerun::Mesh3D::new(moved.iter().copied())
                        .with_triangle_indices(run.rec.triangles.iter().copied())
                        .with_albedo_factor(rerun::Rgba32::from_unmultiplied_rgba(
                            c.0.to_array()[0],
                            c.0.to_array()[1],
                            c.0.to_array()[2],
                            160,
                        )),
                )?;
            }
        }
        for (frame, text) in &run.rec.events {
            set_time(rec, run, *frame);
            rec.log(
                format!("events/{name}"),
                &rerun::TextLog::new(format!("{}: {text}", run.name))
                    .with_level(rerun::TextLogLevel::INFO),
            )?;
        }
        if k > 0 && incomparable(&runs[0], run).is_none() {
            let path = format!("metrics/difference/{name}");
            style(path.clone())?;
            for (frame, d) in state_diff(&runs[0], run).per_frame {
                set_time(rec, run, frame);
                rec.log(path.as_str(), &rerun::Scalars::single(d as f64))?;
            }
        }
    }
    rec.flush_blocking()?;
    Ok(())
}

/// Entity-path names for the runs, unique.
pub fn unique_entity_names(runs: &[RunData]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in runs {
        let base = entity_name(&r.name);
        let mut name = base.clone();
        let mut k = 2;
        while out.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        out.push(name);
    }
    out
}
