//! Self-collision: the cloth never passes through itself, counted by an
//! independent brute-force check of every edge against every triangle; the
//! check catches a cloth that does (self-collision off); contacts push
//! layers apart monotonically; results are bit-identical for any thread
//! count; bad values are refused.

// Tests and benchmarks set their scenes up with glam's rotations and
// compare with the standard library: they run on one machine, so the
// platform's math library is fine here (see `solver::portable`).
#![allow(clippy::disallowed_methods)]

mod common;

use common::calm;
use common::crossings::{brute_force_crossings, mesh};

use glam::Vec3;
use weft::scene::load::{self, Override};
use weft::scene::{Scene, preset::Preset};
use weft::solver::{ClothSpec, ClothState, Family, Params, Solver, Weights};

fn preset(name: &str, sets: &[&str]) -> Preset {
    let sets: Vec<Override> = sets.iter().map(|s| s.parse().unwrap()).collect();
    load::load(name, &sets)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .preset
}

/// Runs a preset to its end, counting crossings at the end of every
/// substep (or of every frame); returns the largest count seen and the
/// frame it was first seen at.
fn worst_crossings(preset: &Preset, every_substep: bool) -> (usize, u64) {
    let mut scene = Scene::new(preset).unwrap();
    let (edges, triangles) = mesh(preset.cloth.weft, preset.cloth.warp);
    let frames = scene.frames_in(preset.duration);
    let (mut worst, mut at) = (0, 0);
    for frame in 1..=frames {
        let mut seen = 0;
        let mut check = |s: &ClothState| {
            seen = seen.max(brute_force_crossings(&s.position, &edges, &triangles));
        };
        if every_substep {
            scene.step_with(&mut check).unwrap();
        } else {
            scene.step().unwrap();
            check(scene.solver().state());
        }
        if seen > worst {
            (worst, at) = (seen, frame);
        }
    }
    (worst, at)
}

#[test]
fn the_new_presets_never_pass_through_themselves() {
    // Every substep, on small grids.
    for (name, sets) in [
        ("folding_sheet", &["cloth.weft=12", "cloth.warp=12"]),
        ("furling_banner", &["cloth.weft=12", "cloth.warp=9"]),
    ] {
        let (worst, frame) = worst_crossings(&preset(name, sets), true);
        assert_eq!(
            worst, 0,
            "{name} at 12 × n: {worst} crossings at frame {frame}"
        );
    }
    // Every frame, as shipped.
    for name in ["folding_sheet", "furling_banner"] {
        let (worst, frame) = worst_crossings(&preset(name, &[]), false);
        assert_eq!(worst, 0, "{name}: {worst} crossings at frame {frame}");
    }
}

/// `folding_sheet` at 12 × 12 with self-collision off: the fold passes
/// through itself. (With facing off too: with it on, this fold happens to
/// clear itself at 12 × 12. These tests check the crossing count and the
/// contact search, not facing.)
const CROSSING_FOLD: &[&str] = &[
    "cloth.weft=12",
    "cloth.warp=12",
    "solver.weights.self=0",
    "solver.weights.facing=0",
];

#[test]
fn without_self_collision_the_fold_passes_through() {
    // The check above can fail: the same fold with the family off crosses.
    let p = preset("folding_sheet", CROSSING_FOLD);
    let (worst, _) = worst_crossings(&p, false);
    assert!(worst > 0, "no crossing without self-collision");
}

/// Runs `seconds` of preset `p` on a 12 × 12 grid and checks, every frame,
/// that `count` (the solver's count, as a caller reads it) equals brute
/// force; and that some frame crossed, so that the check checked something.
fn count_agrees_with_brute_force(p: &Preset, seconds: f32, count: impl Fn(&Solver) -> usize) {
    let mut scene = Scene::new(p).unwrap();
    scene.solver_mut().set_diagnostics(true);
    let (edges, triangles) = mesh(12, 12);
    let mut crossed = 0;
    for _ in 0..scene.frames_in(seconds) {
        scene.step().unwrap();
        let s = scene.solver();
        let brute = brute_force_crossings(&s.state().position, &edges, &triangles);
        assert_eq!(count(s), brute, "at frame {}", scene.frame());
        crossed += brute;
    }
    assert!(crossed > 0, "the comparison never saw a crossing");
}

#[test]
fn the_solvers_count_agrees_with_brute_force() {
    let p = preset("folding_sheet", CROSSING_FOLD);
    count_agrees_with_brute_force(&p, p.duration, Solver::self_crossings);
}

#[test]
fn with_self_collision_on_the_diagnostics_count_agrees_with_brute_force() {
    // The count the diagnostics report is found from the contact search's
    // kept pairs while they cover the cloth, else from a new hash: on a
    // jerked cloth that tangles and comes apart, both must give the count.
    let p = preset(
        "stress_jerk",
        &["cloth.weft=12", "cloth.warp=12", "solver.weights.self=1"],
    );
    count_agrees_with_brute_force(&p, 5.0, |s| {
        s.diagnostics().unwrap().self_crossings.unwrap()
    });
}

#[test]
fn stress_jerk_with_self_collision_keeps_its_bounds_and_comes_apart_within_half_a_second() {
    // Each teleport drags the cloth through itself. The tangled particles
    // are left out of the contacts and bounds and moved so that the
    // intersection contours shrink (docs/method.md §11b), until the cloth
    // is free of crossings again; from then on the bounds keep it so.
    let p = preset("stress_jerk", &["solver.weights.self=1"]);
    let mut scene = Scene::new(&p).unwrap();
    let mut peak = 0.0f32;
    // Teleports every 1.5 s (90 frames): a crossing (the solver's count,
    // which the tests above check against brute force) only in the half
    // second after one.
    let mut late = Vec::new();
    let mut tangled = 0;
    for _ in 0..scene.frames_in(9.0) {
        scene.step().unwrap();
        let s = scene.solver();
        peak = peak.max(s.max_strain());
        let frame = scene.frame();
        if s.self_crossings() > 0 {
            tangled += 1;
            if frame % 90 > 30 {
                late.push(frame);
            }
        }
    }
    assert!(
        tangled > 0,
        "no teleport tangled the cloth: nothing was tested"
    );
    assert!(
        late.is_empty(),
        "crossings later than 0.5 s after a teleport: frames {late:?}"
    );
    let bound = p.expect.as_ref().and_then(|e| e.max_strain);
    let bound = bound.expect("stress_jerk bounds its strain");
    assert!(
        peak < bound,
        "peak strain {peak}, the preset's bound {bound}"
    );
}

/// The shipped presets other than `stress_jerk` (which teleports its cloth
/// through itself on purpose), with how long of each the test below runs:
/// its start, where the cloth falls, folds, wraps or is whipped round.
const BOUNDED: &[(&str, f32)] = &[
    ("flag_on_car", 3.0),
    ("windy_flag", 3.0),
    ("cape_runner", 3.0),
    ("hanging_sheet", 2.0),
    ("sphere_drape", 3.0),
    ("folding_sheet", 6.0),
    ("furling_banner", 8.0),
];

#[test]
fn with_self_collision_no_shipped_preset_crosses_itself_at_any_substep() {
    // The path check (docs/method.md §11b): counted by brute force at the
    // end of every substep. Without it the flags crossed themselves in
    // most frames, self-collision on or off.
    let listed: Vec<&str> = BOUNDED.iter().map(|(n, _)| *n).collect();
    for p in weft::scene::shipped::ALL {
        assert!(
            p.name == "stress_jerk" || listed.contains(&p.name),
            "{} is not checked",
            p.name
        );
    }
    for &(name, seconds) in BOUNDED {
        let duration = format!("duration={seconds}");
        let p = preset(name, &["solver.weights.self=1", &duration]);
        let (worst, frame) = worst_crossings(&p, true);
        assert_eq!(worst, 0, "{name}: {worst} crossings at frame {frame}");
    }
}

/// A 10 × 10 sheet folded in half: its upper half lies `gap` above its
/// lower half, mirrored, facing it; no gravity or air.
fn folded(gap: f32, params: Params) -> Solver {
    let spec = ClothSpec {
        weft: 10,
        warp: 10,
        width: 0.9,
        height: 0.9,
        imperfection: 0.0,
        thickness: 0.01,
        ..ClothSpec::default()
    };
    let mut s = Solver::new(spec, params, &[]).unwrap();
    let st = s.state_mut();
    for j in 0..10 {
        for i in 0..10 {
            let k = spec.index(i, j);
            let x = 0.1 * i as f32;
            // Columns 0-4 below; 5-9 folded back over them.
            st.position[k] = if i < 5 {
                Vec3::new(x, 0.1 * j as f32, 0.0)
            } else {
                Vec3::new(0.9 - x, 0.1 * j as f32, gap)
            };
        }
    }
    st.prev_position.clone_from(&st.position);
    s
}

#[test]
fn contacts_push_the_layers_apart_monotonically() {
    let params = Params {
        weights: Weights::splat(0.0).with(Family::SelfCollision, 1.0),
        damping: 0.0,
        ..Params::default()
    };
    let mut s = folded(0.004, params);
    let first = s.violation(Family::SelfCollision);
    assert!(
        first.max > 0.005,
        "the layers start inside the thickness: {first:?}"
    );
    let mut last = first.max;
    for step in 0..10 {
        s.step(&calm(), &[]).unwrap();
        let now = s.violation(Family::SelfCollision).max;
        assert!(now <= last + 1e-7, "rose at step {step}: {last} -> {now}");
        last = now;
    }
    assert!(last < 1e-4, "still {last} inside the thickness");
    // The upper layer stayed above: nothing crossed.
    assert_eq!(s.self_crossings(), 0);
}

/// The folded sheet with its layers inside the thickness, self-collision
/// at `weight` and every other family at its default.
fn folded_inside(weight: f32) -> Solver {
    let params = Params {
        weights: Weights::default().with(Family::SelfCollision, weight),
        ..Params::default()
    };
    folded(0.004, params)
}

/// Per particle, the self family's violation is what the figures report,
/// particle by particle: its largest value is the family's measured max
/// while the family is on, and, like the figures, it is 0 while the family
/// is off (the contact search is not run for it).
#[test]
fn per_particle_self_violation_agrees_with_the_figures() {
    for weight in [0.0, 1.0] {
        let s = folded_inside(weight);
        let each = s.particle_violation(Family::SelfCollision);
        let largest = each.iter().copied().fold(0.0f32, f32::max);
        let figures = s.measured_violations()[Family::SelfCollision];
        assert_eq!(largest, figures.max, "weight {weight}");
        if weight > 0.0 {
            assert!(largest > 0.005, "the layers start inside the thickness");
        } else {
            assert!(each.iter().all(|v| *v == 0.0));
        }
    }
}

/// Inspecting one particle measures only the constraints that involve it,
/// and reads the same as the whole cloth's per-particle values, bit for
/// bit, for every family, with self-collision on and off.
#[test]
fn one_particle_s_readout_matches_the_whole_cloth_s() {
    for weight in [0.0, 1.0] {
        let mut s = folded_inside(weight);
        // Move and tilt every element a little, each its own way, so that
        // every family is violated somewhere (the layers stay inside the
        // thickness).
        let st = s.state_mut();
        for k in 0..st.len() {
            let along = Vec3::new((k % 3) as f32 - 1.0, (k % 5) as f32 - 2.0, 1.0);
            st.position[k] += 2e-4 * along;
            st.orientation[k] =
                (glam::Quat::from_scaled_axis(0.05 * along) * st.orientation[k]).normalize();
        }
        let strain = s.particle_strain();
        assert!(strain.iter().any(|v| *v > 0.0), "some edge is stretched");
        for f in Family::ALL {
            let each = s.particle_violation(f);
            let measured = !f.measured_only_while_on() || s.params().weights[f] > 0.0;
            assert!(
                !measured || each.iter().any(|v| *v > 0.0),
                "{f:?} is violated somewhere"
            );
            for (i, v) in each.iter().enumerate() {
                assert_eq!(
                    s.particle_violation_at(f, i).to_bits(),
                    v.to_bits(),
                    "{f:?}, particle {i}, weight {weight}"
                );
            }
        }
        for (i, v) in strain.iter().enumerate() {
            assert_eq!(
                s.particle_strain_at(i).to_bits(),
                v.to_bits(),
                "particle {i}"
            );
        }
    }
}

#[test]
fn a_layer_carried_through_is_pushed_back_to_its_side() {
    // Both layers start apart; the upper one arrives moving down so fast
    // that one update carries it through the lower one. The side kept
    // from the substep's start sends it back up, not on down.
    let params = Params {
        weights: Weights::splat(0.0).with(Family::SelfCollision, 1.0),
        substeps: 1,
        damping: 1.0,
        ..Params::default()
    };
    let mut s = folded(0.02, params);
    let st = s.state_mut();
    for k in 0..st.len() {
        if k % 10 >= 7 {
            // 4 cm a substep, downwards: the update lands it 2 cm below.
            st.prev_position[k].z = st.position[k].z + 0.04;
        }
    }
    s.step(&calm(), &[]).unwrap();
    let x = &s.state().position;
    for j in 0..10 {
        for c in 7..10 {
            let (upper, lower) = (x[j * 10 + c], x[j * 10 + 9 - c]);
            assert!(
                upper.z > lower.z,
                "column {c} went through: z {} below {}",
                upper.z,
                lower.z
            );
        }
    }
    assert_eq!(s.self_crossings(), 0);
}

#[test]
fn self_contacts_are_bit_identical_for_any_thread_count() {
    // Big enough (48 × 48) that the adjust phase shares its batches; run
    // until the fold is laid down, with contacts in every substep.
    let p = preset(
        "folding_sheet",
        &["cloth.weft=48", "cloth.warp=48", "duration=4.6"],
    );
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut scene = Scene::new(&p).unwrap();
            for _ in 0..scene.frames_in(p.duration) {
                scene.step().unwrap();
            }
            assert!(scene.solver().violation(Family::SelfCollision).max > 0.0);
            scene.solver().state().digest()
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn bad_self_collision_values_are_refused_with_their_range() {
    for (set, key) in [
        ("solver.weights.self=-0.5", "weights.self"),
        ("solver.weights.self=nan", "weights.self"),
        ("cloth.thickness=-0.001", "cloth.thickness"),
        ("cloth.friction=-1", "cloth.friction"),
    ] {
        let o: Override = set.parse().unwrap();
        let err = load::load("folding_sheet", &[o]).unwrap_err().to_string();
        assert!(err.contains(key), "{set}: {err}");
        assert!(err.contains("allowed"), "{set}: {err}");
    }
}

#[test]
fn a_thickness_unfit_for_the_spacing_is_warned_about() {
    // The sheet's spacing is 1 m / 23 ≈ 43 mm.
    for (thickness, says) in [("0.05", "spacing"), ("0.0001", "spacing")] {
        let o: Override = format!("cloth.thickness={thickness}").parse().unwrap();
        let loaded = load::load("folding_sheet", &[o]).unwrap();
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("thickness") && w.contains(says)),
            "{thickness}: {:?}",
            loaded.warnings
        );
    }
    assert!(
        load::load("folding_sheet", &[])
            .unwrap()
            .warnings
            .is_empty()
    );
}
