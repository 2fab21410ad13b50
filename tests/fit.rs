//! Fits: the distance is zero against itself, symmetric, and ranks the
//! drape ladder as a person would; a fit is the same for the same seed
//! whatever the threads, when interrupted and resumed, and when run shard by
//! shard; a drape target is met; every bad input is refused with exit 2,
//! naming the argument, before anything runs.
//!
//! The ladder's figures (`cargo test --test fit -- --nocapture`) are the
//! table in `docs/method.md`, "The fit's distance".

use std::path::{Path, PathBuf};
use std::process::Output;

use weft::fit::distance::between;
use weft::fit::measure::{Lattice, measure, measure_with};
use weft::fit::search::Method;
use weft::fit::{Fit, Request};
use weft::scene::{Override, Scene, Tuning, load};

mod common;
use common::weft;

const CUSICK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/presets/cusick_drape.toml");

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

fn set(key: &str, value: f64) -> Override {
    Override {
        key: key.into(),
        value: toml::Value::Float(value),
    }
}

/// The arguments of a small drape fit: 1 s of the Cusick tester, curvature
/// searched, written to `out`.
fn drape_args<'a>(out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "fit",
        CUSICK,
        "--vary",
        "solver.weights.curvature=0.5..0.95",
        "--target",
        "drape_coefficient=0.45",
        "--seconds",
        "1",
        "--budget",
        "10",
        "--seed",
        "7",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    args
}

/// Runs the small drape fit ([`drape_args`]).
fn drape_fit(out: &Path, extra: &[&str]) -> Output {
    weft().args(drape_args(out, extra)).output().unwrap()
}

/// Every point's settings and measurements (the figures without wall-clock
/// timing), by file, for comparing two fits.
fn points(dir: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut gens: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    gens.sort();
    for g in gens {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&g)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .filter(|p| p.file_name().unwrap() != "sweep.json")
            .collect();
        files.sort();
        for f in files {
            let mut v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
            v["figures"]["wall_seconds"] = 0.into();
            v["figures"]["steps_per_second"] = 0.into();
            let name = format!(
                "{}/{}",
                g.file_name().unwrap().to_string_lossy(),
                f.file_name().unwrap().to_string_lossy()
            );
            out.push((name, v.to_string()));
        }
    }
    out
}

#[test]
fn the_distance_is_zero_against_itself_and_symmetric() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("self.rrd");
    let rec = weft()
        .args(["record", CUSICK, "--seconds", "0.5", "--level", "summary"])
        .arg("--save")
        .arg(&reference)
        .output()
        .unwrap();
    assert!(rec.status.success(), "{}", stderr(&rec));
    let fit = Fit::new(Request {
        preset: CUSICK.into(),
        base: Vec::new(),
        vary: vec!["solver.weights.curvature=0.05..0.9".parse().unwrap()],
        reference: Some(reference),
        reference_weight: 1.0,
        targets: Vec::new(),
        budget: 1,
        seed: 1,
        method: Method::Swarm,
        seconds: Some(0.5),
    })
    .unwrap();
    let stop = std::sync::atomic::AtomicBool::new(false);
    let run = || {
        weft::fit::run(
            &fit,
            &dir.path().join("fit"),
            None,
            1,
            &stop,
            false,
            &mut |_| {},
        )
        .unwrap()
    };
    let outcome = run();
    assert_eq!(outcome.points.len(), 1);
    // Run again: the reference's features are read from the cache, not measured again.
    let cache = dir.path().join("fit/reference.json");
    let written = std::fs::metadata(&cache).unwrap().modified().unwrap();
    let again = run();
    assert_eq!(
        std::fs::metadata(&cache).unwrap().modified().unwrap(),
        written
    );
    assert_eq!(again.points[0].distance, outcome.points[0].distance);
    let start = &outcome.points[0];
    assert_eq!(
        start.distance.total, 0.0,
        "the preset against its own recording: {:?}",
        start.distance
    );
    assert_eq!(
        start.features.horizon,
        Some(0.0),
        "on the reference's grid, restarted from its states with its settings: no error"
    );

    // Two different cloths: the same distance either way.
    let loaded = load::load(CUSICK, &[]).unwrap();
    let lattice = Lattice::of(&Scene::new(&loaded.preset).unwrap());
    let a = measure(&loaded.preset, &lattice, 0.5).unwrap();
    let stiff = load::load(CUSICK, &[set("solver.weights.curvature", 0.9)]).unwrap();
    let b = measure(&stiff.preset, &lattice, 0.5).unwrap();
    let (ab, ba) = (
        between(&a, &b, lattice.length),
        between(&b, &a, lattice.length),
    );
    assert_eq!(ab, ba);
    assert!(ab.total() > 0.0);

    // Restarted from the limp cloth's states, the stiff settings part from it.
    let (_, horizon) = measure_with(&loaded.preset, &lattice, 0.5, true).unwrap();
    let horizon = horizon.expect("shared states on the same grid");
    assert_eq!(horizon.starts.len(), 4);
    let same = horizon.error(&lattice, &Tuning::of(&loaded.preset));
    let other = horizon.error(&lattice, &Tuning::of(&stiff.preset));
    assert_eq!(same, Some(0.0));
    assert!(other.is_some_and(|e| e > 0.0), "{other:?}");
}

/// The drape ladder of docs/method.md: against each reference rung, the
/// distance to the other rungs grows as their drape coefficients part from
/// the reference's, as a person comparing the draped cloths would rank them.
#[test]
fn the_distance_ranks_the_drape_ladder() {
    let ladder = [0.05, 0.5, 0.7, 0.8, 0.9, 0.95];
    let base = load::load(CUSICK, &[]).unwrap();
    let lattice = Lattice::of(&Scene::new(&base.preset).unwrap());
    let runs: Vec<_> = ladder
        .iter()
        .map(|&c| {
            let p = load::load(CUSICK, &[set("solver.weights.curvature", c)]).unwrap();
            measure(&p.preset, &lattice, 6.0).unwrap()
        })
        .collect();
    println!(
        "drape coefficients: {:?}",
        runs.iter()
            .map(|f| (f.drape_coefficient * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>()
    );
    for (r, reference) in runs.iter().enumerate() {
        let mut ranked: Vec<(f64, f64, f64)> = runs
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != r)
            .map(|(k, f)| {
                (
                    between(f, reference, lattice.length).total(),
                    (f.drape_coefficient - reference.drape_coefficient).abs(),
                    ladder[k],
                )
            })
            .collect();
        println!(
            "reference λ = {}: {}",
            ladder[r],
            ranked
                .iter()
                .map(|(d, dc, c)| format!("λ {c}: D {d:.4} (|Δ drape| {dc:.3})"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        for w in ranked.windows(2) {
            assert!(
                w[0].1 <= w[1].1 + 0.01,
                "against λ = {}, the distance ranks λ = {} (|Δ drape| {:.3}) before λ = {} ({:.3})",
                ladder[r],
                w[0].2,
                w[0].1,
                w[1].2,
                w[1].1
            );
        }
    }
}

#[test]
fn a_drape_target_is_met() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("drape");
    let mut args = vec![
        "fit",
        CUSICK,
        "--vary",
        "solver.weights.curvature=0.5..0.95",
        "--target",
        "drape_coefficient=0.45",
        "--budget",
        "24",
        "--out",
    ];
    let out_s = out.to_str().unwrap().to_string();
    args.push(&out_s);
    let o = weft().args(&args).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    println!("{table}");
    let row = table
        .lines()
        .find(|l| l.trim_start().starts_with("drape_coefficient"))
        .expect("a drape row");
    let fitted: f64 = row.split_whitespace().nth(4).unwrap().parse().unwrap();
    assert!(
        (fitted - 0.45).abs() <= 0.02,
        "fitted drape coefficient {fitted}: {row}"
    );
    // The fitted preset loads, and is what `weft show` prints.
    let fitted = out.join("fitted.toml");
    let show = weft().arg("show").arg(&fitted).output().unwrap();
    assert!(show.status.success(), "{}", stderr(&show));
    assert!(out.join("comparison.rrd").is_file());
}

#[test]
fn a_fit_is_the_same_across_threads_interruptions_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let straight = dir.path().join("straight");
    let o = drape_fit(&straight, &["--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    let fitted = std::fs::read_to_string(straight.join("fitted.toml")).unwrap();

    // One thread each, interrupted once a point of the first swarm is done,
    // then resumed by the same command.
    let resumed = dir.path().join("resumed");
    let mut child = weft()
        .args(drape_args(&resumed, &["--jobs", "1"]))
        .env("RAYON_NUM_THREADS", "1")
        .stderr(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = || {
        std::fs::read_dir(resumed.join("gen-001"))
            .map(|d| {
                d.filter_map(Result::ok).any(|e| {
                    let n = e.file_name().to_string_lossy().to_string();
                    n.ends_with(".json") && n != "sweep.json"
                })
            })
            .unwrap_or(false)
    };
    let code = common::interrupt_when(&mut child, "no point of the swarm finished", started);
    assert_eq!(code, Some(130), "interrupted");
    assert!(!resumed.join("fitted.toml").exists());
    let o = drape_fit(&resumed, &["--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("generation 0:"),
        "the resumed fit skips what was run: {}",
        stderr(&o)
    );
    assert_eq!(String::from_utf8_lossy(&o.stdout), table);
    assert_eq!(
        std::fs::read_to_string(resumed.join("fitted.toml")).unwrap(),
        fitted
    );
    assert_eq!(points(&resumed), points(&straight));

    // Two shards, each run in turn until the fit is complete, then the report.
    let sharded = dir.path().join("sharded");
    for _ in 0..20 {
        let status = drape_fit(&sharded, &["--status"]);
        if status.status.code() == Some(0) {
            break;
        }
        assert_eq!(status.status.code(), Some(3), "{}", stderr(&status));
        for s in ["0/2", "1/2"] {
            let o = drape_fit(&sharded, &["--shard", s]);
            assert!(o.status.success(), "{}", stderr(&o));
        }
    }
    let o = drape_fit(&sharded, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("run(s) here"), "{}", stderr(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout), table);
    assert_eq!(points(&sharded), points(&straight));
}

#[test]
fn bad_fits_exit_2_naming_the_argument_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let other = dir.path().join("other.rrd");
    let rec = weft()
        .args(["record", "hanging_sheet", "--frames", "2", "--level", "off"])
        .arg("--save")
        .arg(&other)
        .output()
        .unwrap();
    assert!(rec.status.success(), "{}", stderr(&rec));
    let other = other.to_str().unwrap().to_string();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--vary", "cloth.width=0.5..2", "--target", "sag=0.1"],
            "--vary cloth.width: not a live key",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvture=0.1..0.5",
                "--target",
                "sag=0.1",
            ],
            "did you mean `solver.weights.curvature`",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.5..0.5",
                "--target",
                "sag=0.1",
            ],
            "the range is empty",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.9..0.5",
                "--target",
                "sag=0.1",
            ],
            "the range is reversed",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.5..3",
                "--target",
                "sag=0.1",
            ],
            "--vary solver.weights.curvature=0.5..3",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.1..0.5",
                "--target",
                "sag=0.1",
                "--budget",
                "0",
            ],
            "--budget 0",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.1..0.5",
                "--target",
                "drape_coeficient=0.45",
            ],
            "did you mean `drape_coefficient`",
        ),
        (
            vec![
                "--vary",
                "solver.weights.curvature=0.1..0.5",
                "--to",
                &other,
            ],
            "a run of another scene",
        ),
        (
            vec!["--vary", "solver.weights.curvature=0.1..0.5"],
            "nothing to fit to",
        ),
        (vec!["--target", "sag=0.1"], "nothing to fit"),
    ];
    for (k, (args, expected)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("fit{k}"));
        let o = weft()
            .args(["fit", "windy_flag", "--out", out.to_str().unwrap()])
            .args(args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(expected),
            "{args:?}: expected `{expected}` in: {}",
            stderr(&o)
        );
        assert!(!out.exists(), "{args:?}: nothing may run or be written");
    }
}
