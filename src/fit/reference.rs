//! The reference run's features, measured once by re-running its stored
//! preset and cached in `reference.json`.

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::measure::{self, Features, Horizon};
use super::{Fit, FitError, REFERENCE};
use crate::scene::Scene;
use crate::sweep::storage::{file, write_shared};

/// The cache of the reference's features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct CachedReference {
    final_state: String,
    frames: u64,
    /// The lattice as JSON text: compared as text, since a float read back
    /// from JSON may differ from the one written in its last bit.
    lattice: String,
    features: Features,
}

/// The reference's features: re-runs its stored preset for the fit's
/// simulated time (measured like every candidate), or reads them from
/// `dir`'s cache. With `states` (a fit that will run points), on the fitted
/// preset's grid, also its shared states for short horizons (a run of the
/// reference, cached or not); a fit that runs nothing (`--status`, `weft
/// report`) finds the features in the cache without running the reference
/// again (the cache is written the same either way).
pub fn reference_features(
    fit: &Fit,
    dir: &Path,
    states: bool,
) -> Result<(Option<Features>, Option<Arc<Horizon>>), FitError> {
    let Some(r) = &fit.reference else {
        return Ok((None, None));
    };
    let preset = r.run.preset.as_ref().expect("checked in Fit::new");
    let failed = |why: String| FitError::ReferenceRun {
        path: r.run.path.clone(),
        why,
    };
    let frames = Scene::new(preset)
        .map_err(|e| failed(e.to_string()))?
        .frames_in(fit.seconds);
    let same_grid = preset.cloth.weft == fit.start.preset.cloth.weft
        && preset.cloth.warp == fit.start.preset.cloth.warp;
    let path = dir.join(REFERENCE);
    let lattice = serde_json::to_string(&fit.lattice).expect("a lattice serializes");
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(c) = serde_json::from_str::<CachedReference>(&text)
        && c.final_state == r.run.figures.final_state
        && c.frames == frames
        && c.lattice == lattice
    {
        let horizon = if same_grid && states {
            measure::measure_with(preset, &fit.lattice, fit.seconds, true)
                .map_err(|e| failed(e.to_string()))?
                .1
        } else {
            None
        };
        return Ok((Some(c.features), horizon.map(Arc::new)));
    }
    let (features, horizon) = measure::measure_with(preset, &fit.lattice, fit.seconds, same_grid)
        .map_err(|e| failed(e.to_string()))?;
    let cached = CachedReference {
        final_state: r.run.figures.final_state.clone(),
        frames,
        lattice,
        features,
    };
    let json = serde_json::to_string_pretty(&cached).expect("features serialize");
    write_shared(&path, json.as_bytes())?;
    // The search reads what is on disk, so that a fit that computed the
    // features and one that found them agree to the bit.
    let text = std::fs::read_to_string(&path).map_err(file("reading", &path))?;
    let back: CachedReference =
        serde_json::from_str(&text).map_err(|e| failed(format!("{REFERENCE}: {e}")))?;
    Ok((Some(back.features), horizon.map(Arc::new)))
}
