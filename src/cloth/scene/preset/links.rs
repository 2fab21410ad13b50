//! What ties the cloth to the world: attachments (which particles follow
//! which body, selected by grid [`Region`] or coordinates) and colliders.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::EulerDegrees;

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
