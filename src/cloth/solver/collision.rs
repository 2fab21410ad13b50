//! Colliders: particles stay outside planes, spheres, capsules and boxes.
//!
//! Each collider is a shape in the frame of a body (or of the world). After
//! every adjust iteration a particle closer than half the cloth's thickness to
//! a shape's surface is pushed out along the surface normal. At the end of the
//! adjust phase, friction removes the particle's tangential motion relative to
//! the collider, up to `μ` times the deepest penetration seen in the substep
//! (position-based Coulomb friction).

use glam::{Quat, Vec3};

/// A rigid transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Translation, in metres.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No translation, no rotation.
    pub const IDENTITY: Self = Self {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
    };

    /// A pose from its parts.
    pub fn new(translation: Vec3, rotation: Quat) -> Self {
        Self {
            translation,
            rotation,
        }
    }

    /// Maps a point from local to world.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.translation + self.rotation * p
    }

    /// Maps a point from world to local.
    #[inline]
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.conjugate() * (p - self.translation)
    }

    /// `self ∘ local`: `local` expressed in the frame of `self`.
    pub fn compose(&self, local: &Pose) -> Pose {
        Pose {
            translation: self.transform_point(local.translation),
            rotation: (self.rotation * local.rotation).normalize(),
        }
    }

    /// The inverse: `p.inverse().compose(&p)` is the identity.
    pub fn inverse(&self) -> Pose {
        let rotation = self.rotation.conjugate();
        Pose {
            translation: -(rotation * self.translation),
            rotation,
        }
    }

    /// The pose a fraction `t ∈ [0, 1]` of the way from `self` to `other`.
    pub fn lerp(&self, other: &Pose, t: f32) -> Pose {
        Pose {
            translation: self.translation.lerp(other.translation, t),
            rotation: self.rotation.slerp(other.rotation, t).normalize(),
        }
    }
}

/// A collider's geometry, in its own frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// The half-space below the local XY plane; its normal is local +Z.
    Plane,
    /// A sphere centred on the origin.
    Sphere {
        /// Radius, in metres.
        radius: f32,
    },
    /// A capsule around the local Z axis from `−half_length` to `+half_length`.
    Capsule {
        /// Radius, in metres.
        radius: f32,
        /// Half the length of the axis segment, in metres.
        half_length: f32,
    },
    /// A flat-ended cylinder around the local Z axis from `−half_length` to
    /// `+half_length` (a table, or the disc of a drape tester).
    Cylinder {
        /// Radius, in metres.
        radius: f32,
        /// Half the height, in metres.
        half_length: f32,
    },
    /// A box centred on the origin.
    Box {
        /// Half sizes along local X, Y, Z, in metres.
        half_extents: Vec3,
    },
}

impl Shape {
    /// Signed distance from the surface and outward normal, for a local point.
    pub fn distance(&self, p: Vec3) -> (f32, Vec3) {
        match *self {
            Shape::Plane => (p.z, Vec3::Z),
            Shape::Sphere { radius } => sphere(p, radius),
            Shape::Capsule {
                radius,
                half_length,
            } => {
                let axis = Vec3::new(0.0, 0.0, p.z.clamp(-half_length, half_length));
                sphere(p - axis, radius)
            }
            Shape::Cylinder {
                radius,
                half_length,
            } => {
                let r = Vec3::new(p.x, p.y, 0.0).length();
                let radial = if r > 1e-9 {
                    Vec3::new(p.x / r, p.y / r, 0.0)
                } else {
                    Vec3::X
                };
                let axial = Vec3::new(0.0, 0.0, if p.z >= 0.0 { 1.0 } else { -1.0 });
                let (dr, dz) = (r - radius, p.z.abs() - half_length);
                if dr > 0.0 && dz > 0.0 {
                    // Beyond the rim: the nearest point is on the edge circle.
                    let d = (dr * dr + dz * dz).sqrt();
                    (d, (radial * dr + axial * dz) / d)
                } else if dr > dz {
                    (dr, radial)
                } else {
                    (dz, axial)
                }
            }
            Shape::Box { half_extents } => {
                let q = p.abs() - half_extents;
                if q.max_element() > 0.0 {
                    let outside = q.max(Vec3::ZERO);
                    let d = outside.length();
                    (d, (outside * p.signum()) / d)
                } else {
                    // Inside: leave through the nearest face.
                    let axis = if q.x >= q.y && q.x >= q.z {
                        Vec3::X
                    } else if q.y >= q.z {
                        Vec3::Y
                    } else {
                        Vec3::Z
                    };
                    (q.max_element(), axis * p.dot(axis).signum())
                }
            }
        }
    }

    /// As [`distance`](Self::distance), but `None` for a point surely
    /// farther than `reach` from the surface, found without the square root
    /// and the normal: most particles are far from most colliders. A point
    /// near `reach` (within a thousandth) is measured, so the result is the
    /// same as `distance` wherever the distance is at most `reach`.
    #[inline]
    pub fn distance_within(&self, p: Vec3, reach: f32) -> Option<(f32, Vec3)> {
        let far = reach.abs() * 1.001 + 1e-6;
        let surely_far = match *self {
            Shape::Plane => p.z > far,
            Shape::Sphere { radius } => p.length_squared() > (radius + far) * (radius + far),
            Shape::Box { half_extents } => (p.abs() - half_extents).max_element() > far,
            Shape::Capsule { .. } | Shape::Cylinder { .. } => false,
        };
        (!surely_far).then(|| self.distance(p))
    }
}

fn sphere(p: Vec3, radius: f32) -> (f32, Vec3) {
    let d = p.length();
    let n = if d > 1e-9 { p / d } else { Vec3::Z };
    (d - radius, n)
}

/// A shape attached to a body (or to the world) with friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collider {
    /// The geometry.
    pub shape: Shape,
    /// The body it moves with; `None` for the world.
    pub body: Option<usize>,
    /// Its pose in the body's frame (or the world's).
    pub pose: Pose,
    /// Coulomb friction coefficient `μ ≥ 0`.
    pub friction: f32,
}

impl Collider {
    /// The collider's world pose, given the body poses.
    pub fn world_pose(&self, bodies: &[Pose]) -> Pose {
        self.pose_from(bodies, glam::DVec3::ZERO)
    }

    /// The collider's pose measured from `origin` (world coordinates), given
    /// the body poses measured from it: a collider without a body stays
    /// where it is in the world (the solver's floating origin,
    /// [`super::frame`]).
    pub fn pose_from(&self, bodies: &[Pose], origin: glam::DVec3) -> Pose {
        match self.body {
            Some(b) => bodies[b].compose(&self.pose),
            None if origin == glam::DVec3::ZERO => self.pose,
            None => Pose::new(
                (self.pose.translation.as_dvec3() - origin).as_vec3(),
                self.pose.rotation,
            ),
        }
    }
}

/// The deepest contact of one particle in the current substep.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Contact {
    /// Penetration depth (0 when no contact).
    pub depth: f32,
    /// Outward surface normal, in world.
    pub normal: Vec3,
    /// Index of the collider.
    pub collider: usize,
}

/// Pushes every free particle out of every collider; records the deepest
/// contact. Returns whether it moved a particle.
pub(crate) fn project(
    x: &mut [Vec3],
    inv_mass: &[f32],
    colliders: &[Collider],
    world_poses: &[Pose],
    margin: f32,
    contacts: &mut [Contact],
) -> bool {
    let mut moved = false;
    for (k, (c, pose)) in colliders.iter().zip(world_poses).enumerate() {
        for i in 0..x.len() {
            if inv_mass[i] == 0.0 {
                continue;
            }
            let local = pose.inverse_transform_point(x[i]);
            let Some((d, n_local)) = c.shape.distance_within(local, margin) else {
                continue;
            };
            let depth = margin - d;
            if depth > 0.0 {
                let n = pose.rotation * n_local;
                x[i] += n * depth;
                moved = true;
                if depth > contacts[i].depth {
                    contacts[i] = Contact {
                        depth,
                        normal: n,
                        collider: k,
                    };
                }
            }
        }
    }
    moved
}

/// Removes tangential motion relative to the collider at each contact.
pub(crate) fn apply_friction(
    x: &mut [Vec3],
    prev_x: &[Vec3],
    colliders: &[Collider],
    before: &[Pose],
    after: &[Pose],
    contacts: &[Contact],
) {
    for i in 0..x.len() {
        let c = contacts[i];
        if c.depth <= 0.0 {
            continue;
        }
        // Where the surface point under the particle was one substep ago.
        let carried =
            before[c.collider].transform_point(after[c.collider].inverse_transform_point(x[i]));
        let rel = (x[i] - prev_x[i]) - (x[i] - carried);
        let tangential = rel - c.normal * rel.dot(c.normal);
        let t = tangential.length();
        if t <= 1e-12 {
            continue;
        }
        let limit = colliders[c.collider].friction * c.depth;
        x[i] -= tangential * (limit / t).min(1.0);
    }
}
