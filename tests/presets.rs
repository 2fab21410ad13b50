//! Presets: every shipped preset runs; the car flag swings forward when the
//! car brakes (self-collision off and on); the drape rests on the sphere; malformed presets give located
//! errors; `extend` and `--set` round-trip.

use glam::Vec3;
use weft::scene::{Scene, load, shipped};
use weft::solver::{Family, Shape};

fn loaded(name: &str) -> load::Loaded {
    load::load(name, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The first two seconds of every preset, where the start-up jerks are,
/// within the preset's own strain bound (and never over 0.2). CI's
/// `.ci/run` records every preset for its whole duration with its verdicts.
#[test]
fn every_shipped_preset_starts_with_low_strain() {
    for p in shipped::ALL {
        let preset = loaded(p.name).preset;
        let bound = preset
            .expect
            .as_ref()
            .and_then(|e| e.max_strain)
            .unwrap_or(0.10)
            .min(0.2);
        let mut scene = Scene::new(&preset).unwrap();
        let frames = scene.frames_in(2.0);
        for frame in 1..=frames {
            scene.step().unwrap_or_else(|e| panic!("{}: {e}", p.name));
            let strain = scene.solver().max_strain();
            assert!(
                strain < bound,
                "{}: frame {frame}: strain {strain} (bound {bound})",
                p.name
            );
        }
        assert!(
            scene
                .solver()
                .state()
                .position
                .iter()
                .all(|x| x.is_finite())
        );
        assert!(!p.description().is_empty(), "{} has no description", p.name);
    }
}

/// With self-collision on too: a crossing-free path must not hold the
/// flag's swing back.
#[test]
fn car_flag_swings_forward_when_the_car_brakes() {
    for weight in [0.0, 1.0] {
        let mut preset = loaded("flag_on_car").preset;
        preset.solver.weights[Family::SelfCollision] = weight;
        let mut scene = Scene::new(&preset).unwrap();
        // The flag's centre along the car's forward axis, relative to the pole.
        let ahead = |scene: &Scene| {
            let car = scene.body_poses()[0];
            let x = &*scene.world_positions();
            let centre = x.iter().copied().sum::<Vec3>() / x.len() as f32;
            let pole = car.transform_point(Vec3::new(-1.6, 0.55, 1.65));
            (car.rotation * Vec3::X).dot(centre - pole)
        };
        // Cruising at 14 m/s the flag streams behind the pole.
        while scene.time() < 5.9 {
            scene.step().unwrap();
        }
        let cruising = ahead(&scene);
        assert!(
            cruising < -0.2,
            "self = {weight}: cruising: flag centre {cruising} m along the car"
        );
        // The car brakes hard from 6.0 s to 6.6 s; the flag swings forward.
        let mut most = f32::MIN;
        while scene.time() < 7.5 {
            scene.step().unwrap();
            most = most.max(ahead(&scene));
        }
        assert!(
            most > 0.0,
            "self = {weight}: after braking the flag centre only reached {most} m (pole at 0)"
        );
    }
}

#[test]
fn drape_settles_on_the_sphere_and_never_goes_through() {
    let preset = loaded("sphere_drape").preset;
    let mut scene = Scene::new(&preset).unwrap();
    let margin = 0.5 * preset.cloth.thickness;
    let sphere = scene
        .solver()
        .colliders()
        .iter()
        .find_map(|c| match c.shape {
            Shape::Sphere { radius } => Some((c.pose.translation, radius)),
            _ => None,
        })
        .unwrap();
    for _ in 0..scene.frames_in(preset.duration) {
        scene.step().unwrap();
        for x in scene.world_positions().iter() {
            assert!(
                x.distance(sphere.0) >= sphere.1 + margin - 1e-3,
                "inside the sphere: {x}"
            );
            assert!(x.z >= margin - 1e-3, "below the ground: {x}");
        }
    }
    let x = &*scene.world_positions();
    let on_top = x
        .iter()
        .filter(|p| p.z > sphere.0.z + sphere.1 * 0.9)
        .count();
    let on_ground = x.iter().filter(|p| p.z < 0.05).count();
    assert!(on_top > 0, "nothing rests on top of the sphere");
    assert!(on_ground > 0, "nothing reached the ground");
    assert!(
        scene.solver().kinetic_energy() < 0.05,
        "still moving: {} J",
        scene.solver().kinetic_energy()
    );
}

/// Writes `text` to a temporary preset file and loads it.
fn load_text(text: &str) -> Result<load::Loaded, load::PresetError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    load::load(path.to_str().unwrap(), &[])
}

const MINIMAL: &str = "description = \"x\"\n[cloth]\nweft = 4\nwarp = 4\n";

#[test]
fn malformed_presets_give_located_errors() {
    // (preset text, expected line, substrings the message must contain)
    let cases: &[(&str, Option<usize>, &[&str])] = &[
        (
            "description = \"x\"\n[cloth]\nweft = \"many\"\n",
            Some(3),
            &["cloth.weft", "u32"],
        ),
        (
            "description = \"x\"\n[cloth]\nweft = 1\n",
            Some(3),
            &["cloth.weft", "2 ≤"],
        ),
        (
            "description = \"x\"\n[cloth]\nwidht = 2.0\n",
            Some(3),
            &["widht", "did you mean `width`"],
        ),
        (
            "description = \"x\"\n[clth]\nweft = 4\n",
            Some(2),
            &["clth", "did you mean `cloth`"],
        ),
        ("description = \"x\"\n", Some(1), &["cloth", "missing"]),
        (
            "description = \"x\"\n[cloth\nweft = 4\n",
            Some(2),
            &["invalid TOML"],
        ),
        ("", None, &["empty"]),
        (
            "description = \"x\"\n[cloth]\nwidth = 1e30\n",
            Some(3),
            &["cloth.width", "1000"],
        ),
        (
            "description = \"x\"\n[cloth]\nweft = 99999999999\n",
            Some(3),
            &["cloth.weft"],
        ),
        (
            "description = \"x\"\n[cloth]\ndensity = nan\n",
            Some(3),
            &["cloth.density", "not finite"],
        ),
        (
            "description = \"x\"\n[cloth]\n[solver]\ndt = inf\n",
            Some(4),
            &["solver.dt", "not finite"],
        ),
        (
            "description = \"x\"\n[cloth]\nweft = 512\nwarp = 100000\n",
            Some(4),
            &["cloth.warp", "512"],
        ),
        (
            "description = \"x\"\n[cloth]\n[solver.weights]\ncurvature = 1.5\n",
            Some(4),
            &["solver.weights.curvature", "0 ≤ λ ≤ 1"],
        ),
        (
            "description = \"x\"\n[cloth]\n[telemetry]\nlevel = \"ful\"\n",
            Some(4),
            &["telemetry.level", "did you mean `full`"],
        ),
        (
            "description = \"x\"\n[cloth]\n[[attachments]]\nbody = \"kar\"\nselect = [\"top\"]\n[[bodies]]\nname = \"car\"\n[bodies.static]\n",
            Some(4),
            &["attachments[0].body", "did you mean `car`"],
        ),
        (
            "description = \"x\"\n[cloth]\n[[colliders]]\nshape = \"sphere\"\n",
            Some(3),
            &["colliders[0].radius", "needs"],
        ),
    ];
    let mut seen = std::collections::HashSet::new();
    for (text, line, needles) in cases {
        let err = load_text(text).expect_err(text);
        let msg = err.to_string();
        assert!(msg.contains("bad.toml"), "no file in: {msg}");
        assert_eq!(err.position.map(|p| p.0), *line, "wrong line in: {msg}");
        for n in *needles {
            assert!(msg.contains(n), "`{n}` missing from: {msg}");
        }
        assert!(seen.insert(msg.clone()), "duplicate message: {msg}");
    }
    // A valid minimal preset loads.
    load_text(MINIMAL).unwrap();
}

#[test]
fn extend_and_set_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let base = dir.path().join("base.toml");
    let child = dir.path().join("child.toml");
    std::fs::write(
        &base,
        "description = \"base\"\n[cloth]\nweft = 6\nwarp = 5\n[solver.weights]\ncurvature = 0.3\n",
    )
    .unwrap();
    std::fs::write(
        &child,
        "extend = \"base.toml\"\ndescription = \"child\"\n[solver.weights]\nnormality = 0.7\n",
    )
    .unwrap();
    let sets: Vec<load::Override> = [
        "solver.iterations=12",
        "telemetry.level=summary",
        "cloth.width=2.5",
    ]
    .iter()
    .map(|s| s.parse().unwrap())
    .collect();
    let loaded = load::load(child.to_str().unwrap(), &sets).unwrap();
    let p = &loaded.preset;
    assert_eq!(p.description, "child");
    assert_eq!((p.cloth.weft, p.cloth.warp, p.cloth.width), (6, 5, 2.5));
    assert_eq!(p.solver.weights[Family::Curvature], 0.3);
    assert_eq!(p.solver.weights[Family::Normality], 0.7);
    assert_eq!(p.solver.iterations, 12);
    assert_eq!(p.telemetry.level, weft::scene::preset::Level::Summary);
    // The resolved text stands alone and loads back to the same preset.
    let again = load::parse("resolved", &loaded.resolved).unwrap();
    assert_eq!(&again, p);
    // Saving the preset and loading it back is lossless too.
    let saved = toml::to_string(p).unwrap();
    assert_eq!(&load::parse("saved", &saved).unwrap(), p);

    // A shipped preset can be extended by name, and errors in --set are located.
    std::fs::write(
        &child,
        "extend = \"hanging_sheet\"\ndescription = \"mine\"\n",
    )
    .unwrap();
    assert_eq!(
        load::load(child.to_str().unwrap(), &[])
            .unwrap()
            .preset
            .cloth
            .weft,
        32
    );
    let bad: load::Override = "solver.damping=3".parse().unwrap();
    let err = load::load(child.to_str().unwrap(), &[bad])
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("--set solver.damping") && err.contains("0 ≤ k ≤ 1"),
        "{err}"
    );
    // An extend cycle is an error, not a hang.
    std::fs::write(
        &base,
        "extend = \"child.toml\"\ndescription = \"b\"\n[cloth]\n",
    )
    .unwrap();
    std::fs::write(&child, "extend = \"base.toml\"\ndescription = \"c\"\n").unwrap();
    assert!(
        load::load(child.to_str().unwrap(), &[])
            .unwrap_err()
            .to_string()
            .contains("cycle")
    );
}

/// Per-family tables (`[solver.weights]`, `[expect.max_violation]`,
/// `telemetry.corrections`): a missing family keeps its default, an unknown
/// one is located and named, and the text written back is the same format.
#[test]
fn per_family_tables_keep_defaults_and_refuse_unknown_families() {
    let p = load_text(
        "description = \"x\"\n[cloth]\n[solver.weights]\ncurvature = 0.3\n\
         [telemetry.corrections]\nstretch = false\n[expect.max_violation]\nplanarity = 0.5\n",
    )
    .unwrap()
    .preset;
    let w = &p.solver.weights;
    assert_eq!(w[Family::Curvature], 0.3);
    assert_eq!(w[Family::Stretch], 1.0);
    assert_eq!(w[Family::Planarity], 0.5);
    assert_eq!(w[Family::Normality], 0.2);
    assert!(!p.telemetry.corrections[Family::Stretch]);
    assert!(p.telemetry.corrections[Family::Curvature]);
    let bounds = p.expect.unwrap().max_violation;
    assert_eq!(bounds[Family::Planarity], Some(0.5));
    assert_eq!(bounds[Family::Stretch], None);
    let text = load::to_toml(&p);
    assert!(text.contains("planarity = 0.5"), "{text}");
    assert!(!text.contains("stretch = nan"), "{text}");
    assert_eq!(load_text(&text).unwrap().preset, p);

    let err = load_text("description = \"x\"\n[cloth]\n[solver.weights]\ncurvatur = 0.3\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains(":4:"), "{err}");
    assert!(err.contains("curvatur"), "{err}");
    assert!(err.contains("curvature"), "{err}");
}
