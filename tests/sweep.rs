//! Sweeps: grid expansion and ranges, point names, resume after an
//! interruption, `--jobs` and shards giving the same results as a serial
//! run, `--collect` (sorting, CSV, JSON, Markdown), shards from Slurm and
//! Kubernetes variables, and every bad input refused with exit 2 before
//! anything runs.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Output;

use weft::sweep::grid::{self, Axis};
use weft::sweep::shard::{self, Shard};
use weft::sweep::{PointResult, collect};

mod common;
use common::weft;

fn run(args: &[&str]) -> Output {
    weft().args(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A small, quick sweep: 2 × 2 points of 6 frames of hanging_sheet.
const GRID: [&str; 4] = [
    "--set",
    "solver.weights.curvature=0.05,0.3",
    "--set",
    "solver.iterations=1..2:2",
];

fn sweep(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["sweep", "hanging_sheet"];
    args.extend(GRID);
    args.extend(["--frames", "6", "--out", dir.to_str().unwrap()]);
    args.extend(extra);
    run(&args)
}

/// Point name → (figures without wall-clock timing, digest) of every point.
fn results(dir: &Path) -> BTreeMap<String, (String, String)> {
    collect::read(dir)
        .unwrap()
        .points
        .into_iter()
        .map(|p: PointResult| {
            let mut f = p.figures.clone();
            f.wall_seconds = 0.0;
            f.steps_per_second = 0.0;
            (p.name, (format!("{f:?}"), p.figures.final_state))
        })
        .collect()
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

#[test]
fn grid_expands_lists_and_ranges_in_order_with_stable_names() {
    let a: Axis = "solver.weights.curvature=0.05..0.4:8".parse().unwrap();
    assert_eq!(
        a.texts,
        ["0.05", "0.1", "0.15", "0.2", "0.25", "0.3", "0.35", "0.4"]
    );
    let b: Axis = "solver.iterations=5..20:4".parse().unwrap();
    assert_eq!(b.texts, ["5", "10", "15", "20"]);
    let c: Axis = "solver.iterations=1..2:3".parse().unwrap();
    assert_eq!(
        c.texts,
        ["1.0", "1.5", "2.0"],
        "a fractional step gives floats"
    );
    let d: Axis = "environment.wind.velocity=[0, 1, 0],[2, 0, 0]"
        .parse()
        .unwrap();
    assert_eq!(d.texts, ["[0, 1, 0]", "[2, 0, 0]"], "commas inside arrays");
    let fixed: Axis = "solver.substeps=4".parse().unwrap();

    let points = grid::points(&[
        b.clone(),
        fixed,
        "solver.weights.curvature=0.1,0.35".parse().unwrap(),
    ]);
    assert_eq!(points.len(), 8);
    let names: Vec<&str> = points.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names[..3],
        [
            "0_iterations=5_curvature=0.1",
            "1_iterations=5_curvature=0.35",
            "2_iterations=10_curvature=0.1"
        ],
        "the first --set varies slowest; one-value axes are not in names"
    );
    assert!(points.iter().enumerate().all(|(i, p)| p.index == i));
    assert_eq!(
        points[7].settings[1],
        ("solver.substeps".into(), "4".into())
    );

    // Names stay file-name safe, and keys sharing a last segment keep their path.
    let wind = grid::points(&[d]);
    assert!(
        wind.iter().all(|p| p
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._=+-".contains(c))),
        "{:?}",
        wind.iter().map(|p| &p.name).collect::<Vec<_>>()
    );
    let twice = grid::points(&[
        "expect.max_violation.stretch=0.1,0.2".parse().unwrap(),
        "telemetry.corrections.stretch=true,false".parse().unwrap(),
    ]);
    assert_eq!(
        twice[0].name,
        "0_expect.max_violation.stretch=0.1_telemetry.corrections.stretch=true"
    );
    // Long values are cut, the index keeps names unique.
    let long = grid::points(&[
        format!("description={},{}", "a".repeat(300), "b".repeat(300))
            .parse()
            .unwrap(),
    ]);
    assert!(long.iter().all(|p| p.name.len() == grid::MAX_NAME));
    assert_ne!(long[0].name, long[1].name);
    // Twelve points: indices padded so names sort in grid order.
    let wide = grid::points(&["solver.iterations=1..12:12".parse().unwrap()]);
    assert_eq!(wide[0].name, "00_iterations=1");
    assert_eq!(wide[11].name, "11_iterations=12");
}

#[test]
fn bad_lists_and_ranges_are_refused_with_their_reason() {
    for (arg, says) in [
        ("solver.iterations=1..4", "say how many values"),
        ("solver.iterations=1..4:1", "at least 2"),
        ("solver.iterations=a..4:2", "must be numbers"),
        ("solver.iterations=1,,2", "empty value"),
        ("solver.iterations=1,1", "listed twice"),
        ("solver.iterations", "not of the form"),
    ] {
        let e = arg.parse::<Axis>().unwrap_err().to_string();
        assert!(e.contains(says), "{arg}: {e}");
    }
}

#[test]
fn shards_parse_check_and_come_from_slurm_or_kubernetes() {
    assert_eq!(
        "1/4".parse::<Shard>().unwrap(),
        Shard { index: 1, count: 4 }
    );
    for (s, says) in [
        ("3/2", "does not exist"),
        ("0/0", "at least 1"),
        ("2", "expected I/N"),
        ("a/2", "not a whole number"),
    ] {
        let e = s.parse::<Shard>().unwrap_err().to_string();
        assert!(e.contains(says), "{s}: {e}");
    }
    let env = |pairs: &'static [(&'static str, &'static str)]| {
        move |k: &str| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    };
    assert_eq!(shard::resolve(None, None, env(&[])).unwrap(), None);
    let slurm = env(&[
        ("SLURM_ARRAY_TASK_ID", "3"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
    ]);
    assert_eq!(
        shard::resolve(None, None, slurm).unwrap(),
        Some(Shard { index: 3, count: 4 })
    );
    // `--array=1-4` and `--array=0-6:2` number their tasks from MIN by STEP.
    let from_one = env(&[
        ("SLURM_ARRAY_TASK_ID", "4"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
    ]);
    assert_eq!(
        shard::resolve(None, None, from_one).unwrap(),
        Some(Shard { index: 3, count: 4 })
    );
    let stepped = env(&[
        ("SLURM_ARRAY_TASK_ID", "6"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
        ("SLURM_ARRAY_TASK_STEP", "2"),
    ]);
    assert_eq!(
        shard::resolve(None, None, stepped).unwrap(),
        Some(Shard { index: 3, count: 4 })
    );
    // The command line wins over the environment.
    let flag = Some(Shard { index: 0, count: 2 });
    assert_eq!(shard::resolve(flag, None, slurm).unwrap(), flag);
    let k8s = env(&[("JOB_COMPLETION_INDEX", "2")]);
    assert_eq!(
        shard::resolve(None, Some(3), k8s).unwrap(),
        Some(Shard { index: 2, count: 3 })
    );
    assert!(
        shard::resolve(None, None, k8s)
            .unwrap_err()
            .to_string()
            .contains("--shards N")
    );
    assert!(
        shard::resolve(None, Some(2), k8s)
            .unwrap_err()
            .to_string()
            .contains("does not exist")
    );
    assert!(
        shard::resolve(None, Some(2), env(&[]))
            .unwrap_err()
            .to_string()
            .contains("--shard I/2")
    );
}

#[test]
fn a_sweep_writes_every_point_and_resumes_after_an_interruption() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    let o = sweep(&out, &["--jobs", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let names = [
        "0_curvature=0.05_iterations=1",
        "1_curvature=0.05_iterations=2",
        "2_curvature=0.3_iterations=1",
        "3_curvature=0.3_iterations=2",
    ];
    let mut expected: Vec<String> = names
        .iter()
        .flat_map(|n| [format!("{n}.json"), format!("{n}.rrd")])
        .collect();
    expected.extend(["sweep.json".into(), "report.html".into()]);
    expected.sort();
    assert_eq!(files(&out), expected);
    let before = results(&out);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(manifest["points"].as_array().unwrap().len(), 4);
    assert_eq!(manifest["axes"][1]["values"], serde_json::json!(["1", "2"]));
    // Each point's recording holds its preset with its settings, and its summary.
    let rec = weft::telemetry::read::read(&out.join(format!("{}.rrd", names[2]))).unwrap();
    assert!(rec.preset.unwrap().contains("curvature = 0.3"));
    assert!(rec.summary.is_some());

    // An interruption: one point cut off mid-write (its JSON gone, a
    // half-written .part left), another never started.
    let cut = out.join(format!("{}.json", names[1]));
    std::fs::rename(&cut, out.join(format!("{}.json.part", names[1]))).unwrap();
    std::fs::remove_file(out.join(format!("{}.rrd", names[3]))).unwrap();
    std::fs::remove_file(out.join(format!("{}.json", names[3]))).unwrap();
    let kept = std::fs::metadata(out.join(format!("{}.rrd", names[0])))
        .unwrap()
        .modified()
        .unwrap();

    let o = sweep(&out, &["--jobs", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("2 run, 2 already done"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::metadata(out.join(format!("{}.rrd", names[0])))
            .unwrap()
            .modified()
            .unwrap(),
        kept,
        "a finished point is not run again"
    );
    assert_eq!(results(&out), before, "the resumed sweep equals the first");
    let after: Vec<String> = files(&out)
        .into_iter()
        .filter(|f| !f.ends_with(".part"))
        .collect();
    assert_eq!(after, expected);

    // Another grid in the same directory is refused, and nothing is touched.
    let o = run(&[
        "sweep",
        "hanging_sheet",
        "--set",
        "solver.iterations=3,4",
        "--frames",
        "6",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("holds another sweep"), "{}", stderr(&o));
    assert_eq!(results(&out), before);
}

#[test]
fn parallel_and_sharded_sweeps_equal_the_serial_one() {
    let dir = tempfile::tempdir().unwrap();
    let serial = dir.path().join("serial");
    let parallel = dir.path().join("parallel");
    let sharded = dir.path().join("sharded");
    assert!(sweep(&serial, &["--jobs", "1"]).status.success());
    assert!(sweep(&parallel, &["--jobs", "2"]).status.success());
    for i in 0..3 {
        let spec = format!("{i}/3");
        let o = sweep(&sharded, &["--jobs", "1", "--shard", &spec]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let reference = results(&serial);
    assert_eq!(reference.len(), 4);
    assert_eq!(results(&parallel), reference, "--jobs 2");
    assert_eq!(results(&sharded), reference, "the union of 3 shards");
    // The same files; a shard leaves the page to `--collect`.
    let mut whole = files(&sharded);
    whole.push("report.html".into());
    whole.sort();
    assert_eq!(whole, files(&serial));

    // A Slurm array task takes its shard from the environment.
    let slurm = dir.path().join("slurm");
    let mut args = vec!["sweep", "hanging_sheet"];
    args.extend(GRID);
    args.extend(["--frames", "6", "--out", slurm.to_str().unwrap()]);
    let o = weft()
        .args(&args)
        .env("SLURM_ARRAY_TASK_ID", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "2")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("shard 1/2, 2 here"), "{}", stderr(&o));
    let got = results(&slurm);
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        [
            "1_curvature=0.05_iterations=2",
            "3_curvature=0.3_iterations=2"
        ]
    );
    assert!(got.iter().all(|(k, v)| reference[k] == *v));
}

#[test]
fn collect_sorts_and_prints_text_csv_json_and_markdown() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    assert!(sweep(&out, &[]).status.success());
    let d = out.to_str().unwrap();

    let o = run(&[
        "sweep",
        "--collect",
        d,
        "--sort",
        "max_strain",
        "--csv",
        "--best",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = String::from_utf8(o.stdout.clone()).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let col = |name: &str| rows[0].iter().position(|c| *c == name).unwrap();
    assert_eq!(rows.len(), 5);
    for key in [
        "solver.weights.curvature",
        "solver.iterations",
        "max_violation.stretch",
        "verdict",
        "final_state",
    ] {
        col(key);
    }
    let strains: Vec<f64> = rows[1..]
        .iter()
        .map(|r| r[col("max_strain")].parse().unwrap())
        .collect();
    assert!(strains.windows(2).all(|w| w[0] <= w[1]), "{strains:?}");
    // The best two, in a comparison recording.
    let best = weft::telemetry::read::read(&out.join("best.rrd")).unwrap();
    assert_eq!(
        best.entities
            .keys()
            .filter(|k| k.starts_with("metrics/strain/"))
            .count(),
        2
    );
    assert!(
        stderr(&o).contains(rows[1][0]),
        "names the best: {}",
        stderr(&o)
    );

    let o = run(&[
        "sweep",
        "--collect",
        d,
        "--sort",
        "steps_per_second",
        "--desc",
        "--json",
        "--best",
        "0",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let speeds: Vec<f64> = json
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["figures"]["steps_per_second"].as_f64().unwrap())
        .collect();
    assert_eq!(speeds.len(), 4);
    assert!(speeds.windows(2).all(|w| w[0] >= w[1]), "{speeds:?}");
    assert!(json[0]["verdict"].is_string());

    let o = run(&[
        "sweep",
        "--collect",
        d,
        "--sort",
        "iterations",
        "--markdown",
        "--best",
        "0",
    ]);
    let md = String::from_utf8(o.stdout).unwrap();
    assert!(md.starts_with("| name |"), "{md}");
    assert_eq!(md.lines().count(), 6);

    let o = run(&["sweep", "--collect", d, "--best", "0"]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("0_curvature=0.05_iterations=1"));

    // A point missing from a partial sweep is named.
    std::fs::remove_file(out.join("3_curvature=0.3_iterations=2.json")).unwrap();
    let o = run(&["sweep", "--collect", d, "--best", "0"]);
    assert!(stderr(&o).contains("1 of 4 points not finished: 3_curvature=0.3_iterations=2"));

    let o = run(&["sweep", "--collect", d, "--sort", "nonsense"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--sort nonsense"), "{}", stderr(&o));
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = run(&["sweep", "--collect", empty.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no weft sweep here"));
}

#[test]
fn bad_sweeps_exit_2_with_a_located_message_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    let o_ = out.to_str().unwrap();
    for (args, says) in [
        (
            vec!["--set", "solver.iterations=2,x"],
            "--set solver.iterations: `solver.iterations`: invalid type",
        ),
        (
            vec!["--set", "solver.iterations=2,x"],
            "at point 1 of the sweep: solver.iterations=x",
        ),
        (
            vec!["--set", "solver.weights.curvature=0.1,-2"],
            "solver.weights.curvature",
        ),
        (
            vec!["--set", "solver.iterationz=2,3"],
            "did you mean `iterations`?",
        ),
        (
            vec!["--set", "solver.iterations=1..4"],
            "say how many values",
        ),
        (
            vec![
                "--set",
                "solver.iterations=1,2",
                "--set",
                "solver.iterations=3",
            ],
            "swept twice",
        ),
        (
            vec!["--set", "solver.iterations=1,2", "--shard", "3/2"],
            "shard 3 of 2 does not exist",
        ),
        (
            vec!["--set", "solver.iterations=1,2", "--shard", "0/0"],
            "at least 1",
        ),
        (
            vec![
                "--set",
                "solver.iterations=1..20:20",
                "--set",
                "solver.weights.curvature=0..1:20",
            ],
            "this sweep has 400 points and would take about",
        ),
    ] {
        let mut all = vec!["sweep", "hanging_sheet", "--frames", "6", "--out", o_];
        all.extend(&args);
        let o = run(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    // A long sweep of few points is refused too.
    let o = run(&[
        "sweep",
        "hanging_sheet",
        "--frames",
        "100000000",
        "--out",
        o_,
        "--set",
        "solver.iterations=1,2",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("this sweep has 2 points and would take about"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("--yes"));
    // Each shard is judged by its own share: shard 0 of 400 is one point.
    let o = run(&[
        "sweep",
        "hanging_sheet",
        "--frames",
        "2",
        "--out",
        o_,
        "--set",
        "solver.iterations=1..20:20",
        "--set",
        "solver.weights.curvature=0..1:20",
        "--shard",
        "0/400",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(collect::read(&out).unwrap().points.len(), 1);
}

#[test]
fn docs_cluster_shows_the_scripts_ci_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/cluster.md")).unwrap();
    for file in [
        "docs/cluster/sweep.sbatch",
        "docs/cluster/sweep-job.yaml",
        "docs/cluster/fit.sbatch",
        "docs/cluster/fit-driver",
    ] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(
            doc.contains(text.trim_end()),
            "docs/cluster.md shows {file} as it is"
        );
    }
    let ci = std::fs::read_to_string(root.join(".ci/run")).unwrap();
    assert!(ci.contains(".ci/slurm-test"), "CI runs the Slurm test");
}

#[test]
fn ctrl_c_finishes_the_running_point_and_the_same_command_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("runs");
    let args = |out: &Path| -> Vec<String> {
        let mut a: Vec<String> = [
            "sweep",
            "hanging_sheet",
            "--set",
            "solver.iterations=1..4:4",
            "--frames",
            "20",
            "--jobs",
            "1",
            "--out",
        ]
        .map(String::from)
        .to_vec();
        a.push(out.to_str().unwrap().into());
        a
    };
    let mut child = weft()
        .args(args(&out))
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let finished = || out.join("0_iterations=1.json").exists();
    let code = common::interrupt_when(&mut child, "no point finished", finished);
    assert_eq!(code, Some(130));
    let done = collect::read(&out).unwrap();
    assert!(
        !done.points.is_empty() && !done.missing.is_empty(),
        "stopped part-way: {:?}",
        done.missing
    );
    assert!(
        files(&out).iter().all(|f| !f.ends_with(".part")),
        "the running point was finished, not cut: {:?}",
        files(&out)
    );
    for p in &done.points {
        assert!(
            weft::telemetry::read::read(&out.join(format!("{}.rrd", p.name)))
                .unwrap()
                .summary
                .is_some()
        );
    }
    let o = weft().args(args(&out)).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{} already done", done.points.len())),
        "{}",
        stderr(&o)
    );
    assert!(collect::read(&out).unwrap().missing.is_empty());
}
