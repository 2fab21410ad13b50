//! Replaying a recording: re-run the preset and the parameter changes it
//! stores, and check that the state comes out bit for bit the same.

use std::path::Path;

use crate::scene::{Scene, Tuning, load};
use crate::solver::Family;
use crate::telemetry::read;

/// What a replay found.
#[derive(Clone, Debug, PartialEq)]
pub struct Replayed {
    /// Frames re-run.
    pub frames: u64,
    /// Digest of the replayed final state.
    pub digest: String,
    /// Digest the recording stored, if it finished.
    pub recorded_digest: Option<String>,
    /// Whether the particles matched bit for bit at the last logged frame
    /// (`None` when the recording has no particles).
    pub positions_match: Option<bool>,
    /// Parameter changes applied.
    pub changes: usize,
    /// Whether the file was cut short (what it holds was still compared).
    pub truncated: bool,
    /// Whether the recording was made by a weft from before the floating
    /// origin (its summary names no `final_origin`): that weft computed in
    /// world coordinates, with other rounding, so this one cannot
    /// reproduce it bit for bit.
    pub before_floating_origin: bool,
    /// The solver revision that made the recording, if it names one
    /// ([`crate::solver::REVISION`]).
    pub solver_revision: Option<u32>,
}

impl Replayed {
    /// Why a recording that did not reproduce could not, as far as can be
    /// told: the weft that made it computed otherwise. `None` when it was
    /// made by this solver revision (then a mismatch is a fault of
    /// determinism).
    pub fn why_not(&self) -> Option<String> {
        let now = crate::solver::REVISION;
        if self.before_floating_origin {
            Some("it was made by a weft from before the floating origin, which simulated in world coordinates with other rounding".into())
        } else {
            match self.solver_revision {
                Some(then) if then == now => None,
                Some(then) => Some(format!(
                    "it was made by solver revision {then}, and this weft's solver, revision {now}, steps the same preset and parameters differently"
                )),
                None => Some(format!(
                    "it was made by a weft from before recordings named their solver revision, whose solver may step the same preset and parameters differently from this one (revision {now})"
                )),
            }
        }
    }

    /// Whether everything that could be compared matched.
    pub fn reproduced(&self) -> bool {
        self.recorded_digest
            .as_ref()
            .is_none_or(|d| *d == self.digest)
            && self.positions_match != Some(false)
    }
}

/// Parameters as a recording stores them. A recording stores every
/// family's weight; one made before a family existed has none for it, and
/// ran without it, so that family's weight is 0, not its default (0.99 for
/// facing).
pub(crate) fn stored_tuning(text: &str) -> Result<Tuning, toml::de::Error> {
    let table: toml::Table = toml::from_str(text)?;
    let weights = table
        .get("solver")
        .and_then(|s| s.get("weights"))
        .and_then(|w| w.as_table());
    let missing: Vec<Family> = Family::ALL
        .into_iter()
        .filter(|f| weights.is_some_and(|w| !w.contains_key(f.name())))
        .collect();
    let mut tuning: Tuning = table.try_into()?;
    for family in missing {
        tuning.solver.weights[family] = 0.0;
    }
    Ok(tuning)
}

/// Why a recording could not be replayed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] read::ReadError),
    /// It holds no stored preset.
    #[error("{}: no preset stored (not a weft recording?)", path.display())]
    NoPreset {
        /// The file.
        path: std::path::PathBuf,
    },
    /// The stored preset does not load (with the error's place in it).
    #[error(transparent)]
    Preset(#[from] crate::scene::PresetError),
    /// The stored preset's scene cannot be built.
    #[error(transparent)]
    Setup(#[from] crate::solver::SetupError),
    /// Stored parameters that do not read or do not apply.
    #[error("stored parameters at frame {frame}: {detail}")]
    Parameters {
        /// The frame they took effect at.
        frame: i64,
        /// What was wrong.
        detail: String,
    },
    /// The solver failed while replaying.
    #[error("replay failed at frame {frame}: {source}")]
    Step {
        /// The frame that failed.
        frame: u64,
        /// The failure.
        source: crate::solver::StepError,
    },
}

/// Re-runs the recording at `path`.
pub fn replay(path: &Path) -> Result<Replayed, ReplayError> {
    let rec = read::read(path)?;
    let solver_revision = rec.solver_revision();
    let text = rec
        .preset
        .ok_or_else(|| ReplayError::NoPreset { path: path.into() })?;
    let label = format!("preset stored in {}", path.display());
    let preset = load::parse(&label, &text)?;
    let summary: Option<toml::Table> = rec.summary.as_deref().and_then(|s| s.parse().ok());
    let recorded_frames = summary
        .as_ref()
        .and_then(|s| s.get("frames")?.as_integer())
        .map(|f| f as u64);
    let recorded_digest = summary
        .as_ref()
        .and_then(|s| Some(s.get("final_state")?.as_str()?.to_string()));
    let before_floating_origin = summary
        .as_ref()
        .is_some_and(|s| !s.contains_key("final_origin"));
    let last_logged = rec.last_positions.as_ref().map(|(f, _)| *f as u64);
    let frames = recorded_frames.or(last_logged).unwrap_or(0);

    let mut changes: Vec<(u64, Tuning)> = Vec::new();
    for (frame, text) in &rec.params {
        let tuning = stored_tuning(text).map_err(|e| ReplayError::Parameters {
            frame: *frame,
            detail: e.to_string(),
        })?;
        changes.push((*frame as u64, tuning));
    }
    let mut scene = Scene::new(&preset)?;
    let apply = |scene: &mut Scene, frame: u64| -> Result<(), ReplayError> {
        for (_, p) in changes.iter().filter(|(f, _)| *f == frame) {
            scene.set_tuning(p).map_err(|e| ReplayError::Parameters {
                frame: frame as i64,
                detail: e.to_string(),
            })?;
        }
        Ok(())
    };
    apply(&mut scene, 0)?;
    let mut positions_match = None;
    for frame in 1..=frames {
        apply(&mut scene, frame)?;
        scene
            .step()
            .map_err(|source| ReplayError::Step { frame, source })?;
        if let Some((f, recorded)) = &rec.last_positions
            && *f as u64 == frame
        {
            let x = &*scene.world_positions();
            positions_match = Some(
                x.len() == recorded.len()
                    && x.iter()
                        .zip(recorded)
                        .all(|(a, b)| a.to_array().map(f32::to_bits) == b.map(f32::to_bits)),
            );
        }
    }
    Ok(Replayed {
        frames,
        digest: format!("{:016x}", scene.solver().state().digest()),
        recorded_digest,
        positions_match,
        changes: changes.len().saturating_sub(1),
        truncated: rec.truncated,
        before_floating_origin,
        solver_revision,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_replay_that_differs_says_which_solver_made_the_recording() {
        let rec = read::Recording {
            version: Some("weft 0.1.0 (solver revision 7)".into()),
            ..read::Recording::default()
        };
        assert_eq!(rec.solver_revision(), Some(7));
        let old = read::Recording {
            version: Some("weft 0.1.0".into()),
            ..read::Recording::default()
        };
        assert_eq!(old.solver_revision(), None);
        let this = crate::solver::version();
        assert_eq!(
            crate::solver::revision_of(&this),
            Some(crate::solver::REVISION)
        );

        let now = crate::solver::REVISION;
        let replayed = |solver_revision, before_floating_origin| Replayed {
            frames: 1,
            digest: "a".into(),
            recorded_digest: Some("b".into()),
            positions_match: None,
            changes: 0,
            truncated: false,
            before_floating_origin,
            solver_revision,
        };
        assert_eq!(replayed(Some(now), false).why_not(), None);
        let other = replayed(Some(now + 1), false).why_not().unwrap();
        assert!(
            other.contains(&format!("solver revision {}", now + 1)),
            "{other}"
        );
        assert!(other.contains(&format!("revision {now}")), "{other}");
        let unnamed = replayed(None, false).why_not().unwrap();
        assert!(
            unnamed.contains("before recordings named their solver revision"),
            "{unnamed}"
        );
        let world = replayed(None, true).why_not().unwrap();
        assert!(world.contains("floating origin"), "{world}");
    }

    #[test]
    fn a_family_missing_from_stored_parameters_was_off() {
        let preset = load::load("flag_on_car", &[]).unwrap().preset;
        let text = toml::to_string(&Tuning::of(&preset)).unwrap();
        assert!(text.contains("facing = 0.99"), "{text}");
        // As this build stores them: every weight kept.
        let now = stored_tuning(&text).unwrap();
        assert_eq!(now, Tuning::of(&preset));
        // As a build before facing stored them: facing was off.
        let before: String = text
            .lines()
            .filter(|l| !l.starts_with("facing"))
            .map(|l| format!("{l}\n"))
            .collect();
        let then = stored_tuning(&before).unwrap();
        assert_eq!(then.solver.weights[Family::Facing], 0.0);
        let mut expected = Tuning::of(&preset);
        expected.solver.weights[Family::Facing] = 0.0;
        assert_eq!(then, expected);
    }
}
