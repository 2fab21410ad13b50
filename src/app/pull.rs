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

use std::sync::Mutex;

use glam::{DVec3, Quat, Vec2, Vec3};

use re_viewer::external::re_chunk_store::MissingChunkReporter;
use re_viewer::external::re_log_types::EntityPath;
use re_viewer::external::re_view_spatial::SpatialViewState;
use re_viewer::external::re_viewer_context::{
    IdentifiedViewSystem, ItemContext, ViewContext, ViewContextSystem,
    ViewContextSystemOncePerFrameResult, ViewQuery, ViewSystemIdentifier,
};

use crate::scene::Scene;
use crate::solver::{Pull, portable};
use crate::telemetry::paths;

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

/// What the probe saw at the last drawing of a 3D view.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Probed {
    /// The view's camera.
    pub eye: Option<Eye>,
    /// The point of the scene under the pointer, and whether it is on the
    /// cloth (its particles or its mesh).
    pub hovered: Option<(Vec3, bool)>,
    /// Whether the pointer is over a 3D view (on the scene or not).
    pub over_view: bool,
}

/// What the probe last saw, for the window (the viewer builds its systems
/// itself, from their `Default`: a shared place is how they report).
pub static PROBED: Mutex<Probed> = Mutex::new(Probed {
    eye: None,
    hovered: None,
    over_view: false,
});

/// The window's side of a Ctrl-drag: takes the press from the viewer's
/// input ([`Gesture::take_events`]), then grabs, moves the target and lets
/// go through the session ([`Gesture::update`]).
#[derive(Clone, Debug, Default)]
pub struct Gesture {
    /// A Ctrl-press on the cloth not yet turned into a grab: where.
    pressed: Option<Vec2>,
    /// The drag under way.
    drag: Option<Drag>,
    /// Whether the button was released during the drag.
    released: bool,
    /// Whether the button's press was taken from the viewer (its release
    /// is taken too).
    taken: bool,
    /// The modifier keys held, as last reported.
    held: egui::Modifiers,
}

/// A drag under way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// How far in front of the camera the grabbed point was: the plane the
    /// target moves in faces the camera at that depth, and moves with it
    /// (a camera that follows a carried cloth carries the plane along).
    pub depth: f32,
    /// The 3D view's rectangle on the screen.
    pub rect: (Vec2, Vec2),
    /// The last target sent.
    pub target: Vec3,
}

impl Gesture {
    /// A drag of `point`, seen by `eye` in the view drawn in `rect` (for
    /// tests; the window starts one with a press).
    pub fn dragging(eye: &Eye, point: Vec3, rect: (Vec2, Vec2)) -> Self {
        Self {
            drag: Some(Drag {
                depth: (point - eye.position).dot(eye.forward()),
                rect,
                target: point,
            }),
            ..Self::default()
        }
    }

    /// Takes the gesture's button events out of the window's input before
    /// the viewer sees them: a press of the primary button with Ctrl (⌘ on
    /// a Mac) while the probe has the pointer over a 3D view, and that
    /// button's release. So the viewer neither selects nor turns its
    /// camera; the pointer's moves still reach it. (A press off the cloth
    /// grabs nothing.)
    pub fn take_events(&mut self, events: &mut Vec<egui::Event>) {
        let over_view = || PROBED.lock().expect("not poisoned").over_view;
        events.retain(|e| match e {
            egui::Event::ModifiersChanged(m) => {
                self.held = *m;
                true
            }
            egui::Event::PointerButton {
                pos,
                button: egui::PointerButton::Primary,
                pressed: true,
                modifiers,
            } if (modifiers.command || self.held.command) && !self.taken && over_view() => {
                self.pressed = Some(Vec2::new(pos.x, pos.y));
                self.taken = true;
                self.released = false;
                false
            }
            egui::Event::PointerButton {
                button: egui::PointerButton::Primary,
                pressed: false,
                ..
            } if self.taken => {
                self.taken = false;
                self.released = true;
                false
            }
            _ => true,
        });
    }

    /// Turns the gesture into the session's commands, once a frame after
    /// the viewer has drawn: a press grabs the particle nearest the point
    /// under the pointer, a move sends the new target, a release lets go.
    pub fn update(&mut self, ctx: &egui::Context, session: &super::session::Session) {
        use super::session::Command;
        let probed = PROBED.lock().expect("not poisoned").clone();
        if let Some(at) = self.pressed.take()
            && let Some(eye) = probed.eye
        {
            let rects = widget_rects(ctx, at);
            match probed.hovered {
                // On the cloth: the particle nearest the point under the
                // pointer.
                Some((point, true)) => {
                    if let Some(rect) = view_rect(&eye, rects, at, point) {
                        re_log::debug!("Ctrl-drag: grabbing the cloth at {point}");
                        self.drag = Self::dragging(&eye, point, rect).drag;
                        session.send(Command::Grab(point.to_array()));
                    }
                }
                // Beside it (it moved from under the pointer): the
                // particle nearest the pointer's ray, in the one view
                // there; the plane's depth comes with the pull.
                _ => {
                    if let [rect] = rects[..] {
                        let (origin, dir) = eye.ray(rect, at);
                        re_log::debug!("Ctrl-drag: grabbing the cloth along {dir}");
                        self.drag = Some(Drag {
                            depth: f32::NAN,
                            rect,
                            target: origin,
                        });
                        session.send(Command::GrabAlong(origin.to_array(), dir.to_array()));
                    }
                }
            }
        }
        if let Some(drag) = &mut self.drag
            && drag.depth.is_nan()
            && let (Some(eye), Some(pull)) = (probed.eye, session.status().pull)
        {
            drag.depth = (pull.at.as_vec3() - eye.position).dot(eye.forward());
            drag.target = pull.target.as_vec3();
        }
        if std::mem::take(&mut self.released) {
            if self.drag.take().is_some() {
                re_log::debug!("Ctrl-drag: letting go");
                session.send(Command::Release);
            }
            return;
        }
        let (Some(eye), Some(pointer)) = (probed.eye, ctx.input(|i| i.pointer.latest_pos())) else {
            return;
        };
        let pointer = Vec2::new(pointer.x, pointer.y);
        if let Some(target) = self.target(&eye, pointer).filter(|t| t.is_finite())
            && let Some(drag) = &mut self.drag
            && target.distance(drag.target) > 1e-4
        {
            drag.target = target;
            session.send(Command::PullTo(target.as_dvec3().to_array()));
        }
    }

    /// Where the target is with the pointer at `pointer` and the camera at
    /// `eye`: where the pointer's ray meets the plane facing the camera at
    /// the grabbed point's depth.
    pub fn target(&self, eye: &Eye, pointer: Vec2) -> Option<Vec3> {
        let d = self.drag?;
        let (origin, dir) = eye.ray(d.rect, pointer);
        let forward = eye.forward();
        on_plane(origin, dir, eye.position + forward * d.depth, forward)
    }
}

/// The rectangles of the widgets under `at` in the window's last frame
/// that take clicks and drags, as a 3D view does (the panels and
/// containers around it take neither).
fn widget_rects(ctx: &egui::Context, at: Vec2) -> Vec<(Vec2, Vec2)> {
    let at = egui::pos2(at.x, at.y);
    ctx.viewport(|v| {
        v.prev_pass
            .widgets
            .layers()
            .flat_map(|(_, widgets)| widgets.iter())
            .filter(|w| w.rect.contains(at) && w.sense.senses_click() && w.sense.senses_drag())
            .map(|w| {
                (
                    Vec2::new(w.rect.min.x, w.rect.min.y),
                    Vec2::new(w.rect.max.x, w.rect.max.y),
                )
            })
            .collect()
    })
}

/// Of the rectangles `rects` (screen corners), the one whose ray through
/// `pointer` passes nearest `point`, the scene's point under the pointer:
/// the 3D view the pointer is over (the viewer says which point is under
/// the pointer, not where its view is drawn).
pub fn view_rect(
    eye: &Eye,
    rects: impl IntoIterator<Item = (Vec2, Vec2)>,
    pointer: Vec2,
    point: Vec3,
) -> Option<(Vec2, Vec2)> {
    rects
        .into_iter()
        .filter(|(a, b)| b.x > a.x && b.y > a.y)
        .map(|r| {
            let (o, d) = eye.ray(r, pointer);
            let off = (point - o) - d * (point - o).dot(d);
            (off.length(), r)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, r)| r)
}

/// The context system the window adds to the viewer's 3D view class: at
/// each drawing of a 3D view it notes the view's camera and the point of
/// the scene under the pointer in [`PROBED`] (the view's last frame's: the
/// viewer updates both while it draws).
#[derive(Default)]
pub struct Probe;

impl IdentifiedViewSystem for Probe {
    fn identifier() -> ViewSystemIdentifier {
        "WeftPullProbe".into()
    }
}

impl ViewContextSystem for Probe {
    fn execute(
        &mut self,
        ctx: &ViewContext<'_>,
        _missing: &MissingChunkReporter,
        _query: &ViewQuery<'_>,
        _once: &ViewContextSystemOncePerFrameResult,
    ) {
        let Some(state) = ctx.view_state.as_any().downcast_ref::<SpatialViewState>() else {
            return;
        };
        let eye = state.state_3d.eye_state.last_eye.map(|e| Eye {
            position: Vec3::from_array(e.world_from_rub_view.translation().to_array()),
            rotation: Quat::from_array(e.world_from_rub_view.rotation().to_array()),
            fov_y: e.fov_y,
        });
        let hovered = ctx.viewer_ctx.hovered();
        let over_view = hovered
            .iter_item_context()
            .any(|c| matches!(c, ItemContext::ThreeD { .. }));
        let point = hovered.iter_item_context().find_map(|c| match c {
            ItemContext::ThreeD { pos, .. } => *pos,
            _ => None,
        });
        let cloth_paths = [paths::PARTICLES, paths::MESH].map(EntityPath::from);
        let cloth = hovered
            .iter_items()
            .any(|item| item.entity_path().is_some_and(|p| cloth_paths.contains(p)));
        let mut probed = PROBED.lock().expect("not poisoned");
        if eye.is_some() {
            probed.eye = eye;
        }
        probed.hovered = point.map(|p| (Vec3::from_array(p.to_array()), cloth));
        probed.over_view = over_view;
    }
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
