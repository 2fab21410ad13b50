//! The preset format: one TOML file per scene, every field documented in
//! `presets/README.md` with its default, unit and range.
//!
//! A preset is plain data, one struct per table: the cloth, the environment
//! and the wind here; the moving bodies in [`bodies`], attachments and
//! colliders in [`links`], the telemetry settings in [`telemetry`] and the
//! CI bounds in [`expect`]. [`Preset::validate`] (in [`validate`]) checks
//! ranges and references and reports the dotted key of the first problem;
//! `scene::load` turns that key into a file, line and column.
//! [`Preset::warnings`] (in [`warnings`]) flags what is valid but costly.

use glam::{DVec3, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::solver::{ClothSpec, Params, portable};

pub mod bodies;
pub mod expect;
pub mod links;
pub mod telemetry;
pub mod validate;
pub mod warnings;

pub use bodies::{
    BodySection, Bump, CarMotion, Interpolation, Key, KeyframeMotion, RoadSection, Rough,
    RunnerMotion, StaticMotion,
};
pub use expect::{Expect, FamilyBounds};
pub use links::{AttachmentSection, ColliderSection, Region, ShapeKind};
pub use telemetry::{ColorBy, FamilyToggles, Level, TelemetrySettings};
pub use validate::{Invalid, clip, nearest};

/// A rotation given as XYZ Euler angles in degrees (intrinsic: X, then Y, then Z).
pub type EulerDegrees = [f32; 3];

/// Converts XYZ Euler degrees to a quaternion.
pub fn euler(deg: EulerDegrees) -> Quat {
    let [x, y, z] = deg.map(f32::to_radians);
    portable::euler_xyz(x, y, z)
}

/// The preset format this weft reads and writes. A preset names the format
/// it was written in (`format = 1`; a preset without the key is read as the
/// first); one written in a later format is refused, saying so, rather than
/// read wrong. Raised when a key changes its meaning or goes away.
pub const FORMAT: u32 = 1;

fn current_format() -> u32 {
    FORMAT
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    /// The preset format it was written in ([`FORMAT`]).
    #[serde(default = "current_format")]
    pub format: u32,
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
    /// Thickness, in metres: colliders keep half of it, self-collision all of it.
    pub thickness: f32,
    /// Friction coefficient of the cloth on itself.
    pub friction: f32,
    /// Largest seeded deviation of the rest layout from flat, in metres
    /// (see [`ClothSpec::imperfection`]).
    pub imperfection: f32,
    /// World position of particle (0, 0) at rest, in metres (read in
    /// double precision: the scene measures it from the solver's floating
    /// origin, [`crate::solver::frame`]).
    pub position: DVec3,
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
            friction: d.friction,
            imperfection: d.imperfection,
            position: DVec3::ZERO,
            rotation: [0.0; 3],
        }
    }
}

impl ClothSection {
    /// The solver's cloth description, in world coordinates.
    pub fn spec(&self) -> ClothSpec {
        self.spec_from(DVec3::ZERO)
    }

    /// The solver's cloth description, its position measured from
    /// `origin` (world coordinates).
    pub fn spec_from(&self, origin: DVec3) -> ClothSpec {
        ClothSpec {
            width: self.width,
            height: self.height,
            weft: self.weft,
            warp: self.warp,
            density: self.density,
            thickness: self.thickness,
            friction: self.friction,
            imperfection: self.imperfection,
            origin: (self.position - origin).as_vec3(),
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
