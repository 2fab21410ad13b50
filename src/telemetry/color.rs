//! Colours: one per constraint family, and a colour map for particles.

use glam::Vec3;
use rerun::Color;

use crate::scene::{Scene, preset::ColorBy};
use crate::solver::Family;

/// The colour of a family, in plots and arrows.
pub fn family(f: Family) -> Color {
    let [r, g, b] = f.color();
    Color::from_rgb(r, g, b)
}

/// A blue → green → yellow → red ramp for `t ∈ [0, 1]`.
pub fn ramp(t: f32) -> Color {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let stops = [
        Vec3::new(40.0, 60.0, 200.0),
        Vec3::new(40.0, 190.0, 160.0),
        Vec3::new(150.0, 220.0, 60.0),
        Vec3::new(250.0, 200.0, 40.0),
        Vec3::new(230.0, 50.0, 40.0),
    ];
    let f = t * (stops.len() - 1) as f32;
    let k = (f.floor() as usize).min(stops.len() - 2);
    let c = stops[k].lerp(stops[k + 1], f - k as f32);
    Color::from_rgb(c.x as u8, c.y as u8, c.z as u8)
}

/// Per-particle colours for `by`, each scaled to a fixed, documented range
/// so colours mean the same from frame to frame: strain 0 → 10 %, speed
/// 0 → 10 m/s, correction (all families, or one) 0 → 1 mm, the normal's
/// offset from the surface's 0 → 180°.
pub fn particles(by: ColorBy, scene: &Scene) -> Vec<Color> {
    let solver = scene.solver();
    let state = solver.state();
    let n = state.len();
    match by {
        ColorBy::None => vec![Color::from_rgb(220, 200, 160); n],
        ColorBy::Strain => solver
            .particle_strain()
            .iter()
            .map(|s| ramp(s / 0.1))
            .collect(),
        ColorBy::NormalOffset => solver
            .normal_offsets()
            .iter()
            .map(|a| ramp(a / std::f32::consts::PI))
            .collect(),
        ColorBy::Speed => {
            // World speed: the particle's motion plus the origin's.
            let dt = solver.params().substep_dt();
            let frame = solver.frame().shift.as_vec3();
            (0..n)
                .map(|i| {
                    let d = state.position[i] - state.prev_position[i] + frame;
                    ramp(d.length() / dt / 10.0)
                })
                .collect()
        }
        ColorBy::Correction | ColorBy::CorrectionOf(_) => match solver.diagnostics() {
            None => vec![Color::from_rgb(220, 200, 160); n],
            Some(d) => (0..n)
                .map(|i| {
                    let total: f32 = match by.family() {
                        Some(f) => d.family(f).dx[i].length(),
                        None => d.families.iter().map(|(_, f)| f.dx[i].length()).sum(),
                    };
                    ramp(total / 1e-3)
                })
                .collect(),
        },
    }
}
