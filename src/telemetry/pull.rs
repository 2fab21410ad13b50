//! The pull drawn: while a particle is pulled (the debugger's Ctrl-drag,
//! [`crate::solver::pull`]), a line from it to the point it is pulled
//! towards, on `world/pull`, at every logged frame; blanked at the first
//! logged frame after it is let go (the viewer shows an entity's latest
//! data, so an entity that simply stopped being logged would stay drawn).

use glam::Vec3;
use rerun::{RecordingStream, RecordingStreamResult};

use super::paths;
use crate::scene::Scene;

/// The line's colour: a hand's, warm against the cloth's ramps.
const COLOR: [u8; 4] = [255, 140, 0, 255];

/// Logs the pull of `scene` as a line from its particle (`x`: the
/// particles in world coordinates) to its target, or blanks the line once
/// there is none. `drawn` says whether the last logged frame drew one.
pub(super) fn log(
    rec: &RecordingStream,
    scene: &Scene,
    x: &[Vec3],
    radius: f32,
    drawn: &mut bool,
) -> RecordingStreamResult<()> {
    match scene.solver().pull() {
        Some(pull) => {
            let from = x[pull.particle].to_array();
            let to = pull.target.as_vec3().to_array();
            rec.log(
                paths::PULL,
                &rerun::LineStrips3D::new([[from, to]])
                    .with_colors([COLOR])
                    .with_radii([0.5 * radius]),
            )?;
            *drawn = true;
        }
        None if std::mem::take(drawn) => {
            rec.log(
                paths::PULL,
                &rerun::LineStrips3D::new(std::iter::empty::<[[f32; 3]; 2]>()),
            )?;
        }
        None => {}
    }
    Ok(())
}
