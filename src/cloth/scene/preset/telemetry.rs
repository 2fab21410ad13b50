//! What a recording carries: the telemetry level, how often frames are
//! logged, correction arrows and particle colours (the `[telemetry]` table).

use std::borrow::Cow;

use serde::{Deserialize, Serialize};

use crate::solver::Family;

/// How much telemetry a recording carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Static data only: no per-frame entities.
    Off,
    /// Scalars and particles.
    Summary,
    /// Everything: normals, mesh, corrections, colliders, bodies.
    #[default]
    Full,
}

/// What particles are coloured by, named in presets as `strain`, `speed`,
/// `correction`, `correction.<family>`, `normal_offset` or `none`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorBy {
    /// Largest strain of the particle's weft and warp edges.
    #[default]
    Strain,
    /// Speed.
    Speed,
    /// Size of the particle's total correction in the last adjust.
    Correction,
    /// Size of one family's correction alone.
    CorrectionOf(Family),
    /// The angle between the element's normal and the surface's (above
    /// 90°: the element faces the other way).
    NormalOffset,
    /// One colour.
    None,
}

impl ColorBy {
    /// Every choice, in menu order.
    pub fn all() -> impl Iterator<Item = ColorBy> {
        [ColorBy::Strain, ColorBy::Speed, ColorBy::Correction]
            .into_iter()
            .chain(Family::ALL.map(ColorBy::CorrectionOf))
            .chain([ColorBy::NormalOffset, ColorBy::None])
    }

    /// The name used in presets (`correction.planarity`).
    pub fn name(self) -> Cow<'static, str> {
        match self {
            ColorBy::Strain => "strain".into(),
            ColorBy::Speed => "speed".into(),
            ColorBy::Correction => "correction".into(),
            ColorBy::CorrectionOf(f) => format!("correction.{}", f.name()).into(),
            ColorBy::NormalOffset => "normal_offset".into(),
            ColorBy::None => "none".into(),
        }
    }

    /// The choice a preset names, if any.
    pub fn from_name(name: &str) -> Option<ColorBy> {
        ColorBy::all().find(|c| c.name() == name)
    }

    /// The one family a `correction.<family>` colouring shows, if any.
    pub fn family(self) -> Option<Family> {
        match self {
            ColorBy::CorrectionOf(f) => Some(f),
            _ => None,
        }
    }

    /// Whether it needs every particle's corrections.
    pub fn uses_corrections(self) -> bool {
        self == ColorBy::Correction || self.family().is_some()
    }
}

impl Serialize for ColorBy {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl<'de> Deserialize<'de> for ColorBy {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        ColorBy::from_name(&name).ok_or_else(|| {
            let names: Vec<String> = ColorBy::all().map(|c| c.name().into_owned()).collect();
            serde::de::Error::custom(format!(
                "unknown colouring `{name}`, expected one of {}",
                names.join(", ")
            ))
        })
    }
}

/// Telemetry settings (see docs/telemetry.md).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TelemetrySettings {
    /// `off`, `summary` or `full`.
    pub level: Level,
    /// Log every N-th frame (≥ 1).
    pub log_every: u32,
    /// Corrections smaller than this (metres for δx, radians for δθ) get no arrow.
    pub arrow_threshold: f32,
    /// Length multiplier for correction arrows.
    pub arrow_scale: f32,
    /// What particles are coloured by.
    pub color_by: ColorBy,
    /// Which families' correction arrows are logged (at level `full`).
    #[serde(deserialize_with = "toggles_over_all_on")]
    pub corrections: FamilyToggles,
}

impl Default for TelemetrySettings {
    fn default() -> Self {
        Self {
            level: Level::Full,
            log_every: 1,
            arrow_threshold: 1e-5,
            arrow_scale: 20.0,
            color_by: ColorBy::Strain,
            corrections: FamilyToggles::splat(true),
        }
    }
}

/// One switch per constraint family (all on unless given).
pub type FamilyToggles = crate::solver::PerFamily<bool>;

/// Reads `telemetry.corrections` over all families on.
fn toggles_over_all_on<'de, D: serde::Deserializer<'de>>(d: D) -> Result<FamilyToggles, D::Error> {
    FamilyToggles::deserialize_over(FamilyToggles::splat(true), d)
}
