//! The preset format: one TOML file per scene, every field documented in
//! `presets/README.md` with its default, unit and range.
//!
//! A preset is plain data. [`Preset::validate`] checks ranges and references
//! and reports the dotted key of the first problem; `load` turns that key
//! into a file, line and column.

use glam::{EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::solver::{ClothSpec, ParamError, Params};

/// A rotation given as XYZ Euler angles in degrees (intrinsic: X, then Y, then Z).
pub type EulerDegrees = [f32; 3];

/// Converts XYZ Euler degrees to a quaternion.
pub fn euler(deg: EulerDegrees) -> Quat {
    let [x, y, z] = deg.map(f32::to_radians);
    Quat::from_euler(EulerRot::XYZ, x, y, z)
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    /// One line shown by `weft presets`.
    pub description: String,
    /// A preset this one builds on (a shipped name or a path relative to this
    /// file); resolved when loading, so a loaded preset never has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extend: Option<String>,
    /// Default length of a recording, in seconds.
    #[serde(default = "default_duration")]
    pub duration: f32,
    /// The cloth.
    pub cloth: ClothSection,
    /// Solver parameters.
    #[serde(default)]
    pub solver: Params,
    /// Gravity, air and wind.
    #[serde(default)]
    pub environment: EnvironmentSection,
    /// Moving bodies and their motion scripts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySection>,
    /// Which particles follow which body.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<AttachmentSection>,
    /// Obstacles.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub colliders: Vec<ColliderSection>,
    /// What is recorded, and how often.
    #[serde(default)]
    pub telemetry: TelemetrySettings,
    /// Bounds a recording must stay within (CI verdicts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expect: Option<Expect>,
}

fn default_duration() -> f32 {
    10.0
}

/// The cloth's size, resolution, material and rest placement.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClothSection {
    /// Size along the weft, in metres.
    pub width: f32,
    /// Size along the warp, in metres.
    pub height: f32,
    /// Particles along the weft.
    pub weft: u32,
    /// Particles along the warp.
    pub warp: u32,
    /// Areal density, in kg/m².
    pub density: f32,
    /// Thickness, in metres.
    pub thickness: f32,
    /// Largest seeded deviation of the rest layout from flat, in metres
    /// (see [`ClothSpec::imperfection`]).
    pub imperfection: f32,
    /// World position of particle (0, 0) at rest, in metres.
    pub position: Vec3,
    /// Rest orientation, XYZ Euler degrees; the weft runs along local X, the
    /// warp along local Y, the normal along local Z.
    pub rotation: EulerDegrees,
}

impl Default for ClothSection {
    fn default() -> Self {
        let d = ClothSpec::default();
        Self {
            width: d.width,
            height: d.height,
            weft: d.weft,
            warp: d.warp,
            density: d.density,
            thickness: d.thickness,
            imperfection: d.imperfection,
            position: Vec3::ZERO,
            rotation: [0.0; 3],
        }
    }
}

impl ClothSection {
    /// The solver's cloth description.
    pub fn spec(&self) -> ClothSpec {
        ClothSpec {
            width: self.width,
            height: self.height,
            weft: self.weft,
            warp: self.warp,
            density: self.density,
            thickness: self.thickness,
            imperfection: self.imperfection,
            origin: self.position,
            rotation: euler(self.rotation),
        }
    }
}

/// Gravity, air and wind.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvironmentSection {
    /// Gravity, in m/s².
    pub gravity: Vec3,
    /// Air density, in kg/m³.
    pub air_density: f32,
    /// Pressure coefficient on the element's face.
    pub drag_normal: f32,
    /// Skin-friction coefficient along the element.
    pub drag_tangent: f32,
    /// The wind.
    pub wind: WindSection,
}

impl Default for EnvironmentSection {
    fn default() -> Self {
        let e = crate::solver::Environment::default();
        Self {
            gravity: e.gravity,
            air_density: e.air_density,
            drag_normal: e.drag_normal,
            drag_tangent: e.drag_tangent,
            wind: WindSection::default(),
        }
    }
}

/// A steady wind with deterministic gusts.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindSection {
    /// Mean wind velocity, in m/s.
    pub velocity: Vec3,
    /// Peak extra speed of gusts along the wind, in m/s.
    pub gust: f32,
    /// Typical time between gusts, in seconds.
    pub gust_period: f32,
    /// Peak swing of the wind's direction, in degrees (about the vertical).
    pub sway: f32,
}

/// A moving body: a name and exactly one motion script.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySection {
    /// Name used by attachments and colliders.
    pub name: String,
    /// Stands still.
    #[serde(default, rename = "static", skip_serializing_if = "Option::is_none")]
    pub fixed: Option<StaticMotion>,
    /// Follows keyframes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframes: Option<KeyframeMotion>,
    /// Drives like a car on a road.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub car: Option<CarMotion>,
    /// Runs like a character.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runner: Option<RunnerMotion>,
}

/// A body that does not move.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StaticMotion {
    /// Position, in metres.
    pub position: Vec3,
    /// Orientation, XYZ Euler degrees.
    pub rotation: EulerDegrees,
}

/// How keyframes are blended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight lines between keys.
    #[default]
    Linear,
    /// Eased in and out at every key (no jumps in velocity).
    Smooth,
    /// Holds each key until the next: teleports.
    Step,
}

/// A pose at a time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Key {
    /// Time, in seconds.
    pub t: f32,
    /// Position, in metres.
    #[serde(default)]
    pub position: Vec3,
    /// Orientation, XYZ Euler degrees.
    #[serde(default)]
    pub rotation: EulerDegrees,
}

/// Motion through keyframes.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeMotion {
    /// How to blend between keys.
    #[serde(default)]
    pub interpolation: Interpolation,
    /// Start over after the last key.
    #[serde(default, rename = "loop")]
    pub looped: bool,
    /// The keys, in increasing time.
    pub keys: Vec<Key>,
}

/// A car: a speed profile, steering and a road.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CarMotion {
    /// Start position, in metres.
    pub start: Vec3,
    /// Initial heading, degrees from +X toward +Y.
    pub heading: f32,
    /// Speed keyframes `[t s, v m/s]`, linear between keys; a steep drop is hard braking.
    pub speed: Vec<[f32; 2]>,
    /// Yaw-rate keyframes `[t s, ω °/s]`, linear between keys; a spike is a sharp turn.
    pub yaw_rate: Vec<[f32; 2]>,
    /// Distance between the axles, in metres (sets pitch over bumps).
    pub wheelbase: f32,
    /// Distance between the wheels on an axle, in metres (sets roll on rough road).
    pub track: f32,
    /// The road surface.
    pub road: RoadSection,
}

impl Default for CarMotion {
    fn default() -> Self {
        Self {
            start: Vec3::ZERO,
            heading: 0.0,
            speed: vec![[0.0, 0.0]],
            yaw_rate: Vec::new(),
            wheelbase: 2.6,
            track: 1.6,
            road: RoadSection::default(),
        }
    }
}

/// Bumps and rough stretches along the road, by distance travelled.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoadSection {
    /// Single bumps.
    pub bumps: Vec<Bump>,
    /// Rough stretches.
    pub rough: Vec<Rough>,
}

/// A smooth bump across the road.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bump {
    /// Where it starts, in metres along the road.
    pub at: f32,
    /// Its height, in metres.
    pub height: f32,
    /// Its length along the road, in metres.
    pub length: f32,
}

/// A stretch of rough road.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rough {
    /// Where it starts, in metres along the road.
    pub from: f32,
    /// Where it ends, in metres along the road.
    pub to: f32,
    /// Peak height of the roughness, in metres.
    pub amplitude: f32,
    /// Typical wavelength, in metres.
    pub wavelength: f32,
}

/// A character that runs, bobs, and turns abruptly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunnerMotion {
    /// Start position of the body frame (on the ground, between the feet), in metres.
    pub start: Vec3,
    /// Initial heading, degrees from +X toward +Y.
    pub heading: f32,
    /// Running speed, in m/s.
    pub speed: f32,
    /// Strides per second.
    pub stride_frequency: f32,
    /// Vertical bob per stride, in metres.
    pub bob: f32,
    /// Forward lean, in degrees.
    pub lean: f32,
    /// Abrupt turns `[t s, Δheading °]`.
    pub turns: Vec<[f32; 2]>,
    /// How long a turn takes, in seconds.
    pub turn_time: f32,
}

impl Default for RunnerMotion {
    fn default() -> Self {
        Self {
            start: Vec3::ZERO,
            heading: 0.0,
            speed: 4.0,
            stride_frequency: 1.4,
            bob: 0.06,
            lean: 8.0,
            turns: Vec::new(),
            turn_time: 0.25,
        }
    }
}

/// Grid regions, for attachments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// Column `i = 0`.
    Left,
    /// Column `i = weft − 1`.
    Right,
    /// Row `j = warp − 1`.
    Top,
    /// Row `j = 0`.
    Bottom,
    /// `(0, warp − 1)`.
    TopLeft,
    /// `(weft − 1, warp − 1)`.
    TopRight,
    /// `(0, 0)`.
    BottomLeft,
    /// `(weft − 1, 0)`.
    BottomRight,
}

impl Region {
    /// The grid coordinates of the region.
    pub fn cells(self, weft: u32, warp: u32) -> Vec<[u32; 2]> {
        let (r, t) = (weft - 1, warp - 1);
        match self {
            Region::Left => (0..warp).map(|j| [0, j]).collect(),
            Region::Right => (0..warp).map(|j| [r, j]).collect(),
            Region::Top => (0..weft).map(|i| [i, t]).collect(),
            Region::Bottom => (0..weft).map(|i| [i, 0]).collect(),
            Region::TopLeft => vec![[0, t]],
            Region::TopRight => vec![[r, t]],
            Region::BottomLeft => vec![[0, 0]],
            Region::BottomRight => vec![[r, 0]],
        }
    }
}

/// Particles that follow a body, keeping their rest offset from it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttachmentSection {
    /// The body's name.
    pub body: String,
    /// Edges and corners of the grid.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub select: Vec<Region>,
    /// Single particles, as `[i, j]` grid coordinates.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<[u32; 2]>,
    /// Whether the body also drives the particles' orientation (a sewn seam);
    /// by default they turn freely about the point (a pin, a grommet).
    #[serde(default)]
    pub clamp: bool,
}

/// Collider shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// The half-space below the local XY plane.
    Plane,
    /// Needs `radius`.
    Sphere,
    /// Needs `radius` and `half_length` (along local Z).
    Capsule,
    /// A flat-ended cylinder; needs `radius` and `half_length` (along local Z).
    Cylinder,
    /// Needs `half_extents`.
    Box,
}

/// An obstacle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderSection {
    /// The shape.
    pub shape: ShapeKind,
    /// Sphere and capsule radius, in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Capsule half length, in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_length: Option<f32>,
    /// Box half sizes, in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_extents: Option<Vec3>,
    /// The body it moves with (none: fixed in the world).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Position in the body's (or world's) frame, in metres.
    #[serde(default)]
    pub position: Vec3,
    /// Orientation in the body's frame, XYZ Euler degrees.
    #[serde(default)]
    pub rotation: EulerDegrees,
    /// Coulomb friction coefficient.
    #[serde(default = "default_friction")]
    pub friction: f32,
}

fn default_friction() -> f32 {
    0.5
}

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
    /// One colour.
    None,
}

impl ColorBy {
    /// Every choice, in menu order.
    pub const ALL: [ColorBy; 8] = [
        ColorBy::Strain,
        ColorBy::Speed,
        ColorBy::Correction,
        ColorBy::CorrectionStretch,
        ColorBy::CorrectionPlanarity,
        ColorBy::CorrectionNormality,
        ColorBy::CorrectionCurvature,
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
            _ => None,
        }
    }

    /// Whether it needs every particle's corrections.
    pub fn uses_corrections(self) -> bool {
        self == ColorBy::Correction || self.family().is_some()
    }
}

/// Telemetry settings (see the README's telemetry section).
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
            corrections: FamilyToggles::default(),
        }
    }
}

/// One switch per constraint family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FamilyToggles {
    /// Stretch.
    pub stretch: bool,
    /// Planarity.
    pub planarity: bool,
    /// Normality.
    pub normality: bool,
    /// Curvature.
    pub curvature: bool,
}

impl Default for FamilyToggles {
    fn default() -> Self {
        Self {
            stretch: true,
            planarity: true,
            normality: true,
            curvature: true,
        }
    }
}

impl FamilyToggles {
    /// The switch of one family.
    pub fn get(&self, f: crate::solver::Family) -> bool {
        use crate::solver::Family::*;
        match f {
            Stretch => self.stretch,
            Planarity => self.planarity,
            Normality => self.normality,
            Curvature => self.curvature,
        }
    }

    /// The switch of one family, mutably.
    pub fn get_mut(&mut self, f: crate::solver::Family) -> &mut bool {
        use crate::solver::Family::*;
        match f {
            Stretch => &mut self.stretch,
            Planarity => &mut self.planarity,
            Normality => &mut self.normality,
            Curvature => &mut self.curvature,
        }
    }
}

/// Per-family bounds.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FamilyBounds {
    /// Bound on the stretch violation (strain).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stretch: Option<f32>,
    /// Bound on the planarity violation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub planarity: Option<f32>,
    /// Bound on the normality violation (radians).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normality: Option<f32>,
    /// Bound on the curvature violation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub curvature: Option<f32>,
}

impl FamilyBounds {
    /// The bound of one family.
    pub fn get(&self, f: crate::solver::Family) -> Option<f32> {
        use crate::solver::Family::*;
        match f {
            Stretch => self.stretch,
            Planarity => self.planarity,
            Normality => self.normality,
            Curvature => self.curvature,
        }
    }
}

/// What a recording must satisfy; `weft record` exits non-zero otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Expect {
    /// Largest edge strain allowed at any frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_strain: Option<f32>,
    /// Largest violation allowed at any frame, per family.
    pub max_violation: FamilyBounds,
    /// Kinetic energy (J) the cloth must be below at the end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settle_energy: Option<f32>,
    /// The state must stay finite.
    pub finite: bool,
}

impl Default for Expect {
    fn default() -> Self {
        Self {
            max_strain: None,
            max_violation: FamilyBounds::default(),
            settle_energy: None,
            finite: true,
        }
    }
}

/// A semantic problem, at a dotted key path.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Dotted key path, e.g. `cloth.weft` or `bodies[0].car.speed`.
    pub key: String,
    /// What is wrong, including the allowed range.
    pub message: String,
}

impl Invalid {
    fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }

    fn from_param(prefix: &str, e: ParamError) -> Self {
        let key = if prefix.is_empty() || e.name.starts_with(prefix) {
            e.name.to_string()
        } else {
            format!("{prefix}{}", e.name)
        };
        Self::new(
            key,
            format!("value {} {}; allowed: {}", e.value, e.problem, e.range),
        )
    }
}

fn range(key: impl Into<String>, v: f32, lo: f32, hi: f32, allowed: &str) -> Result<(), Invalid> {
    let problem = if !v.is_finite() {
        "is not finite"
    } else if v < lo || v > hi {
        "is out of range"
    } else {
        return Ok(());
    };
    Err(Invalid::new(
        key,
        format!("value {v} {problem}; allowed: {allowed}"),
    ))
}

fn finite3(key: impl Into<String>, v: Vec3, limit: f32) -> Result<(), Invalid> {
    if v.is_finite() && v.abs().max_element() <= limit {
        Ok(())
    } else {
        Err(Invalid::new(
            key,
            format!(
                "value {v} is not finite or too large; allowed: finite components with magnitude ≤ {limit}"
            ),
        ))
    }
}

fn euler_ok(key: impl Into<String>, e: EulerDegrees) -> Result<(), Invalid> {
    finite3(key, Vec3::from(e), 1e4)
}

fn keyframes_ok(
    key: String,
    keys: &[[f32; 2]],
    lo: f32,
    hi: f32,
    unit: &'static str,
) -> Result<(), Invalid> {
    let mut last = f32::NEG_INFINITY;
    for (k, [t, v]) in keys.iter().enumerate() {
        range(format!("{key}[{k}]"), *t, 0.0, 1e5, "0 ≤ t ≤ 100000 s")?;
        range(format!("{key}[{k}]"), *v, lo, hi, unit)?;
        if *t < last {
            return Err(Invalid::new(
                format!("{key}[{k}]"),
                "keys must be in increasing time",
            ));
        }
        last = *t;
    }
    Ok(())
}

impl Preset {
    /// Checks every range and reference; returns the first problem.
    pub fn validate(&self) -> Result<(), Invalid> {
        range(
            "duration",
            self.duration,
            0.0,
            86_400.0,
            "0 ≤ duration ≤ 86400 s",
        )?;
        self.cloth
            .spec()
            .validate()
            .map_err(|e| Invalid::from_param("", e))?;
        euler_ok("cloth.rotation", self.cloth.rotation)?;
        self.solver
            .validate()
            .map_err(|e| Invalid::from_param("solver.", e))?;
        let env = &self.environment;
        finite3("environment.gravity", env.gravity, 1e4)?;
        range(
            "environment.air_density",
            env.air_density,
            0.0,
            100.0,
            "0 ≤ air_density ≤ 100 kg/m³",
        )?;
        range(
            "environment.drag_normal",
            env.drag_normal,
            0.0,
            10.0,
            "0 ≤ drag_normal ≤ 10",
        )?;
        range(
            "environment.drag_tangent",
            env.drag_tangent,
            0.0,
            10.0,
            "0 ≤ drag_tangent ≤ 10",
        )?;
        finite3("environment.wind.velocity", env.wind.velocity, 1e3)?;
        range(
            "environment.wind.gust",
            env.wind.gust,
            0.0,
            1e3,
            "0 ≤ gust ≤ 1000 m/s",
        )?;
        range(
            "environment.wind.gust_period",
            env.wind.gust_period,
            0.0,
            1e4,
            "0 ≤ gust_period ≤ 10000 s",
        )?;
        range(
            "environment.wind.sway",
            env.wind.sway,
            0.0,
            180.0,
            "0 ≤ sway ≤ 180°",
        )?;
        self.validate_bodies()?;
        self.validate_links()?;
        let t = &self.telemetry;
        if !(1..=1_000_000).contains(&t.log_every) {
            return Err(Invalid::new(
                "telemetry.log_every",
                format!(
                    "value {} is out of range; allowed: 1 ≤ log_every ≤ 1000000",
                    t.log_every
                ),
            ));
        }
        range(
            "telemetry.arrow_threshold",
            t.arrow_threshold,
            0.0,
            1e3,
            "0 ≤ arrow_threshold ≤ 1000",
        )?;
        range(
            "telemetry.arrow_scale",
            t.arrow_scale,
            1e-6,
            1e6,
            "0.000001 ≤ arrow_scale ≤ 1000000",
        )?;
        if let Some(e) = &self.expect {
            let bound = |key: &str, v: Option<f32>| match v {
                Some(v) => range(key.to_string(), v, 0.0, f32::MAX, "a finite bound ≥ 0"),
                None => Ok(()),
            };
            bound("expect.max_strain", e.max_strain)?;
            bound("expect.settle_energy", e.settle_energy)?;
            for f in crate::solver::Family::ALL {
                bound(
                    &format!("expect.max_violation.{}", f.name()),
                    e.max_violation.get(f),
                )?;
            }
        }
        Ok(())
    }

    fn validate_bodies(&self) -> Result<(), Invalid> {
        for (b, body) in self.bodies.iter().enumerate() {
            let key = |k: &str| format!("bodies[{b}].{k}");
            if body.name.trim().is_empty() {
                return Err(Invalid::new(key("name"), "a body needs a non-empty name"));
            }
            if self.bodies[..b].iter().any(|o| o.name == body.name) {
                return Err(Invalid::new(
                    key("name"),
                    format!("body name `{}` is used twice", body.name),
                ));
            }
            let scripts = [
                body.fixed.is_some(),
                body.keyframes.is_some(),
                body.car.is_some(),
                body.runner.is_some(),
            ];
            if scripts.iter().filter(|s| **s).count() != 1 {
                return Err(Invalid::new(
                    format!("bodies[{b}]"),
                    "a body needs exactly one motion table: [bodies.static], [bodies.keyframes], [bodies.car] or [bodies.runner]",
                ));
            }
            if let Some(m) = &body.fixed {
                finite3(key("static.position"), m.position, 1e6)?;
                euler_ok(key("static.rotation"), m.rotation)?;
            }
            if let Some(m) = &body.keyframes {
                if m.keys.is_empty() {
                    return Err(Invalid::new(
                        key("keyframes.keys"),
                        "at least one key is needed",
                    ));
                }
                let mut last = f32::NEG_INFINITY;
                for (k, key_) in m.keys.iter().enumerate() {
                    range(
                        key(&format!("keyframes.keys[{k}].t")),
                        key_.t,
                        0.0,
                        1e5,
                        "0 ≤ t ≤ 100000 s",
                    )?;
                    if key_.t <= last {
                        return Err(Invalid::new(
                            key(&format!("keyframes.keys[{k}].t")),
                            "keys must be in strictly increasing time",
                        ));
                    }
                    last = key_.t;
                    finite3(
                        key(&format!("keyframes.keys[{k}].position")),
                        key_.position,
                        1e6,
                    )?;
                    euler_ok(key(&format!("keyframes.keys[{k}].rotation")), key_.rotation)?;
                }
            }
            if let Some(m) = &body.car {
                finite3(key("car.start"), m.start, 1e6)?;
                range(
                    key("car.heading"),
                    m.heading,
                    -1e4,
                    1e4,
                    "|heading| ≤ 10000°",
                )?;
                if m.speed.is_empty() {
                    return Err(Invalid::new(
                        key("car.speed"),
                        "at least one speed key is needed",
                    ));
                }
                keyframes_ok(
                    key("car.speed"),
                    &m.speed,
                    -100.0,
                    100.0,
                    "-100 ≤ speed ≤ 100 m/s",
                )?;
                keyframes_ok(
                    key("car.yaw_rate"),
                    &m.yaw_rate,
                    -720.0,
                    720.0,
                    "-720 ≤ yaw rate ≤ 720 °/s",
                )?;
                range(
                    key("car.wheelbase"),
                    m.wheelbase,
                    0.1,
                    20.0,
                    "0.1 ≤ wheelbase ≤ 20 m",
                )?;
                range(key("car.track"), m.track, 0.1, 10.0, "0.1 ≤ track ≤ 10 m")?;
                for (k, bump) in m.road.bumps.iter().enumerate() {
                    range(
                        key(&format!("car.road.bumps[{k}].at")),
                        bump.at,
                        -1e6,
                        1e6,
                        "|at| ≤ 1000000 m",
                    )?;
                    range(
                        key(&format!("car.road.bumps[{k}].height")),
                        bump.height,
                        -1.0,
                        1.0,
                        "-1 ≤ height ≤ 1 m",
                    )?;
                    range(
                        key(&format!("car.road.bumps[{k}].length")),
                        bump.length,
                        0.01,
                        100.0,
                        "0.01 ≤ length ≤ 100 m",
                    )?;
                }
                for (k, r) in m.road.rough.iter().enumerate() {
                    range(
                        key(&format!("car.road.rough[{k}].from")),
                        r.from,
                        -1e6,
                        1e6,
                        "|from| ≤ 1000000 m",
                    )?;
                    range(
                        key(&format!("car.road.rough[{k}].to")),
                        r.to,
                        r.from,
                        1e6,
                        "from ≤ to ≤ 1000000 m",
                    )?;
                    range(
                        key(&format!("car.road.rough[{k}].amplitude")),
                        r.amplitude,
                        0.0,
                        0.5,
                        "0 ≤ amplitude ≤ 0.5 m",
                    )?;
                    range(
                        key(&format!("car.road.rough[{k}].wavelength")),
                        r.wavelength,
                        0.05,
                        100.0,
                        "0.05 ≤ wavelength ≤ 100 m",
                    )?;
                }
            }
            if let Some(m) = &body.runner {
                finite3(key("runner.start"), m.start, 1e6)?;
                range(
                    key("runner.heading"),
                    m.heading,
                    -1e4,
                    1e4,
                    "|heading| ≤ 10000°",
                )?;
                range(
                    key("runner.speed"),
                    m.speed,
                    0.0,
                    15.0,
                    "0 ≤ speed ≤ 15 m/s",
                )?;
                range(
                    key("runner.stride_frequency"),
                    m.stride_frequency,
                    0.0,
                    5.0,
                    "0 ≤ stride_frequency ≤ 5 Hz",
                )?;
                range(key("runner.bob"), m.bob, 0.0, 0.5, "0 ≤ bob ≤ 0.5 m")?;
                range(key("runner.lean"), m.lean, -45.0, 45.0, "-45 ≤ lean ≤ 45°")?;
                range(
                    key("runner.turn_time"),
                    m.turn_time,
                    0.01,
                    10.0,
                    "0.01 ≤ turn_time ≤ 10 s",
                )?;
                keyframes_ok(
                    key("runner.turns"),
                    &m.turns,
                    -360.0,
                    360.0,
                    "-360 ≤ turn ≤ 360°",
                )?;
            }
        }
        Ok(())
    }

    fn validate_links(&self) -> Result<(), Invalid> {
        let names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        let known = |key: String, name: &str| {
            if names.contains(&name) {
                Ok(())
            } else {
                let hint = crate::scene::load::nearest(name, names.iter().copied())
                    .map(|n| format!("; did you mean `{n}`?"))
                    .unwrap_or_default();
                Err(Invalid::new(
                    key,
                    format!(
                        "no body is named `{name}`; bodies: [{}]{hint}",
                        names.join(", ")
                    ),
                ))
            }
        };
        for (a, att) in self.attachments.iter().enumerate() {
            known(format!("attachments[{a}].body"), &att.body)?;
            if att.select.is_empty() && att.particles.is_empty() {
                return Err(Invalid::new(
                    format!("attachments[{a}]"),
                    "an attachment needs `select` or `particles`",
                ));
            }
            for (k, [i, j]) in att.particles.iter().enumerate() {
                if *i >= self.cloth.weft || *j >= self.cloth.warp {
                    return Err(Invalid::new(
                        format!("attachments[{a}].particles[{k}]"),
                        format!(
                            "particle [{i}, {j}] is outside the grid; allowed: 0 ≤ i < {}, 0 ≤ j < {}",
                            self.cloth.weft, self.cloth.warp
                        ),
                    ));
                }
            }
        }
        for (c, col) in self.colliders.iter().enumerate() {
            let key = |k: &str| format!("colliders[{c}].{k}");
            if let Some(b) = &col.body {
                known(key("body"), b)?;
            }
            finite3(key("position"), col.position, 1e6)?;
            euler_ok(key("rotation"), col.rotation)?;
            range(
                key("friction"),
                col.friction,
                0.0,
                10.0,
                "0 ≤ friction ≤ 10",
            )?;
            let need = |field: &str, v: bool| {
                if v {
                    Ok(())
                } else {
                    Err(Invalid::new(
                        key(field),
                        format!("a {:?} collider needs `{field}`", col.shape).to_lowercase(),
                    ))
                }
            };
            match col.shape {
                ShapeKind::Plane => {}
                ShapeKind::Sphere => need("radius", col.radius.is_some())?,
                ShapeKind::Capsule | ShapeKind::Cylinder => {
                    need("radius", col.radius.is_some())?;
                    need("half_length", col.half_length.is_some())?;
                }
                ShapeKind::Box => need("half_extents", col.half_extents.is_some())?,
            }
            if let Some(r) = col.radius {
                range(key("radius"), r, 1e-4, 1e3, "0.0001 ≤ radius ≤ 1000 m")?;
            }
            if let Some(h) = col.half_length {
                range(key("half_length"), h, 0.0, 1e3, "0 ≤ half_length ≤ 1000 m")?;
            }
            if let Some(h) = col.half_extents {
                finite3(key("half_extents"), h, 1e3)?;
                if h.min_element() <= 0.0 {
                    return Err(Invalid::new(
                        key("half_extents"),
                        "half extents must be > 0",
                    ));
                }
            }
        }
        Ok(())
    }
}
