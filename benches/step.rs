//! Solver benchmarks (`cargo bench`): step time by size, beside a peer XPBD
//! solver on the same grid; threads; the shipped presets; cost per family;
//! self-collision on and off; telemetry cost.
//!
//! Every "step" here is one solver step of Δt = 1/60 s with one substep and
//! 10 adjust iterations, a vertical sheet pinned at its two top corners,
//! measured after 30 warm-up steps so the cloth is moving.

// Tests and benchmarks set their scenes up with glam's rotations and
// compare with the standard library: they run on one machine, so the
// platform's math library is fine here (see `solver::portable`).
#![allow(clippy::disallowed_methods)]

use std::f32::consts::FRAC_PI_2;
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Quat;
use weft::scene::{Scene, load};
use weft::solver::{ClothSpec, Environment, Family, Params, Pose, Solver, Weights};
use weft::telemetry::Telemetry;

const DT: f32 = 1.0 / 60.0;
const ITERATIONS: u32 = 10;

fn weft_sheet(n: u32, weights: Weights) -> Solver {
    let spec = ClothSpec {
        weft: n,
        warp: n,
        rotation: Quat::from_rotation_x(FRAC_PI_2),
        ..ClothSpec::default()
    };
    let params = Params {
        iterations: ITERATIONS,
        substeps: 1,
        dt: DT,
        weights,
        ..Params::default()
    };
    let mut s = Solver::new(spec, params, &[Pose::IDENTITY]).unwrap();
    s.attach(spec.index(0, n - 1), 0);
    s.attach(spec.index(n - 1, n - 1), 0);
    for _ in 0..30 {
        s.step(&Environment::default(), &[Pose::IDENTITY]).unwrap();
    }
    s
}

/// The default weights with self-collision off: the peer has none, and the
/// step and thread benchmarks measure the paper's families.
fn without_self_collision() -> Weights {
    Weights::default_weights().with(Family::SelfCollision, 0.0)
}

/// The peer: rapier-cloth-core's XPBD solver, same grid, pins, iterations, Δt.
struct Peer {
    cloth: rapier_cloth_core::Cloth,
    solver: rapier_cloth_core::Solver,
    settings: rapier_cloth_core::SolverSettings,
}

impl Peer {
    fn new(n: usize) -> Self {
        use rapier_cloth_core::{Cloth, ClothMaterial, GridBuilder, Solver, SolverSettings, Vec3};
        let mesh = GridBuilder::new(n, n)
            .size(1.0, 1.0)
            .origin(Vec3::ZERO)
            .axes(Vec3::X, Vec3::Z)
            .build()
            .unwrap();
        let mut cloth = Cloth::new(mesh, ClothMaterial::default()).unwrap();
        let top = |i: usize| ((n - 1) * n + i) as u32;
        for i in [top(0), top(n - 1)] {
            let p = cloth.positions()[i as usize];
            cloth.pin(i, p).unwrap();
        }
        let settings = SolverSettings {
            iterations: ITERATIONS as usize,
            ..SolverSettings::default()
        };
        let mut peer = Self {
            cloth,
            solver: Solver::new(),
            settings,
        };
        for _ in 0..30 {
            peer.step();
        }
        peer
    }

    fn step(&mut self) {
        let g = rapier_cloth_core::Vec3::new(0.0, 0.0, -9.81);
        self.solver
            .step(&mut self.cloth, DT, g, &self.settings)
            .unwrap();
    }
}

fn step_by_size(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    g.sample_size(20);
    for n in [32u32, 64, 128, 256] {
        g.throughput(Throughput::Elements((n * n) as u64));
        let mut s = weft_sheet(n, without_self_collision());
        g.bench_with_input(BenchmarkId::new("weft", n), &n, |b, _| {
            b.iter(|| s.step(&Environment::default(), &[Pose::IDENTITY]).unwrap())
        });
        let mut peer = Peer::new(n as usize);
        g.bench_with_input(BenchmarkId::new("rapier-cloth-core", n), &n, |b, _| {
            b.iter(|| peer.step())
        });
    }
    g.finish();
}

fn threads(c: &mut Criterion) {
    let mut g = c.benchmark_group("threads");
    g.sample_size(20);
    for n in [64u32, 128] {
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut s = pool.install(|| weft_sheet(n, without_self_collision()));
            g.bench_with_input(
                BenchmarkId::new(format!("weft {n}x{n}"), threads),
                &threads,
                |b, _| {
                    b.iter(|| {
                        pool.install(|| s.step(&Environment::default(), &[Pose::IDENTITY]).unwrap())
                    })
                },
            );
        }
    }
    g.finish();
}

/// Every shipped preset as it ships, one frame (1/60 s) per iteration,
/// stepped from 2 s into its run, without telemetry: the solver's share of
/// `weft record`'s steps per second (real time is 60 frames a second).
fn presets(c: &mut Criterion) {
    let mut g = c.benchmark_group("preset frame");
    g.sample_size(30);
    for shipped in weft::scene::shipped::ALL {
        let loaded = load::load(shipped.name, &[]).unwrap();
        let mut scene = Scene::new(&loaded.preset).unwrap();
        for _ in 0..120 {
            scene.step().unwrap();
        }
        g.bench_function(shipped.name, |b| b.iter(|| scene.step().unwrap()));
    }
    g.finish();
}

fn per_family(c: &mut Criterion) {
    let mut g = c.benchmark_group("family 64x64");
    g.sample_size(20);
    for f in Family::ALL {
        let mut s = weft_sheet(64, Weights::splat(0.0).with(f, 1.0));
        g.bench_function(f.name(), |b| {
            b.iter(|| s.step(&Environment::default(), &[Pose::IDENTITY]).unwrap())
        });
    }
    g.finish();
}

/// Self-collision's cost at 64 × 64, on and off: on the benchmark sheet
/// (hanging, no contacts: the contact search alone), and on `folding_sheet`
/// at 64 × 64 (4 substeps × 2 sweeps) from the moment its fold is laid down,
/// with contacts in every substep.
fn self_collision(c: &mut Criterion) {
    let mut g = c.benchmark_group("self-collision 64x64");
    g.sample_size(20);
    for (name, weight) in [("sheet off", 0.0), ("sheet on", 1.0)] {
        let weights = Weights::default_weights().with(Family::SelfCollision, weight);
        let mut s = weft_sheet(64, weights);
        g.bench_function(name, |b| {
            b.iter(|| s.step(&Environment::default(), &[Pose::IDENTITY]).unwrap())
        });
    }
    let sets: Vec<load::Override> = ["cloth.weft=64", "cloth.warp=64"]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let folded = {
        let preset = load::load("folding_sheet", &sets).unwrap().preset;
        let mut scene = Scene::new(&preset).unwrap();
        for _ in 0..scene.frames_in(4.6) {
            scene.step().unwrap();
        }
        scene
    };
    for (name, weight) in [("fold off", 0.0), ("fold on", 1.0)] {
        let mut scene = folded.clone();
        let mut params = *scene.solver().params();
        params.weights[Family::SelfCollision] = weight;
        scene.set_params(params).unwrap();
        g.bench_function(name, |b| b.iter(|| scene.step().unwrap()));
    }
    g.finish();
}

fn telemetry(c: &mut Criterion) {
    let mut g = c.benchmark_group("telemetry 64x64");
    g.sample_size(20);
    let dir = tempfile::tempdir().unwrap();
    let sets = |level: &str| -> Vec<weft::scene::Override> {
        [
            "cloth.weft=64",
            "cloth.warp=64",
            "solver.substeps=1",
            "solver.iterations=10",
            "solver.weights.self=0",
            &format!("telemetry.level=\"{level}\""),
        ]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect()
    };
    for level in ["off", "summary", "full"] {
        for sink in ["file", "memory"] {
            let loaded = load::load("hanging_sheet", &sets(level)).unwrap();
            let mut scene = Scene::new(&loaded.preset).unwrap();
            let (rec, _storage) = match sink {
                "file" => (
                    rerun::RecordingStreamBuilder::new("weft-bench")
                        .batcher_config(weft::telemetry::file_batching().unwrap())
                        .save(dir.path().join(format!("{level}.rrd")))
                        .unwrap(),
                    None,
                ),
                _ => {
                    let (rec, storage) = rerun::RecordingStreamBuilder::new("weft-bench")
                        .memory()
                        .unwrap();
                    (rec, Some(storage))
                }
            };
            let mut t = Telemetry::new(rec, loaded.preset.telemetry);
            t.configure(scene.solver_mut());
            t.log_static(&scene, &loaded.resolved).unwrap();
            g.bench_function(BenchmarkId::new(level, sink), |b| {
                b.iter(|| {
                    scene.step().unwrap();
                    t.log_frame(black_box(&scene)).unwrap();
                })
            });
            if let Some(storage) = _storage {
                // Keep memory bounded between benchmarks.
                drop(storage.take());
            }
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = step_by_size, threads, presets, per_family, self_collision, telemetry
}
criterion_main!(benches);
