//! Moving bodies: a name and exactly one motion script each (static,
//! keyframes, a car on a road, a runner). `scene::motion` brings them to life.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::EulerDegrees;

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
    /// Position, in metres (world positions are read in double precision).
    pub position: DVec3,
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
    pub position: DVec3,
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
    pub start: DVec3,
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
            start: DVec3::ZERO,
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
    pub start: DVec3,
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
            start: DVec3::ZERO,
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
