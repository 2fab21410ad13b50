//! The colliders as the 3D view draws them.
//!
//! Spheres, capsules, cylinders and boxes are logged once, static, in their
//! body's frame (`world/bodies/{name}/colliders/{k}`) or the world's
//! (`world/colliders/{k}`). A plane has no size, so it is drawn as a square
//! patch under the cloth, [`GROUND_SPAN`] times the cloth's larger side,
//! that follows the cloth at every logged frame. The viewer's default
//! camera frames everything it draws at the current frame, so a patch of
//! the cloth's scale keeps the cloth in view and large, even when it rides
//! on a car 100 m down the road; the viewer's own grid, fixed in the world,
//! shows the motion.

use glam::Vec3;
use rerun::{RecordingStream, RecordingStreamResult};

use super::paths;
use crate::scene::{
    Scene,
    preset::{ColliderSection, ShapeKind},
};
use crate::solver::{Pose, Shape};

/// The side of a plane's patch, in units of the cloth's larger side.
const GROUND_SPAN: f32 = 3.0;

/// Logs the colliders that never change (all but the planes' patches).
pub fn log_static(rec: &RecordingStream, scene: &Scene) -> RecordingStreamResult<()> {
    for (k, c) in scene.preset().colliders.iter().enumerate() {
        let path = path(c, k);
        let rotation = crate::scene::preset::euler(c.rotation);
        // Faint: the cloth is what the view is about.
        let colour = rerun::Color::from_unmultiplied_rgba(120, 140, 170, 80);
        match c.shape {
            ShapeKind::Plane => rec.log_static(
                path,
                &rerun::Mesh3D::update_fields()
                    .with_triangle_indices([[0, 1, 2], [0, 2, 3]])
                    .with_albedo_factor(rerun::Rgba32::from_unmultiplied_rgba(90, 100, 90, 255)),
            )?,
            ShapeKind::Sphere => rec.log_static(
                path,
                &rerun::Ellipsoids3D::from_centers_and_radii(
                    [c.position],
                    [c.radius.unwrap_or(0.0)],
                )
                .with_colors([colour])
                .with_fill_mode(rerun::FillMode::Solid),
            )?,
            ShapeKind::Capsule => {
                let h = c.half_length.unwrap_or(0.0);
                let axis = rotation * Vec3::Z * h;
                rec.log_static(
                    path,
                    &rerun::Capsules3D::from_endpoints_and_radii(
                        [c.position - axis],
                        [c.position + axis],
                        [c.radius.unwrap_or(0.0)],
                    )
                    .with_colors([colour]),
                )?
            }
            ShapeKind::Cylinder => {
                let h = c.half_length.unwrap_or(0.0);
                rec.log_static(
                    path,
                    &rerun::Cylinders3D::from_lengths_and_radii(
                        [2.0 * h],
                        [c.radius.unwrap_or(0.0)],
                    )
                    .with_centers([c.position])
                    .with_quaternions([rotation])
                    .with_colors([colour])
                    .with_fill_mode(rerun::FillMode::Solid),
                )?
            }
            ShapeKind::Box => rec.log_static(
                path,
                &rerun::Boxes3D::from_centers_and_half_sizes(
                    [c.position],
                    [c.half_extents.unwrap_or(Vec3::ZERO)],
                )
                .with_quaternions([rotation])
                .with_colors([colour])
                .with_fill_mode(rerun::FillMode::Solid),
            )?,
        }
    }
    Ok(())
}

/// Logs each plane's patch under the cloth whose particles are at `x`
/// (the time already set), where the solver has the plane now.
pub fn log_planes(rec: &RecordingStream, scene: &Scene, x: &[Vec3]) -> RecordingStreamResult<()> {
    // The solver's colliders are the preset's, in its order.
    let solver = scene.solver();
    let planes = solver.colliders().iter().zip(&scene.preset().colliders);
    let mut planes = planes
        .enumerate()
        .filter(|(_, (c, _))| c.shape == Shape::Plane)
        .peekable();
    if planes.peek().is_none() {
        return Ok(());
    }
    let spec = solver.spec();
    let half = 0.5 * GROUND_SPAN * spec.width.max(spec.height);
    let centre = centre(x);
    for (k, (c, section)) in planes {
        let world = c.world_pose(scene.body_poses());
        let corners = patch(&c.pose, world.inverse_transform_point(centre), half);
        rec.log(
            path(section, k),
            &rerun::Mesh3D::update_fields().with_vertex_positions(corners),
        )?;
    }
    Ok(())
}

/// `world/bodies/{name}/colliders/{k}` or `world/colliders/{k}`.
fn path(c: &ColliderSection, k: usize) -> String {
    match &c.body {
        Some(b) => paths::body_collider(b, k),
        None => paths::world_collider(k),
    }
}

/// The centre of the box that bounds `x` (the origin for none).
fn centre(x: &[Vec3]) -> Vec3 {
    let Some(first) = x.first() else {
        return Vec3::ZERO;
    };
    let (lo, hi) = x
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    0.5 * (lo + hi)
}

/// The corners, in `plane`'s parent frame, of the square of half side
/// `half` on the plane (its local XY) centred where `over` (in the plane's
/// frame) projects onto it.
fn patch(plane: &Pose, over: Vec3, half: f32) -> [Vec3; 4] {
    [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
        .map(|[u, v]| plane.transform_point(Vec3::new(over.x + u * half, over.y + v * half, 0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn a_patch_lies_on_its_plane_under_the_point_it_follows() {
        // A plane tilted about X, raised, and a point above it.
        let plane = Pose::new(Vec3::new(1.0, 2.0, 0.5), Quat::from_rotation_x(0.3));
        let point = Vec3::new(40.0, -3.0, 7.0);
        let corners = patch(&plane, plane.inverse_transform_point(point), 2.0);
        let normal = plane.rotation * Vec3::Z;
        let mid = corners.iter().sum::<Vec3>() / 4.0;
        for c in corners {
            assert!(
                (c - plane.translation).dot(normal).abs() < 1e-4,
                "{c} off the plane"
            );
            assert!(
                (c.distance(mid) - 2.0 * 2f32.sqrt()).abs() < 1e-4,
                "half side 2"
            );
        }
        // The patch's centre is the point's foot on the plane.
        let foot = point - normal * (point - plane.translation).dot(normal);
        assert!(mid.distance(foot) < 1e-4, "{mid} is not under {point}");
    }

    #[test]
    fn the_centre_is_that_of_the_bounding_box() {
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(4.0, -2.0, 1.0),
            Vec3::new(1.0, 1.0, 3.0),
        ];
        assert_eq!(centre(&x), Vec3::new(2.0, -0.5, 1.5));
        assert_eq!(centre(&[]), Vec3::ZERO);
    }
}
