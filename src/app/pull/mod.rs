//! Grabbing the cloth: Ctrl-drag in the 3D view pulls the particle nearest
//! the pointer with a spring towards the pointer, as MuJoCo's `simulate`
//! does with a body.
//!
//! Three parts:
//!
//! - **The session** turns the gesture into a pull ([`crate::solver::pull`])
//!   on the run's tuning: [`Command::Grab`](super::session::Command::Grab)
//!   pulls the particle nearest a point ([`nearest`]) towards where it is,
//!   with a spring [`stiffness`] that suits the cloth;
//!   [`Command::PullTo`](super::session::Command::PullTo) moves the target;
//!   [`Command::Release`](super::session::Command::Release) lets go. Each
//!   is a change of the tuning from the next step, logged at the frame it
//!   takes effect, so a recording with a drag replays bit for bit. Points
//!   come from the frame the viewer shows, which may be a little behind
//!   the simulation's; the session carries them to its frame with the
//!   solver's origin ([`Trail`]).
//! - **The probe**, a context system added to the viewer's 3D view class
//!   ([`Probe`]): each time a 3D view is drawn it notes the view's camera
//!   (the eye: where it is, how it is turned, its field of view) and the
//!   point of the scene under the pointer with the entity there, the
//!   viewer's own picking. The viewer offers these to its views only, so
//!   the probe hands them to the window through [`PROBED`].
//! - **The gesture** ([`Gesture`]), in the window: Ctrl and the primary
//!   button pressed while the pointer is over the cloth grab the particle
//!   nearest the point under it; beside the cloth (it moved from under the
//!   pointer), the particle nearest the pointer's ray ([`grab_along`]).
//!   A Ctrl-press anywhere in a 3D view is taken from the viewer's input,
//!   so the viewer neither selects nor turns its camera (it orbits on a
//!   drag otherwise); the pointer's moves still reach it. While the button is held, the target is where the pointer's ray
//!   meets the plane facing the camera at the grabbed point's depth (it
//!   moves with the camera, which follows a carried cloth): the ray from
//!   the eye through the pointer, within the 3D view's rectangle
//!   ([`Eye::ray`]). Releasing the button lets go.

use glam::{DVec3, Quat, Vec2, Vec3};

use crate::scene::Scene;
use crate::solver::{Pull, portable};

mod gesture;

pub use gesture::{Drag, Gesture, PROBED, Probe, Probed, view_rect};

/// How stiff a grab's spring is, per kilogram of cloth: (2π · 2 Hz)², so
/// the whole cloth, hanging on the spring alone, would swing at about
/// 2 Hz. A flag of 0.3 kg gets 47 N/m: half a metre off, 24 N, eight times
/// its weight.
pub const STIFFNESS_PER_KG: f32 = 158.0;

/// The spring for a grab of `scene`'s cloth (N/m), from its mass.
pub fn stiffness(scene: &Scene) -> f32 {
    let spec = scene.solver().spec();
    STIFFNESS_PER_KG * spec.density * spec.width * spec.height
}

/// The particle nearest `at` (world coordinates) at the scene's frame.
pub fn nearest(scene: &Scene, at: Vec3) -> Option<usize> {
    scene
        .world_positions()
        .iter()
        .enumerate()
        .min_by(|a, b| {
            a.1.distance_squared(at)
                .total_cmp(&b.1.distance_squared(at))
        })
        .map(|(i, _)| i)
}

/// A grab of the particle nearest `at`: pulled towards where it is now
/// (so nothing jumps until the target moves), with the cloth's
/// [`stiffness`].
pub fn grab(scene: &Scene, at: Vec3) -> Option<Pull> {
    let particle = nearest(scene, at)?;
    let local = scene.solver().state().position[particle];
    Some(Pull {
        particle,
        target: scene.solver().frame().world(local),
        stiffness: stiffness(scene),
    })
}

/// How far from the pointer's ray a grab off the cloth's surface reaches,
/// as a share of the cloth's larger side.
pub const RAY_REACH: f32 = 0.25;

/// A grab of the particle nearest the ray from `origin` along the unit
/// vector `dir` (world coordinates), in front of it and within
/// [`RAY_REACH`] of the cloth's larger side: for a press that missed the
/// surface of a cloth that moves under the pointer.
pub fn grab_along(scene: &Scene, origin: Vec3, dir: Vec3) -> Option<Pull> {
    let spec = scene.solver().spec();
    let reach = RAY_REACH * spec.width.max(spec.height);
    let x = scene.world_positions();
    let off = |p: Vec3| {
        let v = p - origin;
        (v - dir * v.dot(dir)).length()
    };
    let (i, d) = (0..x.len())
        .filter(|&i| (x[i] - origin).dot(dir) > 0.0)
        .map(|i| (i, off(x[i])))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    (d <= reach).then(|| grab(scene, x[i])).flatten()
}

/// The pull as the panel and the window see it, after the last step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pulled {
    /// The particle pulled.
    pub particle: usize,
    /// Where it is (world coordinates).
    pub at: DVec3,
    /// Where it is pulled to (world coordinates).
    pub target: DVec3,
}

impl Pulled {
    /// The pull of `scene`, if any.
    pub fn of(scene: &Scene) -> Option<Self> {
        let pull = scene.solver().pull()?;
        let local = scene.solver().state().position[pull.particle];
        Some(Self {
            particle: pull.particle,
            at: scene.solver().frame().world(local),
            target: pull.target,
        })
    }
}

/// Where the solver's origin was at the last frames of a run, so that a
/// point seen in the viewer, which may show a frame a little behind the
/// simulation (at most [`MAX_LEAD`](super::session::MAX_LEAD) while it
/// follows), is carried to the simulation's frame: on a carried cloth
/// (the car flag at 14 m/s) a quarter of a second is 3.5 m.
#[derive(Clone, Debug, Default)]
pub struct Trail {
    /// `(frame, time, origin)`, oldest first, at most [`Trail::LEN`].
    frames: std::collections::VecDeque<(u64, f64, DVec3)>,
}

impl Trail {
    /// Frames kept: more than the viewer lags behind while it follows.
    pub const LEN: usize = 256;

    /// Notes the origin at a frame stepped.
    pub fn note(&mut self, frame: u64, time: f64, origin: DVec3) {
        if self.frames.len() == Self::LEN {
            self.frames.pop_front();
        }
        self.frames.push_back((frame, time, origin));
    }

    /// Forgets every frame (a new run).
    pub fn clear(&mut self) {
        self.frames.clear();
    }

    /// How far the origin moved from the frame `seen` (a frame number, or
    /// the latest frame at a simulated time) to `now`: what to add to a
    /// point seen there. Zero for a frame no longer kept.
    pub fn since(&self, seen: super::session::BranchAt, now: DVec3) -> DVec3 {
        use super::session::BranchAt;
        let found = match seen {
            BranchAt::Frame(f) => self.frames.iter().find(|(k, _, _)| *k == f),
            BranchAt::Time(t) => self.frames.iter().rev().find(|(_, at, _)| *at <= t + 1e-9),
        };
        found.map_or(DVec3::ZERO, |(_, _, origin)| now - *origin)
    }
}

/// A 3D view's camera, as its last drawing had it (world coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eye {
    /// Where it is.
    pub position: Vec3,
    /// Its turn from the view's axes (x right, y up, looking down −z).
    pub rotation: Quat,
    /// The vertical field of view (radians); none for an orthographic one.
    pub fov_y: Option<f32>,
}

impl Eye {
    /// Which way it looks.
    pub fn forward(&self) -> Vec3 {
        self.rotation * Vec3::NEG_Z
    }

    /// The ray (origin, unit direction) from the camera through `pointer`,
    /// a point of the screen within `rect` (`min`, `max` corners), where
    /// the view is drawn. The rectangle's corners span the field of view
    /// vertically and as much horizontally as its shape gives.
    pub fn ray(&self, rect: (Vec2, Vec2), pointer: Vec2) -> (Vec3, Vec3) {
        let size = rect.1 - rect.0;
        // The pointer from the rectangle's centre, in [-1, 1], y up.
        let ndc = Vec2::new(
            2.0 * (pointer.x - rect.0.x) / size.x - 1.0,
            1.0 - 2.0 * (pointer.y - rect.0.y) / size.y,
        );
        match self.fov_y {
            Some(fov) => {
                let (sin, cos) = portable::sin_cos(0.5 * fov);
                let half = sin / cos;
                let d = Vec3::new(ndc.x * half * size.x / size.y, ndc.y * half, -1.0);
                (self.position, (self.rotation * d).normalize_or_zero())
            }
            None => {
                let offset =
                    self.rotation * Vec3::new(0.5 * ndc.x * size.x, 0.5 * ndc.y * size.y, 0.0);
                (self.position + offset, self.forward())
            }
        }
    }
}

/// Where the ray (`origin`, `dir`) meets the plane through `point` facing
/// `normal`; none if it runs along the plane or the plane is behind it.
pub fn on_plane(origin: Vec3, dir: Vec3, point: Vec3, normal: Vec3) -> Option<Vec3> {
    let along = dir.dot(normal);
    if along.abs() < 1e-6 {
        return None;
    }
    let t = (point - origin).dot(normal) / along;
    (t > 0.0).then(|| origin + dir * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ray_through_the_centre_is_the_camera_s_forward() {
        let eye = Eye {
            position: Vec3::new(0.0, -5.0, 1.0),
            rotation: Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            fov_y: Some(1.0),
        };
        let rect = (Vec2::new(100.0, 50.0), Vec2::new(500.0, 350.0));
        let (o, d) = eye.ray(rect, Vec2::new(300.0, 200.0));
        assert_eq!(o, eye.position);
        assert!((d - eye.forward()).length() < 1e-6, "{d}");
        // The top edge's centre is half the field of view up.
        let (_, up) = eye.ray(rect, Vec2::new(300.0, 50.0));
        assert!((up.angle_between(d) - 0.5).abs() < 1e-5);
        assert!(up.z > 0.0, "{up}");
    }

    #[test]
    fn a_drag_moves_the_target_in_the_plane_facing_the_camera() {
        let eye = Eye {
            position: Vec3::new(0.0, -5.0, 0.0),
            rotation: Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            fov_y: Some(1.0),
        };
        let rect = (Vec2::ZERO, Vec2::new(400.0, 300.0));
        let point = Vec3::ZERO;
        // The rectangle is found from the point under the pointer.
        let other = (Vec2::new(0.0, 300.0), Vec2::new(400.0, 600.0));
        let found = view_rect(&eye, [other, rect], Vec2::new(200.0, 150.0), point);
        assert_eq!(found, Some(rect));
        let g = Gesture::dragging(&eye, point, rect);
        let right = g.target(&eye, Vec2::new(300.0, 150.0)).unwrap();
        assert!(
            right.x > 0.5 && right.y.abs() < 1e-5 && right.z.abs() < 1e-5,
            "{right}"
        );
        let up = g.target(&eye, Vec2::new(200.0, 100.0)).unwrap();
        assert!(up.z > 0.1 && up.x.abs() < 1e-5, "{up}");
        // A camera that moves (following a carried cloth) carries the
        // plane, and the target under the pointer, along.
        let moved = Eye {
            position: eye.position + Vec3::new(3.0, 0.0, 0.0),
            ..eye
        };
        let carried = g.target(&moved, Vec2::new(300.0, 150.0)).unwrap();
        assert!((carried - right - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn a_point_seen_a_few_frames_back_is_carried_to_now() {
        use crate::app::session::BranchAt;
        let mut trail = Trail::default();
        for f in 0..300u64 {
            trail.note(f, f as f64 / 60.0, DVec3::new(f as f64 * 0.25, 0.0, 0.0));
        }
        let now = DVec3::new(299.0 * 0.25, 0.0, 0.0);
        assert_eq!(
            trail.since(BranchAt::Frame(290), now),
            DVec3::new(2.25, 0.0, 0.0)
        );
        let t = 280.5 / 60.0; // between frames: the one shown is 280
        assert_eq!(
            trail.since(BranchAt::Time(t), now),
            DVec3::new(4.75, 0.0, 0.0)
        );
        assert_eq!(
            trail.since(BranchAt::Frame(10), now),
            DVec3::ZERO,
            "forgotten"
        );
    }

    #[test]
    fn a_ray_beside_the_cloth_grabs_the_particle_nearest_it() {
        let preset = crate::scene::load::load("hanging_sheet", &[])
            .unwrap()
            .preset;
        let scene = Scene::new(&preset).unwrap();
        let x = scene.world_positions();
        // Looking along +y at a point a centimetre beside particle 7.
        let beside = x[7] + Vec3::new(0.01, 0.0, 0.0);
        let from = beside - Vec3::new(0.0, 3.0, 0.0);
        let pull = grab_along(&scene, from, Vec3::Y).unwrap();
        assert_eq!(pull.particle, 7);
        assert_eq!(pull.target.as_vec3(), x[7]);
        // Looking away, or far off to the side: nothing.
        assert_eq!(grab_along(&scene, from, Vec3::NEG_Y), None);
        let far = from + Vec3::new(0.0, 0.0, 10.0);
        assert_eq!(grab_along(&scene, far, Vec3::Y), None);
    }

    #[test]
    fn a_grab_holds_the_nearest_particle_where_it_is() {
        let preset = crate::scene::load::load("hanging_sheet", &[])
            .unwrap()
            .preset;
        let scene = Scene::new(&preset).unwrap();
        let x = scene.world_positions();
        let pull = grab(&scene, x[5] + Vec3::splat(1e-3)).unwrap();
        assert_eq!(pull.particle, 5);
        assert_eq!(pull.target.as_vec3(), x[5]);
        assert!(pull.stiffness > 0.0);
    }
}
