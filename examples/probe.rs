//! Prints a preset's strain, energy and violations once per simulated second.
use weft::scene::{Scene, load};
use weft::solver::Family;

fn main() {
    let name = std::env::args().nth(1).unwrap_or("flag_on_car".into());
    let sets: Vec<load::Override> = std::env::args()
        .skip(2)
        .map(|s| s.parse().unwrap())
        .collect();
    let preset = load::load(&name, &sets).unwrap().preset;
    let mut scene = Scene::new(&preset).unwrap();
    let per_second = scene.frames_in(1.0);
    let mut worst = 0.0f32;
    let start = std::time::Instant::now();
    for f in 1..=scene.frames_in(preset.duration) {
        scene.step().unwrap();
        worst = worst.max(scene.solver().max_strain());
        if f % per_second == 0
            || (std::env::var("FRAMES").is_ok() && scene.solver().max_strain() > 0.05)
        {
            let v = Family::ALL
                .map(|fam| format!("{}={:.3}", fam.name(), scene.solver().violation(fam).max));
            println!(
                "t={:5.1} strain(max so far)={:.4} now={:.4} ke={:.2e} {}",
                scene.time(),
                worst,
                scene.solver().max_strain(),
                scene.solver().kinetic_energy(),
                v.join(" ")
            );
        }
    }
    println!("{:?} per frame", start.elapsed() / scene.frame() as u32);
}
