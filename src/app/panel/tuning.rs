//! The live settings: the solver's parameters, the wind and the telemetry,
//! each edit validated like a preset value before it is sent.

use egui::{RichText, Slider, SliderClamping};

use super::{Panel, Place};
use crate::app::session::{Command, Session};
use crate::scene::{
    Tuning,
    preset::{ColorBy, Level, TelemetrySettings, WindSection},
};
use crate::solver::{Family, Params, Width};

impl Panel {
    /// Sends the tuning if it validates (`Tuning::validate`), else restores
    /// the last good one and shows why.
    fn commit(&mut self, session: &Session, before: Tuning, place: Place) {
        if self.tuning == before {
            return;
        }
        match self.tuning.validate() {
            Ok(()) => {
                session.send(Command::Tune(self.tuning));
                self.valid_input();
            }
            Err(e) => {
                self.say(place, false, e.to_string());
                self.tuning = before;
            }
        }
    }

    pub(super) fn solver_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Solver").strong());
        let before = self.tuning;
        // Every field, by name: a new parameter without a control here does
        // not compile.
        let Params {
            damping,
            weights,
            phi,
            h,
            iterations,
            dt,
            substeps,
        } = &mut self.tuning.solver;
        let free = SliderClamping::Never;
        ui.add(slider(damping, 0.0..=1.0).clamping(free).text("k damping"));
        for f in Family::ALL {
            ui.add(
                slider(&mut weights[f], 0.0..=1.0)
                    .clamping(free)
                    .text(format!("λ {}", f.name())),
            );
        }
        ui.add(
            slider(phi, 0.0..=std::f32::consts::PI)
                .clamping(free)
                .text("Φ cap (rad)"),
        );
        ui.horizontal(|ui| {
            let mut auto = *h == Width::Auto;
            if ui.checkbox(&mut auto, "h auto").changed() {
                *h = if auto {
                    Width::Auto
                } else {
                    Width::Fixed(0.001)
                };
            }
            if let Width::Fixed(h) = h {
                ui.add(
                    slider(h, 0.0..=0.1)
                        .logarithmic(true)
                        .clamping(free)
                        .text("h"),
                );
            }
        });
        ui.add(slider(iterations, 1..=50).clamping(free).text("iterations"));
        ui.add(slider(dt, 0.001..=0.05).clamping(free).text("Δt (s)"));
        ui.add(slider(substeps, 1..=32).clamping(free).text("substeps"));
        self.commit(session, before, Place::Solver);
        self.message_ui(ui, Place::Solver);
    }

    pub(super) fn wind_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Wind").strong());
        let before = self.tuning;
        let WindSection {
            velocity,
            gust,
            gust_period,
            sway,
        } = &mut self.tuning.wind;
        ui.horizontal(|ui| {
            ui.label("velocity");
            for (v, axis) in [
                (&mut velocity.x, "x "),
                (&mut velocity.y, "y "),
                (&mut velocity.z, "z "),
            ] {
                ui.add(drag(v).speed(0.1).prefix(axis));
            }
        });
        ui.add(slider(gust, 0.0..=20.0).text("gust (m/s)"));
        ui.add(slider(gust_period, 0.0..=10.0).text("gust period (s)"));
        ui.add(slider(sway, 0.0..=90.0).text("sway (°)"));
        self.commit(session, before, Place::Wind);
        self.message_ui(ui, Place::Wind);
    }

    pub(super) fn telemetry_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        ui.label(RichText::new("Telemetry").strong());
        let before = self.telemetry;
        let TelemetrySettings {
            level,
            log_every,
            arrow_threshold,
            arrow_scale,
            color_by,
            corrections,
        } = &mut self.telemetry;
        egui::ComboBox::from_label("level")
            .selected_text(format!("{level:?}").to_lowercase())
            .show_ui(ui, |ui| {
                for l in [Level::Off, Level::Summary, Level::Full] {
                    ui.selectable_value(level, l, format!("{l:?}").to_lowercase());
                }
            });
        egui::ComboBox::from_label("colour by")
            .selected_text(color_by.name().into_owned())
            .show_ui(ui, |ui| {
                for c in ColorBy::all() {
                    ui.selectable_value(color_by, c, c.name().into_owned());
                }
            });
        ui.add(
            drag(log_every)
                .range(1..=1000)
                .prefix("log every ")
                .suffix(" frames"),
        );
        if ui
            .checkbox(&mut self.arrows, "correction arrows")
            .on_hover_text(
                "Draw each family's δx and δθ (level full), of the families ticked below",
            )
            .changed()
        {
            session.send(Command::Arrows(self.arrows));
        }
        ui.horizontal_wrapped(|ui| {
            ui.label("corrections:");
            for f in Family::ALL {
                ui.checkbox(&mut corrections[f], f.name());
            }
        });
        ui.add(
            slider(arrow_scale, 0.1..=500.0)
                .logarithmic(true)
                .text("arrow scale"),
        );
        ui.add(slider(arrow_threshold, 0.0..=0.01).text("arrow threshold"));
        if self.telemetry != before {
            session.send(Command::Telemetry(self.telemetry));
            self.valid_input();
        }
    }
}

/// A slider whose value, typed, is taken on Enter or when the field loses
/// focus (dragging still applies as it moves).
pub(super) fn slider<Num: egui::emath::Numeric>(
    value: &mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> Slider<'_> {
    Slider::new(value, range).update_while_editing(false)
}

/// A number field whose value, typed, is taken on Enter or when it loses
/// focus.
fn drag<Num: egui::emath::Numeric>(value: &mut Num) -> egui::DragValue<'_> {
    egui::DragValue::new(value).update_while_editing(false)
}
