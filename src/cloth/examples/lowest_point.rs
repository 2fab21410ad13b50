//! The smallest host loop: load the car flag preset, step it, and print the
//! cloth's lowest point each simulated second.
//!
//! ```sh
//! cargo run -p weft-cloth --example lowest_point
//! ```

use weft_cloth::scene::{Scene, load};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A shipped preset by name; a file (one the debugger saved, or `weft
    // fit`'s fitted.toml) by its path.
    let loaded = load::load("flag_on_car", &[])?;
    let mut scene = Scene::new(&loaded.preset)?;
    let per_second = scene.frames_in(1.0);
    let frames = scene.frames_in(loaded.preset.duration);
    for frame in 1..=frames {
        scene.step()?;
        if frame % per_second == 0 {
            let lowest = scene
                .world_positions()
                .iter()
                .copied()
                .min_by(|a, b| a.z.total_cmp(&b.z))
                .unwrap_or_default();
            println!(
                "t = {:4.1} s: lowest point ({:7.3}, {:6.3}, {:5.3}) m",
                scene.time(),
                lowest.x,
                lowest.y,
                lowest.z
            );
        }
    }
    println!(
        "final state {:016x} ({})",
        scene.solver().state().digest(),
        weft_cloth::solver::version()
    );
    Ok(())
}
