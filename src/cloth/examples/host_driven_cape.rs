//! A cape on a body the host moves: the preset (written here, as a host
//! would ship it) sews a cape to a static body, `shoulders`; each frame
//! the host puts the shoulders where its own character is, walking a circle
//! of 2 m radius at 1.5 m/s, and the cape follows and swings out. Prints
//! how far the hem trails behind the shoulders, each second.
//!
//! ```sh
//! cargo run -p weft-cloth --example host_driven_cape
//! ```

use glam::DVec3;
use weft_cloth::scene::{Placement, Scene, load};
use weft_cloth::solver::portable::rotation_z;

/// A cape behind the shoulders, sewn along its top edge, with a torso to
/// hang against.
const CAPE: &str = r#"
description = "A cape on shoulders the host moves"
duration = 6.0

[cloth]
width = 0.6
height = 0.9
weft = 14
warp = 20
density = 0.25
position = [-0.16, -0.3, 0.55]
rotation = [90.0, 90.0, 0.0]

[solver]
substeps = 16
iterations = 1

[[bodies]]
name = "shoulders"
[bodies.static]
position = [0.0, 0.0, 0.0]

[[attachments]]
body = "shoulders"
select = ["top"]
clamp = true

[[colliders]]
shape = "capsule"
body = "shoulders"
position = [0.0, 0.0, 0.95]
radius = 0.14
half_length = 0.35
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let preset = load::parse("host_driven_cape", CAPE)?;
    let mut scene = Scene::new(&preset)?;
    let shoulders = scene.body("shoulders").ok_or("the preset has shoulders")?;
    let dt = f64::from(scene.solver().params().dt);
    let (radius, speed) = (2.0, 1.5);
    let per_second = scene.frames_in(1.0);
    for frame in 1..=scene.frames_in(preset.duration) {
        // The host's character at the end of this step: on the circle,
        // facing along it (its local +x forward).
        let angle = speed / radius * frame as f64 * dt;
        let at = Placement {
            translation: DVec3::new(radius * angle.sin(), radius * (1.0 - angle.cos()), 0.0),
            // weft's own sine (the same bits on every machine).
            rotation: rotation_z(angle as f32),
        };
        scene.drive(shoulders, at)?;
        scene.step()?;
        if frame % per_second == 0 {
            let x = scene.world_positions();
            let hem: DVec3 = x.iter().take(14).map(|p| p.as_dvec3()).sum::<DVec3>() / 14.0;
            let trail = (hem - at.translation).truncate().length();
            println!(
                "t = {:3.1} s: shoulders at ({:5.2}, {:5.2}), hem {:4.2} m from them, {:4.2} m up",
                scene.time(),
                at.translation.x,
                at.translation.y,
                trail,
                hem.z
            );
        }
    }
    Ok(())
}
