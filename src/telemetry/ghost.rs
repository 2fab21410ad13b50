//! The ghost: another run's cloth drawn faint in the same 3D view, so that
//! what a change did is seen beside the cloth, not only in the plots.
//!
//! The desktop debugger draws a branch's parent this way: the parent's
//! world positions at the frame the branch shows, as a translucent mesh at
//! [`paths::GHOST`], beside the branch's own cloth. The ghost has the
//! cloth's triangles (logged once, static, with its colour) and, at each
//! frame, its vertex positions and normals; the normals are computed here
//! from the triangles (each vertex's the area-weighted sum of its
//! triangles'), since only positions are kept of the other run. A ghost
//! turned off, or at a frame the other run never reached, is logged empty,
//! which clears it (the viewer shows each entity's latest data).

use glam::Vec3;
use rerun::{RecordingStream, RecordingStreamResult};

use super::{batch, paths};

/// The ghost's colour: a pale blue-grey at a third opacity, faint beside
/// the sand cloth and the strain-coloured dots.
pub const COLOR: [u8; 4] = [170, 200, 235, 85];

/// Logs what the ghost keeps: the cloth's triangles, and the colour.
pub fn log_static(rec: &RecordingStream, triangles: &[[u32; 3]]) -> RecordingStreamResult<()> {
    let [r, g, b, a] = COLOR;
    rec.log_static(
        paths::GHOST,
        &rerun::Mesh3D::update_fields()
            .with_triangle_indices(triangles.to_vec())
            .with_albedo_factor(rerun::Rgba32::from_unmultiplied_rgba(r, g, b, a)),
    )
}

/// Logs the ghost at `frame` (simulated time `time`): the other run's
/// world `positions` then, or nothing (`None`, or empty), which clears it.
pub fn log(
    rec: &RecordingStream,
    frame: u64,
    time: f64,
    positions: Option<&[Vec3]>,
    triangles: &[[u32; 3]],
) -> RecordingStreamResult<()> {
    rec.set_time_sequence(paths::FRAME, frame as i64);
    rec.set_duration_secs(paths::SIM_TIME, time);
    let positions = positions.unwrap_or(&[]);
    rec.log(
        paths::GHOST,
        &batch::mesh_update(positions, &normals(positions, triangles)),
    )
}

/// Each vertex's normal: the sum of its triangles' (area-weighted, as the
/// cross product of two edges is), normalised; zero for a vertex of no
/// triangle, or of triangles of no area.
pub fn normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let (Some(&pa), Some(&pb), Some(&pc)) =
            (positions.get(a), positions.get(b), positions.get(c))
        else {
            continue;
        };
        let face = (pb - pa).cross(pc - pa);
        for i in [a, b, c] {
            n[i] += face;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_sheet_s_normals_face_the_way_its_triangles_turn() {
        // Two triangles of the unit square in the XY plane, counter-clockwise
        // seen from +Z.
        let x = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let n = normals(&x, &[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(n, vec![Vec3::Z; 4]);
        // Turned over, they face the other way.
        let n = normals(&x, &[[0, 2, 1], [0, 3, 2]]);
        assert_eq!(n, vec![-Vec3::Z; 4]);
    }

    #[test]
    fn a_fold_s_crease_has_the_mean_normal() {
        // Two unit right triangles meeting at a right angle along the Y
        // axis: the crease's vertices get the bisector, the others their
        // own triangle's normal.
        let x = [Vec3::ZERO, Vec3::Y, Vec3::X, Vec3::Z];
        let n = normals(&x, &[[0, 2, 1], [0, 1, 3]]);
        let bisector = Vec3::new(1.0, 0.0, 1.0).normalize();
        assert!((n[0] - bisector).length() < 1e-6, "{:?}", n[0]);
        assert!((n[1] - bisector).length() < 1e-6, "{:?}", n[1]);
        assert_eq!(n[2], Vec3::Z);
        assert_eq!(n[3], Vec3::X);
    }

    #[test]
    fn missing_vertices_and_degenerate_triangles_give_zero() {
        let x = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        // Collinear, and a triangle naming a vertex that is not there.
        let n = normals(&x, &[[0, 1, 2], [0, 1, 7]]);
        assert_eq!(n, vec![Vec3::ZERO; 3]);
        assert!(normals(&[], &[[0, 1, 2]]).is_empty());
    }
}
