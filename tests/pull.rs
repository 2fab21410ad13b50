//! A pull on one particle (the debugger's Ctrl-drag, `solver::pull`):
//! it draws the particle towards its target (self-collision off and on:
//! the energy it holds bounds where the particle can go),
//! on a cloth at rest and on one
//! carried by a car (the target in world coordinates, the solver in its
//! floating origin's); a pull to where the particle already is changes
//! nothing; and without a pull a run is what it was before pulls existed,
//! bit for bit.

use glam::DVec3;
use proptest::prelude::*;
use weft::scene::{Scene, Tuning, load};
use weft::solver::{ClothSpec, Family, Params, Pull, Solver};

mod common;
use common::calm;

/// An `n × n` cloth's layout, exactly flat at rest.
fn flat(n: u32) -> ClothSpec {
    ClothSpec {
        weft: n,
        warp: n,
        imperfection: 0.0,
        ..ClothSpec::default()
    }
}

/// An `n × n` cloth, exactly flat at rest, self-collision off.
fn sheet(n: u32) -> Solver {
    let mut params = Params::default();
    params.weights[Family::SelfCollision] = 0.0;
    Solver::new(flat(n), params, &[]).unwrap()
}

fn steps(s: &mut Solver, n: usize) {
    for _ in 0..n {
        s.step(&calm(), &[]).unwrap();
    }
}

/// The most energy a pull's spring holds at the start, with self-collision
/// on (J): 100 J/kg of the test's 0.2 kg cloth, all of it spent at once
/// flinging the cloth at 14 m/s. A yank far harder than that can draw
/// energy from self-collision's parting of layers that meet at such speeds
/// (docs/method.md §11b, "Limits, and the default").
const SELF_COLLISION_ENERGY: f64 = 20.0;

/// Pulls `particle` of an 8 × 8 sheet by `offset` with a spring of
/// `stiffness` for ten steps; where it started and ended, and the target.
fn pulled(
    spec: ClothSpec,
    particle: usize,
    offset: DVec3,
    stiffness: f32,
    self_collision: f32,
) -> (DVec3, DVec3, DVec3, Solver) {
    let mut params = Params::default();
    params.weights[Family::SelfCollision] = self_collision;
    let mut s = Solver::new(spec, params, &[]).unwrap();
    let start = s.state().position[particle].as_dvec3();
    let target = start + offset;
    s.set_pull(Some(Pull {
        particle,
        target,
        stiffness,
    }))
    .unwrap();
    steps(&mut s, 10);
    let now = s.state().position[particle].as_dvec3();
    (start, now, target, s)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Whichever particle, wherever the target (within a metre), however
    /// stiff the spring, self-collision off or on (the pulled particle is
    /// pushed by the layers it meets like any other, but not held back by
    /// the check on the substep's path): the particle ends nearer its
    /// target, and the cloth stays finite. In calm air with no gravity
    /// this is the conservation of energy: the spring holds `½ k d²`, the
    /// rest of the energy can only be positive, and the solver may lose
    /// energy but must not make it, so the distance can never exceed the
    /// one it started at.
    #[test]
    fn a_pull_draws_its_particle_towards_the_target(
        particle in 0usize..64,
        offset in prop::array::uniform3(-1.0f64..1.0),
        stiffness in 0.5f32..1e4,
        self_collision in prop::sample::select(vec![0.0f32, 1.0]),
    ) {
        let offset = DVec3::from_array(offset);
        prop_assume!(offset.length() > 0.05);
        let stiffness = if self_collision > 0.0 {
            stiffness.min((2.0 * SELF_COLLISION_ENERGY / offset.length_squared()) as f32)
        } else {
            stiffness
        };
        let (start, now, target, s) = pulled(flat(8), particle, offset, stiffness, self_collision);
        prop_assert!(s.state().position.iter().all(|x| x.is_finite()));
        prop_assert!(
            now.distance(target) < start.distance(target),
            "{start} → {now}, target {target}"
        );
    }

    /// A pull to exactly where the particle is, on a cloth at rest in calm
    /// air: nothing moves, bit for bit, as without it.
    #[test]
    fn a_pull_to_where_the_particle_is_changes_nothing(
        particle in 0usize..36,
        stiffness in 0.5f32..1e6,
    ) {
        let mut free = sheet(6);
        let mut held = sheet(6);
        let target = held.state().position[particle].as_dvec3();
        held.set_pull(Some(Pull { particle, target, stiffness })).unwrap();
        steps(&mut free, 5);
        steps(&mut held, 5);
        prop_assert_eq!(free.state().digest(), held.state().digest());
    }
}

/// With self-collision on, a corner folded gently over the sheet (2 N/m)
/// and stiff yanks of up to a metre and a half: each particle ends less
/// than half as far from its target as it started. (These flung the cloth
/// metres off while the fallback clamp's common motion followed the pulled
/// particle and parting treated it as an immovable paddle.)
#[test]
fn pulls_across_the_sheet_with_self_collision_draw_the_particle_in() {
    let flat = flat(8);
    let rumpled = ClothSpec {
        imperfection: 0.01,
        ..flat
    };
    let cases = [
        (&rumpled, 7, [0.0, 0.7828827345575622, 0.0], 2.0),
        (
            &flat,
            26,
            [
                -0.1657436165783627,
                -0.19496318573272292,
                -0.5800892733400986,
            ],
            240.3406,
        ),
        (
            &flat,
            2,
            [0.28027890543506884, 0.35892265747705226, 0.0],
            1126.2708,
        ),
        (&flat, 56, [0.5799238461395454, 0.0, 0.0], 281.744),
        (
            &flat,
            15,
            [-0.9151447678117612, 0.5299713304187625, -0.9617720973423396],
            7624.65,
        ),
        (&flat, 25, [0.9499443157151131, 0.0, 0.0], 9382.6045),
    ];
    for (spec, particle, offset, stiffness) in cases {
        let offset = DVec3::from_array(offset);
        let (_, now, target, _) = pulled(*spec, particle, offset, stiffness, 1.0);
        let d = now.distance(target);
        assert!(
            d < 0.5 * offset.length(),
            "particle {particle}, {stiffness} N/m: {d:.3} m from its target, {:.3} at the start",
            offset.length()
        );
    }
}

#[test]
fn a_bad_pull_is_refused_and_changes_nothing() {
    let mut s = sheet(4);
    let pull = Pull {
        particle: 16,
        target: DVec3::ZERO,
        stiffness: 1.0,
    };
    assert_eq!(s.set_pull(Some(pull)).unwrap_err().key, "pull.particle");
    assert_eq!(s.pull(), None);
    let preset = load::load("hanging_sheet", &[]).unwrap().preset;
    let mut scene = Scene::new(&preset).unwrap();
    let n = scene.solver().state().len();
    let bad = Tuning {
        pull: Some(Pull {
            particle: n,
            target: DVec3::ZERO,
            stiffness: 1.0,
        }),
        ..scene.tuning()
    };
    let mut also = bad;
    also.solver.iterations += 1;
    assert_eq!(scene.set_tuning(&also).unwrap_err().key, "pull.particle");
    assert_eq!(scene.tuning(), Tuning::of(&preset), "nothing applied");
}

/// The car flag's free tip, pulled towards a point fixed in the world
/// beside the road while the car drives on: the solver's origin moves with
/// the car, the target stays put, and the tip is drawn there (compared
/// with the same run without the pull).
#[test]
fn a_carried_cloth_is_pulled_towards_a_point_fixed_in_the_world() {
    let preset = load::load("flag_on_car", &[]).unwrap().preset;
    let mut free = Scene::new(&preset).unwrap();
    for _ in 0..60 {
        free.step().unwrap();
    }
    let mut held = free.clone();
    let tip = preset.cloth.weft as usize - 1;
    let at = held.world_positions()[tip].as_dvec3();
    let target = at + DVec3::new(0.0, 0.0, 0.6);
    let tuning = Tuning {
        pull: Some(Pull {
            particle: tip,
            target,
            stiffness: 50.0,
        }),
        ..held.tuning()
    };
    held.set_tuning(&tuning).unwrap();
    for _ in 0..30 {
        free.step().unwrap();
        held.step().unwrap();
    }
    assert_eq!(
        held.solver().frame().origin,
        free.solver().frame().origin,
        "the origin moves with the car, pull or not"
    );
    let pulled = held.world_positions()[tip].as_dvec3();
    let left = free.world_positions()[tip].as_dvec3();
    // The car drives off (some 3 m in half a second) and the tip with it,
    // but nearer the target, and higher, than left alone.
    assert!(
        pulled.distance(target) + 0.05 < left.distance(target) && pulled.z > left.z + 0.1,
        "pulled {pulled}, left alone {left}, target {target}"
    );
}

/// Without a pull, runs are what they were before pulls existed: these
/// digests are those of the same runs (120 frames, self-collision off as it
/// was then) made by the weft that had none.
#[test]
fn without_a_pull_nothing_changes() {
    let off = ["solver.weights.self=0".parse().unwrap()];
    for (preset, digest) in [
        ("flag_on_car", "3eabafb62f587e10"),
        ("hanging_sheet", "18e3caa428002428"),
    ] {
        let preset_data = load::load(preset, &off).unwrap().preset;
        let mut scene = Scene::new(&preset_data).unwrap();
        for _ in 0..120 {
            scene.step().unwrap();
        }
        let got = format!("{:016x}", scene.solver().state().digest());
        assert_eq!(got, digest, "{preset}");
    }
}
