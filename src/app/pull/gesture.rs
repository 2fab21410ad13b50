//! The gesture in the window: the probe the viewer's 3D view runs each
//! frame (its camera and the point under the pointer), and the Ctrl-press
//! and drag taken from the viewer and sent to the session as a grab, its
//! moves and its release.

use std::sync::Mutex;

use glam::{Quat, Vec2, Vec3};

use re_viewer::external::re_chunk_store::MissingChunkReporter;
use re_viewer::external::re_log_types::EntityPath;
use re_viewer::external::re_view_spatial::SpatialViewState;
use re_viewer::external::re_viewer_context::{
    IdentifiedViewSystem, ItemContext, ViewContext, ViewContextSystem,
    ViewContextSystemOncePerFrameResult, ViewQuery, ViewSystemIdentifier,
};

use super::{Eye, on_plane};
use crate::telemetry::paths;

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
    pub fn update(&mut self, ctx: &egui::Context, session: &crate::app::session::Session) {
        use crate::app::session::Command;
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
