//! The tuning: the part of a scene that may change while it runs.
//!
//! A [`Tuning`] is the solver parameters and the wind, and the debugger's
//! pull on a particle while there is one. The panel edits one, the session
//! applies it from the next step ([`Scene::set_tuning`]), a recording logs
//! it whenever it changes, and `weft replay` applies the logged ones at
//! their frames. Everything else in a preset (the cloth, bodies, colliders)
//! needs a new scene.
//!
//! The pull ([`Pull`]: a hand on the cloth, the debugger's Ctrl-drag) is
//! no preset key: a preset never has one, [`Tuning::of`] gives none and
//! [`Tuning::apply_to`] leaves it out. It is part of the tuning so that
//! grabbing, moving and letting go are changes at their frames like any
//! other, recorded, replayed and re-applied when branching. It is written
//! only while there is one, so a recording without a pull stores exactly
//! what it did before pulls existed. Its particle is checked against the
//! cloth by the scene ([`Scene::set_tuning`]), which knows how many there
//! are.
//!
//! ```
//! use weft_cloth::scene::{Tuning, load};
//! use weft_cloth::solver::Family;
//!
//! let mut preset = load::load("flag_on_car", &[]).unwrap().preset;
//! let mut tuning = Tuning::of(&preset);
//! tuning.solver.weights[Family::Normality] = 0.35;
//! tuning.validate().unwrap();
//! tuning.apply_to(&mut preset);
//! assert_eq!(preset.solver.weights[Family::Normality], 0.35);
//! assert!(Tuning::is_live("solver.weights.normality"));
//! assert!(!Tuning::is_live("cloth.weft"));
//! ```
//!
//! [`Scene::set_tuning`]: super::Scene::set_tuning

use serde::{Deserialize, Serialize};

use super::preset::{Preset, WindSection};
use crate::solver::{Params, Pull, Range, RangeError};

/// What can change while a scene runs, and is recorded whenever it does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// Solver parameters.
    pub solver: Params,
    /// The wind.
    pub wind: WindSection,
    /// A particle pulled towards a point (the debugger's Ctrl-drag), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pull: Option<Pull>,
}

/// Where each of the tuning's fields lives in a preset: the preset keys
/// under these apply live. A test checks that every field but the pull
/// (which no preset has) has its row.
const IN_PRESET: [(&str, &str); 2] = [("solver", "solver"), ("wind", "environment.wind")];

/// Mean wind speed, per component.
const WIND_VELOCITY: Range = Range::components(1e3).unit(" m/s");
/// Peak gust speed.
const WIND_GUST: Range = Range::new(0.0, 1e3).unit(" m/s");
/// Typical time between gusts.
const WIND_GUST_PERIOD: Range = Range::new(0.0, 1e4).unit(" s");
/// Peak swing of the wind's direction.
const WIND_SWAY: Range = Range::new(0.0, 180.0).unit("°");

impl Tuning {
    /// The tuning a preset describes (no pull).
    pub fn of(preset: &Preset) -> Self {
        Self {
            solver: preset.solver,
            wind: preset.environment.wind,
            pull: None,
        }
    }

    /// Writes this tuning into `preset` (all but the pull, which is no
    /// preset key).
    pub fn apply_to(&self, preset: &mut Preset) {
        preset.solver = self.solver;
        preset.environment.wind = self.wind;
    }

    /// Checks the solver parameters, the wind and the pull's target and
    /// stiffness; the first problem, under its key (`solver.dt`,
    /// `environment.wind.gust`, `pull.stiffness`). The pull's particle is
    /// checked by the scene, against its cloth.
    pub fn validate(&self) -> Result<(), RangeError> {
        self.solver.validate().map_err(|e| e.under("solver."))?;
        let w = &self.wind;
        WIND_VELOCITY.check_each("environment.wind.velocity", &w.velocity.to_array())?;
        WIND_GUST.check("environment.wind.gust", w.gust)?;
        WIND_GUST_PERIOD.check("environment.wind.gust_period", w.gust_period)?;
        WIND_SWAY.check("environment.wind.sway", w.sway)?;
        match &self.pull {
            Some(p) => p.validate(p.particle + 1),
            None => Ok(()),
        }
    }

    /// The preset sections that are the tuning (`solver`, `environment.wind`).
    pub fn sections() -> impl Iterator<Item = &'static str> {
        IN_PRESET.iter().map(|(_, path)| *path)
    }

    /// Whether a change to the preset key `key` (as written in `--set`)
    /// applies to a running scene, or needs a new one.
    pub fn is_live(key: &str) -> bool {
        Self::sections().any(|s| {
            key == s
                || key
                    .strip_prefix(s)
                    .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_has_its_place_in_a_preset() {
        let preset = crate::scene::load::load("windy_flag", &[]).unwrap().preset;
        let table = toml::Table::try_from(Tuning::of(&preset)).unwrap();
        let fields: Vec<&str> = table.keys().map(String::as_str).collect();
        let mapped: Vec<&str> = IN_PRESET.iter().map(|(field, _)| *field).collect();
        assert_eq!(
            fields, mapped,
            "a Tuning field without its row in IN_PRESET"
        );
        // And each row names the preset section that holds that field.
        let whole = toml::Table::try_from(&preset).unwrap();
        for (field, path) in IN_PRESET {
            let mut at = toml::Value::Table(whole.clone());
            for key in path.split('.') {
                at = at.get(key).cloned().unwrap();
            }
            assert_eq!(Some(&at), table.get(field), "{path}");
        }
    }

    #[test]
    fn live_keys_are_the_tuning_sections() {
        for key in [
            "solver.dt",
            "solver.weights.stretch",
            "environment.wind.gust",
        ] {
            assert!(Tuning::is_live(key), "{key}");
        }
        for key in [
            "cloth.weft",
            "environment.gravity",
            "solverx",
            "environment.windy",
        ] {
            assert!(!Tuning::is_live(key), "{key}");
        }
    }

    #[test]
    fn the_wind_is_checked_like_a_preset_value() {
        let mut t = Tuning::of(&crate::scene::load::load("windy_flag", &[]).unwrap().preset);
        t.wind.gust = -1.0;
        let e = t.validate().unwrap_err();
        assert_eq!(e.key, "environment.wind.gust");
        t.wind.gust = 0.0;
        t.wind.velocity.x = f32::NAN;
        assert!(t.validate().unwrap_err().not_finite);
    }

    #[test]
    fn a_scene_refuses_a_bad_wind_and_keeps_its_tuning() {
        let preset = crate::scene::load::load("windy_flag", &[]).unwrap().preset;
        let mut scene = crate::scene::Scene::new(&preset).unwrap();
        let before = scene.tuning();
        let mut bad = before;
        bad.wind.sway = 400.0;
        bad.solver.weights[crate::solver::Family::Normality] = 0.3;
        let e = scene.set_tuning(&bad).unwrap_err();
        assert_eq!(e.key, "environment.wind.sway");
        assert_eq!(scene.tuning(), before, "nothing applied");
    }
}
