//! Where self-collision's time goes, stage by stage (the stages of
//! `solver::self_collision`, in the order a step runs them), on shipped
//! presets: each run whole with the solver's diagnostics on, the stages'
//! wall time summed over the run and given per step. Prints CSV rows as in
//! `benches/results/` (`commit,benchmark,measure,value,unit,note`).
//!
//! ```sh
//! cargo bench -p weft-cloth --profile dev --bench self_collision_stages -- windy_flag flag_on_car
//! ```
//!
//! Without presets, every shipped one. The sweeps' share of the family's
//! time (projecting the contacts) is the `sweeps` row: the family's time
//! less its stages'.

use std::time::{Duration, Instant};

use weft_cloth::scene::{Scene, load, shipped};
use weft_cloth::solver::Family;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut presets: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    if presets.is_empty() {
        presets = shipped::ALL.iter().map(|s| s.name.to_string()).collect();
    }
    let commit = std::env::var("WEFT_COMMIT").unwrap_or_else(|_| "-".into());
    for name in presets {
        let loaded = load::load(&name, &[])?;
        let mut scene = Scene::new(&loaded.preset)?;
        scene.solver_mut().set_diagnostics(true);
        let frames = scene.frames_in(loaded.preset.duration);
        let mut stages = [Duration::ZERO; 6];
        let (mut family, mut total) = (Duration::ZERO, Duration::ZERO);
        let start = Instant::now();
        for _ in 0..frames {
            scene.step()?;
            let d = scene.solver().diagnostics().expect("diagnostics are on");
            for (k, (_, t)) in d.self_collision.iter().into_iter().enumerate() {
                stages[k] += t;
            }
            family += d.families[Family::SelfCollision].time;
            total += d.timings.total;
        }
        let wall = start.elapsed();
        let per_step = |t: Duration| 1e3 * t.as_secs_f64() / frames as f64;
        let names = weft_cloth::solver::self_collision::StageTimes::default().iter();
        let row = |measure: &str, t: Duration| {
            println!(
                "{commit},self-collision stages/{name},{measure},{:.3},ms/step,{frames} steps in {:.1} s",
                per_step(t),
                wall.as_secs_f64()
            );
        };
        for (k, (stage, _)) in names.into_iter().enumerate() {
            row(stage, stages[k]);
        }
        row("sweeps", family.saturating_sub(stages.iter().sum()));
        row("step", total);
    }
    Ok(())
}
