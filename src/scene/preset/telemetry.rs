//! What a recording carries: the telemetry level, how often frames are
//! logged, correction arrows and particle colours (the `[telemetry]` table).

use serde::{Deserialize, Serialize};

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

/// What particles are coloured by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorBy {
    /// Largest strain of the particle's weft and warp edges.
    #[default]
    Strain,
    /// Speed.
    Speed,
    /// Size of the particle's total correction in the last adjust.
    Correction,
    /// Size of the stretch family's correction alone.
    #[serde(rename = "correction.stretch")]
    CorrectionStretch,
    /// Size of the planarity family's correction alone.
    #[serde(rename = "correction.planarity")]
    CorrectionPlanarity,
    /// Size of the normality family's correction alone.
    #[serde(rename = "correction.normality")]
    CorrectionNormality,
    /// Size of the curvature family's correction alone.
    #[serde(rename = "correction.curvature")]
    CorrectionCurvature,
    /// Size of the self-collision family's correction alone.
    #[serde(rename = "correction.self")]
    CorrectionSelf,
    /// The angle between the element's normal and the surface's (above
    /// 90°: the element faces the other way).
    NormalOffset,
    /// One colour.
    None,
}

impl ColorBy {
    /// Every choice, in menu order.
    pub const ALL: [ColorBy; 10] = [
        ColorBy::Strain,
        ColorBy::Speed,
        ColorBy::Correction,
        ColorBy::CorrectionStretch,
        ColorBy::CorrectionPlanarity,
        ColorBy::CorrectionNormality,
        ColorBy::CorrectionCurvature,
        ColorBy::CorrectionSelf,
        ColorBy::NormalOffset,
        ColorBy::None,
    ];

    /// The name used in presets (`correction.planarity`).
    pub fn name(self) -> &'static str {
        match self {
            ColorBy::Strain => "strain",
            ColorBy::Speed => "speed",
            ColorBy::Correction => "correction",
            ColorBy::CorrectionStretch => "correction.stretch",
            ColorBy::CorrectionPlanarity => "correction.planarity",
            ColorBy::CorrectionNormality => "correction.normality",
            ColorBy::CorrectionCurvature => "correction.curvature",
            ColorBy::CorrectionSelf => "correction.self",
            ColorBy::NormalOffset => "normal_offset",
            ColorBy::None => "none",
        }
    }

    /// The one family a `correction.<family>` colouring shows, if any.
    pub fn family(self) -> Option<crate::solver::Family> {
        use crate::solver::Family;
        match self {
            ColorBy::CorrectionStretch => Some(Family::Stretch),
            ColorBy::CorrectionPlanarity => Some(Family::Planarity),
            ColorBy::CorrectionNormality => Some(Family::Normality),
            ColorBy::CorrectionCurvature => Some(Family::Curvature),
            ColorBy::CorrectionSelf => Some(Family::SelfCollision),
            _ => None,
        }
    }

    /// Whether it needs every particle's corrections.
    pub fn uses_corrections(self) -> bool {
        self == ColorBy::Correction || self.family().is_some()
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
