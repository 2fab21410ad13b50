//! The frame of reference and the distance from the origin do not matter:
//! the solver measures every position from a floating origin that moves
//! with the cloth's carrier (docs/method.md, "The frame of reference"), so
//! a flag a kilometre or twenty down the road, or on a car already
//! cruising, moves bit for bit as the same flag at rest at the origin,
//! compared in its carrier's frame. A limp flag is chaotic (a 0.05 mm
//! difference in where it starts grows to centimetres within a second), so
//! only the same arithmetic passes these tests.

use glam::DVec3;
use weft::scene::{Scene, load};

/// The shipped car flag's cloth and solver, no air, pinned along its left
/// edge to a carrier whose motion table is `body`, with the cloth placed at
/// `x` metres along X.
fn flag_on(body: &str, x: f64, title: &str) -> Scene {
    let text = format!(
        r#"
description = "{title}"
duration = 3.0

[cloth]
width = 0.9
height = 0.6
weft = 24
warp = 16
density = 0.15
thickness = 0.004
position = [{cloth}, 0.55, 1.35]
rotation = [-90.0, 0.0, -180.0]

[solver]
damping = 0.99
iterations = 2
substeps = 8

[environment]
air_density = 0.0

[[bodies]]
name = "carrier"

{body}

[[attachments]]
body = "carrier"
select = ["left"]
"#,
        cloth = x - 1.6
    );
    let preset = load::parse(title, &text).unwrap();
    Scene::new(&preset).unwrap()
}

/// The limp flag on a carrier at `x` metres along X: on a fixed pole
/// (`speed` none) or on a car at `speed` m/s from the start.
fn limp_flag(x: f64, speed: Option<f64>) -> Scene {
    let body = match speed {
        None => format!("[bodies.static]\nposition = [{x}, 0.0, 0.0]"),
        Some(v) => format!("[bodies.car]\nstart = [{x}, 0.0, 0.0]\nspeed = [[0.0, {v}]]"),
    };
    flag_on(&body, x, "A limp flag on a carrier, no air")
}

/// Steps `scene` for 3 s; at every frame, the particles in the carrier's
/// frame (world positions less the carrier's, in `f64`).
fn in_carrier_frame(mut scene: Scene) -> Vec<Vec<DVec3>> {
    let frames = scene.frames_in(3.0);
    let carrier = scene.carrier().expect("the flag is attached");
    (0..frames)
        .map(|_| {
            scene.step().unwrap();
            let origin = scene.solver().frame().origin;
            let at = scene.body_placements()[carrier].translation;
            let x = &scene.solver().state().position;
            x.iter().map(|p| origin + p.as_dvec3() - at).collect()
        })
        .collect()
}

/// The first frame at which `b` differs from `a` at all, and the largest
/// distance between their particles over all frames.
fn compare(a: &[Vec<DVec3>], b: &[Vec<DVec3>]) -> (Option<usize>, f64) {
    let first = a.iter().zip(b).position(|(a, b)| a != b);
    let worst = a
        .iter()
        .zip(b)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| p.distance(*q)))
        .fold(0.0, f64::max);
    (first, worst)
}

#[test]
fn a_flag_far_from_the_origin_moves_bit_for_bit_as_at_the_origin() {
    let at_origin = in_carrier_frame(limp_flag(0.0, None));
    for x in [1e3, 2e4] {
        let (first, worst) = compare(&at_origin, &in_carrier_frame(limp_flag(x, None)));
        assert!(worst <= 1e-3, "{x} m out: {worst} m apart");
        assert_eq!(first, None, "{x} m out: first differs at frame {first:?}");
    }
}

#[test]
fn a_flag_on_a_cruising_car_moves_bit_for_bit_as_on_a_car_at_rest() {
    let at_rest = in_carrier_frame(limp_flag(0.0, Some(0.0)));
    for (x, v) in [(0.0, 14.0), (2e4, 14.0), (1e3, 0.0)] {
        let (first, worst) = compare(&at_rest, &in_carrier_frame(limp_flag(x, Some(v))));
        assert!(worst <= 1e-3, "{v} m/s from {x} m: {worst} m apart");
        assert_eq!(
            first, None,
            "{v} m/s from {x} m: first differs at frame {first:?}"
        );
    }
}

/// A cloth starts moving with what carries it: on a car at 14 m/s from the
/// start, every free particle moves at 14 m/s at the first frame (in world
/// terms), and the flag is where it hangs, not dragged up to speed.
#[test]
fn a_cloth_starts_moving_with_its_carrier() {
    let mut scene = limp_flag(0.0, Some(14.0));
    scene.step().unwrap();
    let solver = scene.solver();
    let mass: f32 = solver.masses().iter().sum();
    let expected = 0.5 * mass * 14.0 * 14.0;
    let e = solver.kinetic_energy();
    assert!(
        (e - expected).abs() < 0.01 * expected,
        "{e} J at the first frame, expected about {expected} J"
    );
    // World positions follow the car: 14 m/s × 1/60 s.
    let x0 = limp_flag(0.0, Some(14.0)).world_positions().into_owned();
    let x1 = scene.world_positions();
    let moved = (x1[1].x - x0[1].x) as f64;
    assert!((moved - 14.0 / 60.0).abs() < 0.01, "moved {moved} m");
}

/// A cloth also starts with its carrier's turn: a flag on a pole that turns
/// at 90°/s from the start moves, over the first frame, as the pole carries
/// it (less than gravity and the constraints' few millimetres), not from
/// rest (2.4 cm behind at its free edge).
#[test]
fn a_cloth_starts_turning_with_its_carrier() {
    let body = "[bodies.keyframes]
keys = [
  { t = 0.0, rotation = [0.0, 0.0, 0.0] },
  { t = 1.0, rotation = [0.0, 0.0, 90.0] },
]";
    let mut scene = flag_on(body, 0.0, "A limp flag on a pole that turns from the start");
    let before = scene.world_positions().into_owned();
    scene.step().unwrap();
    let after = scene.world_positions();
    let turn = scene.body_poses()[0].rotation;
    let worst = before
        .iter()
        .zip(after.iter())
        .map(|(x0, x1)| (turn * *x0).distance(*x1))
        .fold(0.0f32, f32::max);
    assert!(worst < 0.005, "{worst} m from where the turn carries it");
}
