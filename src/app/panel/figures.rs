//! What the panel reads out of the run: frame, speed and the largest
//! violations after the last step, the `[expect]` verdicts so far, and one
//! particle's numbers (the inspector).

use egui::{Color32, RichText};

use super::Panel;
use crate::app::session::{Command, Session, Status};
use crate::solver::Family;

impl Panel {
    pub(super) fn readouts_ui(&mut self, ui: &mut egui::Ui, status: &Status) {
        egui::Grid::new("readouts")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let row = |ui: &mut egui::Ui, k: &str, v: String| {
                    ui.label(k);
                    ui.monospace(v);
                    ui.end_row();
                };
                row(
                    ui,
                    "frame",
                    format!("{} ({:.2} s)", status.frame, status.time),
                );
                row(ui, "3D view", self.view_lag(status));
                row(ui, "steps/s", format!("{:.0}", status.steps_per_second));
                row(ui, "step time", format!("{:.2} ms", status.step_ms));
                row(ui, "max strain", format!("{:.4}", status.max_strain));
                for (f, v) in status.max_violation.iter() {
                    row(ui, &format!("max {}", f.name()), format!("{v:.4}"));
                }
                row(ui, "crossing edges", status.crossings.to_string());
                row(
                    ui,
                    "checkpoints",
                    format!(
                        "{} (every {} frames)",
                        status.checkpoints.0, status.checkpoints.1
                    ),
                );
                if let Some(heap) = re_memory::accounting_allocator::global_allocs() {
                    ui.label("memory").on_hover_text(
                        "the heap (the viewer's recordings, the runs' checkpoints, the solver); \
                         past the limit (--memory-limit) the viewer drops its oldest data",
                    );
                    let mb = |b: usize| b as f64 / 1e6;
                    ui.monospace(format!("{:.0} MB of {}", mb(heap.size), self.memory_limit));
                    ui.end_row();
                }
            });
        ui.label(RichText::new(format!("run {}", status.run.name)).small())
            .on_hover_text(format!(
                "Rerun recording {}; {} runs in this session (the viewer's recording list)",
                status.run.recording_id,
                status.runs.len()
            ));
    }

    /// Where the viewer's time cursor is against the simulation: weft's
    /// own measure of how far behind the picture is, in simulated seconds
    /// (Rerun's "Latency", in its top bar, counts wall-clock seconds from
    /// logging to the viewer, which include the time a simulation held
    /// back by a slow viewer waits).
    fn view_lag(&self, status: &Status) -> String {
        let cursor = self.link.lock().expect("not poisoned").cursor.clone();
        let dt = status.preset.as_ref().map_or(0.0, |p| p.solver.dt) as f64;
        match cursor {
            Some((id, at)) if id == status.run.recording_id => {
                let shown = match at {
                    crate::app::session::BranchAt::Frame(f) => f as f64 * dt,
                    crate::app::session::BranchAt::Time(t) => t,
                };
                let behind = status.time - shown;
                if behind.abs() < 0.5 * dt {
                    format!("{shown:.2} s, this frame")
                } else {
                    format!("{shown:.2} s, {behind:.2} s behind")
                }
            }
            Some(_) => "another run".into(),
            None => "—".into(),
        }
    }

    /// The preset's `[expect]` bounds against the run so far.
    pub(super) fn verdicts_ui(&mut self, ui: &mut egui::Ui, status: &Status) {
        ui.label(RichText::new("Verdicts").strong())
            .on_hover_text("the preset's [expect] bounds against this run's values so far");
        if status.checks.is_empty() {
            ui.label("no [expect] bounds in this preset");
            return;
        }
        egui::Grid::new("verdicts")
            .num_columns(4)
            .striped(true)
            .show(ui, |ui| {
                for c in &status.checks {
                    ui.label(c.bound.trim_start_matches("expect."));
                    ui.monospace(figure(c.value));
                    ui.monospace(format!("≤ {}", figure(c.limit)));
                    if c.ok {
                        ui.colored_label(Color32::from_rgb(110, 190, 110), "ok");
                    } else {
                        ui.colored_label(Color32::from_rgb(230, 80, 70), "FAIL");
                    }
                    ui.end_row();
                }
            });
    }

    /// One particle's numbers: pick it in the 3D view, or type its index.
    pub(super) fn inspector_ui(&mut self, ui: &mut egui::Ui, session: &Session, status: &Status) {
        ui.label(RichText::new("Particle").strong())
            .on_hover_text("click a particle in the 3D view, or type its index");
        let n = status
            .preset
            .as_ref()
            .map_or(1, |p| (p.cloth.weft * p.cloth.warp) as usize);
        ui.horizontal(|ui| {
            let mut changed = ui
                .checkbox(&mut self.inspecting, "inspect particle")
                .changed();
            changed |= ui
                .add(
                    egui::DragValue::new(&mut self.particle)
                        .range(0..=n.saturating_sub(1))
                        .update_while_editing(false),
                )
                .changed();
            if changed {
                session.send(Command::Inspect(self.inspecting.then_some(self.particle)));
            }
        });
        let Some(p) = status.particle.as_ref().filter(|_| self.inspecting) else {
            return;
        };
        ui.monospace(format!(
            "#{}  (i, j) = ({}, {})   strain {:.4}",
            p.index, p.cell.0, p.cell.1, p.strain
        ));
        let offset = p.normal_offset.to_degrees();
        let turned = if offset > 90.0 { ", turned over" } else { "" };
        ui.monospace(format!("normal {offset:.1}° off the surface's{turned}"))
            .on_hover_text(
                "the angle between the element's normal and the surface its neighbours make",
            );
        egui::Grid::new("particle")
            .num_columns(4)
            .striped(true)
            .show(ui, |ui| {
                ui.label("family");
                ui.label("violation");
                ui.label("|δx| (mm)");
                ui.label("|δθ| (mrad)");
                ui.end_row();
                // Until a step records them (at level summary, the step
                // after the particle is picked), the corrections read "–".
                let correction = |ui: &mut egui::Ui, v: glam::Vec3| {
                    if p.corrections {
                        ui.monospace(format!("{:.4}", v.length() * 1e3));
                    } else {
                        ui.monospace("–")
                            .on_hover_text("recorded from the next step");
                    }
                };
                for f in Family::ALL {
                    ui.label(f.name());
                    ui.monospace(format!("{:.4}", p.violation[f]));
                    correction(ui, p.dx[f]);
                    correction(ui, p.dtheta[f]);
                    ui.end_row();
                }
            });
    }
}

/// A figure as a person reads it: four decimals in the usual range,
/// scientific notation only for the very small or large.
fn figure(v: f64) -> String {
    if v == 0.0 || (1e-3..1e4).contains(&v.abs()) {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}
