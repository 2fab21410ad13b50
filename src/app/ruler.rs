//! A drag on the viewer's time ruler moves the time cursor, as it does
//! everywhere else in the time panel, instead of making a loop selection.
//!
//! In the expanded time panel of Rerun 0.36, pressing and dragging on the
//! ruler (the strip of time ticks at the top) starts a time selection and
//! turns on looping over it (`re_time_panel`'s `loop_selection_ui`: "drags
//! in the timeline rect should create loop selections"; no setting turns
//! this off). In the debugger that is a trap: whoever drags there to scrub
//! is left with the viewer replaying a few frames in a loop, no longer
//! following the simulation, and the panel's branch frame jumping with it.
//! The viewer cannot be told not to, and weft cannot read its time
//! selection to clear it; but the window sees the pointer before the
//! viewer does. So a press that lands on the ruler is moved down, at the
//! same x, into the area just under it, where the time panel scrubs
//! (`time_marker_ui`: a press there sets the time cursor at the pointer's
//! x, and a drag moves it), and so is the rest of that drag, until the
//! button is released.
//!
//! The ruler is found among the widgets egui placed in the last frame by
//! the ids the time panel gives them: the ruler `timeline` and the area
//! under it `time_area_interact`, both salted with the id of the time
//! panel's `Ui` ([`find`]). With the time panel collapsed (as the debugger
//! opens it) there is no ruler, and nothing is moved.

use egui::{Event, Pos2, Rect, WidgetRects};

/// The id salts the time panel gives its ruler and the area under it.
const RULER: &str = "timeline";
const UNDER: &str = "time_area_interact";

/// How far below the ruler's bottom edge a moved press lands, in points.
const DROP: f32 = 4.0;

/// The ruler and the area under it, as egui placed them in the last frame.
pub fn find(widgets: &WidgetRects) -> Option<(Rect, Rect)> {
    widgets.layers().find_map(|(_, layer)| {
        layer.iter().find_map(|w| {
            if w.id != w.parent_id.with(RULER) {
                return None;
            }
            let under = widgets.get(w.parent_id.with(UNDER))?;
            Some((w.interact_rect, under.interact_rect))
        })
    })
}

/// A drag that began on the ruler, moved into the area under it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scrub {
    /// While the press that began on the ruler is held: how far down its
    /// pointer events are moved.
    shift: Option<f32>,
}

impl Scrub {
    /// Moves the pointer events of a press on `ruler` (and of the drag that
    /// follows, until the button is released) into `under`, at the same x.
    /// `None`: no ruler on screen (a drag already moved still is, to its
    /// end).
    pub fn remap(&mut self, events: &mut [Event], ruler: Option<(Rect, Rect)>) {
        for event in events {
            match event {
                Event::PointerButton {
                    pos,
                    button: egui::PointerButton::Primary,
                    pressed: true,
                    ..
                } if self.shift.is_none() => {
                    if let Some((ruler, under)) = ruler
                        && ruler.contains(*pos)
                        && under.height() > 0.0
                    {
                        let y = (ruler.bottom() + DROP)
                            .min(under.center().y)
                            .max(under.top());
                        self.shift = Some(y - pos.y);
                    }
                    self.apply(pos);
                }
                Event::PointerButton {
                    pos,
                    button: egui::PointerButton::Primary,
                    pressed: false,
                    ..
                } => {
                    self.apply(pos);
                    self.shift = None;
                }
                Event::PointerButton { pos, .. } | Event::PointerMoved(pos) => self.apply(pos),
                Event::PointerGone => self.shift = None,
                _ => {}
            }
        }
    }

    /// Whether a drag that began on the ruler is under way.
    pub fn active(&self) -> bool {
        self.shift.is_some()
    }

    fn apply(&self, pos: &mut Pos2) {
        if let Some(dy) = self.shift {
            pos.y += dy;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Modifiers, PointerButton, pos2, vec2};

    fn button(x: f32, y: f32, pressed: bool) -> Event {
        Event::PointerButton {
            pos: pos2(x, y),
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        }
    }

    const RULER_RECT: Rect = Rect::from_min_max(pos2(100.0, 600.0), pos2(900.0, 620.0));
    const UNDER_RECT: Rect = Rect::from_min_max(pos2(100.0, 620.0), pos2(900.0, 800.0));

    #[test]
    fn a_drag_on_the_ruler_is_moved_under_it_until_released() {
        let mut scrub = Scrub::default();
        let ruler = Some((RULER_RECT, UNDER_RECT));
        let mut events = vec![
            Event::PointerMoved(pos2(300.0, 610.0)),
            button(300.0, 610.0, true),
            Event::PointerMoved(pos2(350.0, 612.0)),
        ];
        scrub.remap(&mut events, ruler);
        assert!(scrub.active());
        // The hover before the press stays where it was.
        assert_eq!(events[0], Event::PointerMoved(pos2(300.0, 610.0)));
        assert_eq!(events[1], button(300.0, 624.0, true));
        assert_eq!(events[2], Event::PointerMoved(pos2(350.0, 626.0)));
        // Later frames, wherever the pointer goes, until the release.
        let mut events = vec![
            Event::PointerMoved(pos2(500.0, 400.0)),
            button(500.0, 400.0, false),
            Event::PointerMoved(pos2(510.0, 610.0)),
        ];
        scrub.remap(&mut events, None);
        assert_eq!(events[0], Event::PointerMoved(pos2(500.0, 414.0)));
        assert_eq!(events[1], button(500.0, 414.0, false));
        assert_eq!(events[2], Event::PointerMoved(pos2(510.0, 610.0)));
        assert!(!scrub.active());
    }

    #[test]
    fn presses_elsewhere_and_other_buttons_are_left_alone() {
        let mut scrub = Scrub::default();
        let ruler = Some((RULER_RECT, UNDER_RECT));
        let secondary = Event::PointerButton {
            pos: pos2(300.0, 610.0),
            button: PointerButton::Secondary,
            pressed: true,
            modifiers: Modifiers::NONE,
        };
        let mut events = vec![
            button(300.0, 700.0, true),
            Event::PointerMoved(pos2(300.0, 610.0)),
            button(300.0, 610.0, false),
            secondary.clone(),
        ];
        let before = events.clone();
        scrub.remap(&mut events, ruler);
        assert_eq!(events, before);
        assert!(!scrub.active());
        // No area under the ruler (nothing to scrub in): left alone too.
        let flat = Rect::from_min_size(pos2(100.0, 620.0), vec2(800.0, 0.0));
        let mut events = vec![button(300.0, 610.0, true)];
        scrub.remap(&mut events, Some((RULER_RECT, flat)));
        assert_eq!(events, vec![button(300.0, 610.0, true)]);
    }

    /// The ruler and the area under it are found by the ids the time panel
    /// gives them, under whatever `Ui` it draws them in.
    #[test]
    fn the_ruler_is_found_among_last_frame_s_widgets() {
        let ctx = egui::Context::default();
        let input = egui::RawInput {
            screen_rect: Some(Rect::from_min_size(Pos2::ZERO, vec2(1000.0, 900.0))),
            ..Default::default()
        };
        let mut output = ctx.run_ui(input.clone(), |ui| {
            ui.push_id("somewhere in the viewer", |ui| {
                ui.interact(
                    RULER_RECT,
                    ui.id().with(RULER),
                    egui::Sense::click_and_drag(),
                );
                ui.interact(
                    UNDER_RECT,
                    ui.id().with(UNDER),
                    egui::Sense::click_and_drag(),
                );
            });
        });
        // Nothing draws here: the fonts' texture is not wanted.
        output.textures_delta.clear();
        let found = ctx.viewport(|v| find(&v.prev_pass.widgets));
        assert_eq!(found, Some((RULER_RECT, UNDER_RECT)));
        // A window without the expanded time panel has none.
        let mut output = ctx.run_ui(input, |ui| {
            ui.label("no time panel");
        });
        output.textures_delta.clear();
        assert_eq!(ctx.viewport(|v| find(&v.prev_pass.widgets)), None);
    }
}
