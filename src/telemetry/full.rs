//! What only level full draws: the cloth's surface and normals, each
//! family's correction arrows, and (in the debugger) the values shown when
//! a particle is hovered; and blanking them once a frame no longer draws
//! them, since the viewer shows each entity's latest data.

use glam::Vec3;
use rerun::RecordingStreamResult;

use super::{Telemetry, batch, color, paths};
use crate::scene::Scene;
use crate::solver::{Diagnostics, Family, PerFamily};

/// What of level full's drawing the viewer still shows: it shows each
/// entity's latest data, so whatever a frame no longer draws (a family
/// whose arrows all fell under the threshold, or everything of level full
/// after a switch to summary) is logged once as empty, and not again.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Drawn {
    /// The mesh's vertices and the normals.
    surface: bool,
    /// The per-particle hover values.
    particle_values: bool,
    /// Per family, its δx and δθ arrows.
    arrows: PerFamily<[bool; 2]>,
}

impl Telemetry {
    /// Draws the surface, the normals (arrows of `2 · radius`), the
    /// corrections and, if asked for, the hover values.
    pub(super) fn log_full(&mut self, scene: &Scene, radius: f32) -> RecordingStreamResult<()> {
        let solver = scene.solver();
        let x = &*scene.world_positions();
        let normals: Vec<Vec3> = (0..x.len()).map(|i| solver.state().normal(i)).collect();
        self.rec
            .log(paths::MESH, &batch::mesh_update(x, &normals))?;
        self.rec.log(
            paths::NORMALS,
            &batch::arrows(x, &normals, 2.0 * radius, f32::INFINITY, |_| true)
                .with_colors([rerun::Color::from_rgb(90, 160, 255)]),
        )?;
        self.drawn.surface = true;
        if let Some(d) = solver.diagnostics() {
            let spec = solver.spec();
            self.log_corrections(x, d, spec.width.max(spec.height))?;
        }
        if self.particle_values {
            self.log_particle_values(scene)?;
        }
        Ok(())
    }

    /// Per-particle values beside the points, so hovering a particle in the
    /// viewer shows them: strain, the normal's angle off the surface's
    /// (radians), each family's violation, and the length
    /// of each family's δx (m) and δθ (rad) in the last adjust (δθ only for
    /// the families that turn elements). Single precision, as the solver
    /// computes them.
    fn log_particle_values(&mut self, scene: &Scene) -> RecordingStreamResult<()> {
        let solver = scene.solver();
        let corrections = solver.diagnostics().filter(|d| d.corrections);
        let lengths = |v: &[Vec3]| f32s(v.iter().map(|v| v.length()).collect());
        let values = hover_values(|value| match value {
            Hover::Strain => Some(f32s(solver.particle_strain())),
            Hover::NormalOffset => Some(f32s(solver.normal_offsets())),
            Hover::Violation(f) => Some(f32s(solver.particle_violation(f))),
            Hover::Dx(f) => corrections.map(|d| lengths(&d.family(f).dx)),
            Hover::Dtheta(f) => corrections.map(|d| lengths(&d.family(f).dtheta)),
        });
        self.drawn.particle_values = true;
        self.rec.log(paths::PARTICLES, &values)
    }

    /// Each family's δx and δθ arrows of at least the threshold's length,
    /// none for a family switched off, each drawn at most `longest` long
    /// (the cloth's longer side): an element turned over turns by up to π in
    /// one sweep, whose arrow at the default scale would be tens of metres
    /// long and pull the viewer's camera, which frames whatever is drawn,
    /// away from the cloth. A family with none to draw logs nothing, unless
    /// it drew some at the last frame: then its empty batch clears them.
    fn log_corrections(
        &mut self,
        x: &[Vec3],
        d: &Diagnostics,
        longest: f32,
    ) -> RecordingStreamResult<()> {
        let (threshold, scale) = (self.settings.arrow_threshold, self.settings.arrow_scale);
        for f in Family::ALL {
            let fd = d.family(f);
            let shown = self.arrows && self.settings.corrections[f];
            for (k, (kind, vectors)) in [("dx", &fd.dx), ("dtheta", &fd.dtheta)]
                .into_iter()
                .enumerate()
            {
                let arrows = batch::arrows(x, vectors, scale, longest, |v| {
                    shown && {
                        let len = v.length();
                        len >= threshold && len > 0.0
                    }
                });
                let any = arrows.vectors.as_ref().is_some_and(|v| !v.array.is_empty());
                if any || self.drawn.arrows[f][k] {
                    self.rec.log(
                        paths::correction(f, kind),
                        &arrows.with_colors([color::family(f)]),
                    )?;
                }
                self.drawn.arrows[f][k] = any;
            }
        }
        Ok(())
    }

    /// Logs as empty what level full drew at the last frame and this frame
    /// does not: the mesh's vertices, the normals, the correction arrows
    /// and the hover values (the mesh's triangles stay: they are static).
    pub(super) fn blank_full(&mut self) -> RecordingStreamResult<()> {
        let rec = &self.rec;
        let drawn = std::mem::take(&mut self.drawn);
        let no_arrows = || batch::arrows(&[], &[], 1.0, f32::INFINITY, |_| true);
        if drawn.surface {
            rec.log(paths::MESH, &batch::mesh_update(&[], &[]))?;
            rec.log(paths::NORMALS, &no_arrows())?;
        }
        for (f, kinds) in drawn.arrows.iter() {
            for (kind, _) in ["dx", "dtheta"].into_iter().zip(kinds).filter(|(_, d)| **d) {
                rec.log(paths::correction(f, kind), &no_arrows())?;
            }
        }
        if drawn.particle_values {
            rec.log(paths::PARTICLES, &hover_values(|_| Some(f32s(Vec::new()))))?;
        }
        Ok(())
    }
}

/// One of the values shown for a hovered particle.
#[derive(Clone, Copy)]
enum Hover {
    Strain,
    NormalOffset,
    Violation(Family),
    Dx(Family),
    Dtheta(Family),
}

/// The hover values, each as `value` gives it (left out where it gives
/// none): `strain`, `normal_offset`, then per family `violation_{family}`,
/// `dx_{family}` and, for the families that turn elements,
/// `dtheta_{family}`.
fn hover_values(
    mut value: impl FnMut(Hover) -> Option<rerun::external::arrow::array::ArrayRef>,
) -> rerun::AnyValues {
    let mut parts = vec![
        (Hover::Strain, "strain".to_string()),
        (Hover::NormalOffset, "normal_offset".to_string()),
    ];
    for f in Family::ALL {
        parts.push((Hover::Violation(f), format!("violation_{}", f.name())));
        parts.push((Hover::Dx(f), format!("dx_{}", f.name())));
        if f.turns() {
            parts.push((Hover::Dtheta(f), format!("dtheta_{}", f.name())));
        }
    }
    let mut values = rerun::AnyValues::default();
    for (part, name) in parts {
        if let Some(array) = value(part) {
            let name = rerun::ComponentIdentifier::try_new(name).expect("not empty");
            values = values.with_component_from_data(name, array);
        }
    }
    values
}

/// A batch of single-precision values, one per particle.
fn f32s(values: Vec<f32>) -> rerun::external::arrow::array::ArrayRef {
    std::sync::Arc::new(rerun::external::arrow::array::Float32Array::from(values))
}
