//! The default layout: the 3D view with the cloth and its corrections beside
//! plots of violations, self-collision's crossings, strain, the normals
//! against the surface, energy and timings.
//!
//! [`send_default`] writes what a recording opens with (`weft record`,
//! `weft sweep`): [`default`]'s views, the plots without legends.
//! The desktop debugger sends [`send_desktop`]: the same views, with the
//! viewer's side panels collapsed and view settings that Rerun's Rust
//! blueprint builder has no setter for (the 3D view's camera following the
//! cloth, small particles, the plots' legends), written into the same
//! blueprint.

use rerun::blueprint::{
    Blueprint, BlueprintActivation, BlueprintPanel, ContainerLike, Horizontal, SelectionPanel,
    Spatial3DView, TextLogView, TimePanel, TimeSeriesView, Vertical, components::PanelState,
};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    EntityBehavior, EyeControls3D, PlotLegend,
};
use rerun::log::LogMsg;
use rerun::{RecordingStream, RecordingStreamResult};

use super::paths;

/// The layout a recording opens with: its views (the legends, which
/// Rerun's builder cannot hide, are hidden by [`send_default`]).
pub fn default() -> Blueprint {
    layout(Views::new(false)).0
}

/// The views of the layout, each with the path of its blueprint entity.
struct Views {
    cloth: ContainerLike,
    plots: Vec<ContainerLike>,
}

impl Views {
    /// The views; for the desktop debugger, the particles drawn small.
    fn new(desktop: bool) -> Self {
        let plot = |name: &str, origin: &str| TimeSeriesView::new(name).with_origin(origin);
        let mut cloth = Spatial3DView::new("Cloth").with_origin(paths::WORLD);
        if desktop {
            cloth = cloth.with_override(
                paths::PARTICLES,
                &rerun::Points3D::update_fields()
                    .with_radii([rerun::Radius::new_ui_points(PARTICLE_UI_RADIUS)]),
            );
        }
        Views {
            cloth: cloth.into(),
            plots: vec![
                plot("Violation per family", "metrics/violation")
                    .with_contents([
                        "$origin/**".to_string(),
                        format!("- {}", paths::SELF_CROSSINGS),
                    ])
                    .into(),
                plot("Crossing edges", paths::SELF_CROSSINGS).into(),
                plot("Strain", "metrics/strain").into(),
                plot("Normals against the surface", "metrics/normals").into(),
                plot("Kinetic energy", "metrics/energy").into(),
                plot("Timings (ms)", "metrics/time").into(),
            ],
        }
    }
}

/// The blueprint entity path (`view/{id}`) of a view.
fn view_path(view: &ContainerLike) -> Option<String> {
    match view {
        ContainerLike::View(v) => Some(v.blueprint_path().to_string()),
        _ => None,
    }
}

/// What the desktop debugger's layout adds to the views' settings, by
/// blueprint path.
struct Extras {
    cloth: String,
    plots: Vec<String>,
}

/// The layout of `views`, and the blueprint paths of its views.
fn layout(views: Views) -> (Blueprint, Extras) {
    let extras = Extras {
        cloth: view_path(&views.cloth).unwrap_or_default(),
        plots: views.plots.iter().filter_map(view_path).collect(),
    };
    let blueprint = Blueprint::new(
        Horizontal::new([
            Vertical::new([
                views.cloth,
                TextLogView::new("Events").with_origin(paths::EVENTS).into(),
            ])
            .with_row_shares([4.0, 1.0])
            .into(),
            Vertical::new(views.plots).into(),
        ])
        .with_column_shares([3.0, 2.0]),
    )
    .with_time_panel(TimePanel::new().with_timeline(paths::SIM_TIME))
    .with_auto_views(false);
    (blueprint, extras)
}

/// The entities of the 3D view a click does not select in the desktop
/// debugger, so that a click on the cloth reaches its mesh and particles:
/// the arrows drawn over it, the bodies, the colliders and a branch's
/// parent drawn as a ghost (and the normals, hidden there).
pub const NOT_PICKED: [&str; 5] = [
    "world/cloth/framing",
    "world/corrections",
    "world/bodies",
    "world/colliders",
    "world/ghost",
];

/// A particle's radius in the desktop debugger's 3D view, in UI points:
/// small dots on the shaded mesh, whatever the distance.
pub const PARTICLE_UI_RADIUS: f32 = 1.5;

/// The desktop debugger's layout: [`default`]'s views with Rerun's side
/// panels collapsed (the recording list and blueprint tree on the left,
/// the selection on the right, the streams under the timeline: each opens
/// from the viewer's top bar), and in the 3D view
///
/// - the camera following the cloth, [`super::framing::DISTANCE`] times
///   its radius away, by tracking [`paths::FRAMING`] (until you move the
///   camera);
/// - the particles drawn [`PARTICLE_UI_RADIUS`] points wide;
/// - clicks passing through the arrows, bodies, colliders and the ghost
///   ([`NOT_PICKED`]);
/// - the element normals ([`paths::NORMALS`]) hidden (their ticks pattern
///   the mesh; the view's entity tree shows them again);
///
/// and the plots without their legends, which covered the curves (hovering
/// a curve names it; each view's settings show the legend again).
pub fn desktop_messages(
    application_id: &rerun::ApplicationId,
    activation: BlueprintActivation,
) -> RecordingStreamResult<Vec<LogMsg>> {
    messages(application_id, activation, true)
}

/// The messages of [`default`]'s layout, with the plots' legends hidden
/// (or, for the desktop debugger, of [`desktop_messages`]'s), ending with
/// the activation command.
fn messages(
    application_id: &rerun::ApplicationId,
    activation: BlueprintActivation,
    desktop: bool,
) -> RecordingStreamResult<Vec<LogMsg>> {
    let (mut blueprint, extras) = layout(Views::new(desktop));
    if desktop {
        blueprint = blueprint
            .with_blueprint_panel(BlueprintPanel::new().with_state(PanelState::Collapsed))
            .with_selection_panel(SelectionPanel::new().with_state(PanelState::Collapsed))
            .with_time_panel(
                TimePanel::new()
                    .with_timeline(paths::SIM_TIME)
                    .with_state(PanelState::Collapsed),
            );
    }
    // The blueprint's messages, as Rerun's builder writes them.
    let (mem, storage) = rerun::RecordingStreamBuilder::new(application_id.clone()).memory()?;
    blueprint.send(&mem, activation)?;
    let mut msgs = Vec::new();
    let mut activate = None;
    for msg in storage.take() {
        match msg {
            LogMsg::BlueprintActivationCommand(cmd) => activate = Some(cmd),
            m if m.store_id().is_blueprint() => msgs.push(m),
            _ => {}
        }
    }
    let Some(activate) = activate else {
        return Ok(msgs);
    };
    // The settings the builder has no setter for, into the same blueprint.
    let (bp, extra) = rerun::RecordingStreamBuilder::new(application_id.clone())
        .recording_id(activate.blueprint_id.recording_id().clone())
        .blueprint()
        .memory()?;
    bp.set_time_sequence("blueprint", 0);
    if desktop {
        bp.log(
            format!("{}/EyeControls3D", extras.cloth),
            &EyeControls3D::new().with_tracking_entity(paths::FRAMING),
        )?;
        for entity in NOT_PICKED {
            bp.log(
                format!(
                    "{}/ViewContents/overrides/{entity}/visualizers",
                    extras.cloth
                ),
                &EntityBehavior::new().with_interactive(false),
            )?;
        }
        bp.log(
            format!(
                "{}/ViewContents/overrides/{}/visualizers",
                extras.cloth,
                paths::NORMALS
            ),
            &EntityBehavior::new()
                .with_interactive(false)
                .with_visible(false),
        )?;
    }
    for plot in &extras.plots {
        bp.log(
            format!("{plot}/PlotLegend"),
            &PlotLegend::new().with_visible(false),
        )?;
    }
    msgs.extend(
        extra
            .take()
            .into_iter()
            .filter(|m| matches!(m, LogMsg::ArrowMsg(..))),
    );
    msgs.push(LogMsg::BlueprintActivationCommand(activate));
    Ok(msgs)
}

/// Sends [`desktop_messages`] into `rec`.
pub fn send_desktop(
    rec: &RecordingStream,
    activation: BlueprintActivation,
) -> RecordingStreamResult<()> {
    send(rec, activation, true)
}

/// Sends [`default`]'s layout into `rec` as its default (what a viewer
/// opens it with), with the plots' legends hidden: what `weft record` and
/// `weft sweep` write at the start of a recording.
pub fn send_default(rec: &RecordingStream) -> RecordingStreamResult<()> {
    let activation = BlueprintActivation {
        make_active: false,
        make_default: true,
    };
    send(rec, activation, false)
}

fn send(
    rec: &RecordingStream,
    activation: BlueprintActivation,
    desktop: bool,
) -> RecordingStreamResult<()> {
    if !rec.is_enabled() {
        return Ok(());
    }
    let app = rec
        .store_info()
        .map(|i| i.application_id().clone())
        .unwrap_or_else(|| "weft".into());
    let mut msgs = messages(&app, activation, desktop)?;
    if let Some(LogMsg::BlueprintActivationCommand(cmd)) = msgs.pop() {
        rec.send_blueprint(msgs, cmd);
    }
    Ok(())
}
