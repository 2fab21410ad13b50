//! What the desktop debugger's camera frames: two points that tell the
//! viewer how far back to stand from the cloth.
//!
//! The debugger's 3D view tracks an entity ([`super::paths::FRAMING`]): the
//! viewer keeps the camera on the centre of that entity's "region of
//! interest" as it moves, at a distance fixed when tracking starts, 1.5
//! times the radius of that region (`re_view_spatial`'s `eye.rs`). For a
//! point cloud the region is the mean ± 2σ of the points on each axis
//! (`re_renderer`'s `point_cloud_bounds`). Tracking the particles
//! themselves put the camera at about 1.7 cloth radii (the radius of the
//! cloth's bounding box), too close for the view's 55° field of view: a
//! flag seen at an angle, or a long sheet, ran past the view's edges.
//!
//! So the view tracks two points instead, at the centre of the cloth's
//! bounding box ± `c` times its half extent. Two points at ±a have a mean
//! ± 2σ of ±2a, so the camera stands 1.5 · 2 · c cloth radii away:
//! [`DISTANCE`] radii for `c = DISTANCE / 3`. The points are drawn with a
//! radius of zero (at most a half-covered pixel, inside the cloth's box)
//! and take no clicks.

use glam::Vec3;

/// How far the camera stands from the centre of the cloth, in radii of its
/// bounding box: the whole box fits in the view's 55° height from any
/// side (`1 / sin 27.5°` is 2.17), with a little margin.
pub const DISTANCE: f32 = 2.3;

/// The two points the debugger's camera tracks for the cloth's world
/// positions `x` (none for an empty or non-finite cloth).
pub fn points(x: &[Vec3]) -> Option<[Vec3; 2]> {
    let (lo, hi) = x.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let (centre, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let a = half * (DISTANCE / 3.0);
    Some([centre - a, centre + a])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The distance the viewer keeps when it starts tracking points `p`:
    /// 1.5 times the half diagonal of their mean ± 2σ per axis.
    fn tracking_distance(p: &[Vec3]) -> f32 {
        let n = p.len() as f32;
        let mean = p.iter().sum::<Vec3>() / n;
        let var = p.iter().map(|q| (*q - mean) * (*q - mean)).sum::<Vec3>() / n;
        let sigma = Vec3::new(var.x.sqrt(), var.y.sqrt(), var.z.sqrt());
        1.5 * (2.0 * sigma).length()
    }

    #[test]
    fn the_camera_stands_distance_radii_back() {
        // A 2 m × 1 m sheet, hanging in the XZ plane, off the origin.
        let mut x = Vec::new();
        for i in 0..=20 {
            for j in 0..=10 {
                x.push(Vec3::new(5.0 + i as f32 * 0.1, 3.0, 1.0 + j as f32 * 0.1));
            }
        }
        let radius = Vec3::new(1.0, 0.0, 0.5).length();
        let p = points(&x).unwrap();
        assert!(((p[0] + p[1]) * 0.5 - Vec3::new(6.0, 3.0, 1.5)).length() < 1e-5);
        let d = tracking_distance(&p);
        assert!((d - DISTANCE * radius).abs() < 1e-4, "{d}");
        // Tracking the particles themselves stood about 1.7 radii back.
        let before = tracking_distance(&x) / radius;
        assert!((1.6..1.9).contains(&before), "{before}");
    }

    #[test]
    fn no_points_for_no_cloth() {
        assert_eq!(points(&[]), None);
        assert_eq!(points(&[Vec3::NAN]), None);
    }
}
