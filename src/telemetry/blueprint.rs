//! The default layout: the 3D view with the cloth and its corrections beside
//! plots of violations, strain, the normals against the surface, energy and
//! timings.

use rerun::blueprint::{
    Blueprint, Horizontal, SelectionPanel, Spatial3DView, TextLogView, TimePanel, TimeSeriesView,
    Vertical, components::PanelState,
};

use super::paths;

/// The layout of the desktop debugger: [`default`], with Rerun's selection
/// panel collapsed to give the 3D view its width (the tuning panel shows the
/// selected particle; the selection panel opens from the viewer's top bar).
pub fn desktop() -> Blueprint {
    default().with_selection_panel(SelectionPanel::new().with_state(PanelState::Collapsed))
}

/// The layout a recording opens with.
pub fn default() -> Blueprint {
    Blueprint::new(
        Horizontal::new([
            Vertical::new([
                Spatial3DView::new("Cloth").with_origin(paths::WORLD).into(),
                TextLogView::new("Events").with_origin(paths::EVENTS).into(),
            ])
            .with_row_shares([4.0, 1.0])
            .into(),
            Vertical::new([
                TimeSeriesView::new("Violation per family")
                    .with_origin("metrics/violation")
                    .into(),
                TimeSeriesView::new("Strain")
                    .with_origin("metrics/strain")
                    .into(),
                TimeSeriesView::new("Normals against the surface")
                    .with_origin("metrics/normals")
                    .into(),
                TimeSeriesView::new("Kinetic energy")
                    .with_origin("metrics/energy")
                    .into(),
                TimeSeriesView::new("Timings (ms)")
                    .with_origin("metrics/time")
                    .into(),
            ])
            .into(),
        ])
        .with_column_shares([3.0, 2.0]),
    )
    .with_time_panel(TimePanel::new().with_timeline(paths::SIM_TIME))
    .with_auto_views(false)
}
