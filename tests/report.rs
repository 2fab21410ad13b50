//! The results' pages (`report.html`), opened in a real browser: a small
//! sweep's, a small fit's and a comparison's page load in headless Chromium
//! without a script error and every plot on them is drawn (the page counts
//! them and says so in its footer). Screenshots of the three are left in
//! `target/report-pages/` for a person to look at. And what a directory
//! that holds no results, or a sweep not finished, gives.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::weft;

/// The browser: Debian's `chromium` (or a Chrome on the path).
fn browser() -> Command {
    let name = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new("sh")
                .args(["-c", &format!("command -v {b}")])
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .expect("Chromium runs the report test (Debian: apt-get install chromium)");
    let mut c = Command::new(name);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--enable-logging=stderr",
        "--v=0",
    ]);
    c
}

/// Opens `page` in the browser: the DOM after the page's script ran, and
/// the browser's log (where a script error would be).
fn open(page: &Path) -> (String, String) {
    let out = browser()
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("the browser runs");
    assert!(out.status.success(), "{out:?}");
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Saves a screenshot of `page` as `target/report-pages/NAME.png`.
fn screenshot(page: &Path, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-pages");
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join(format!("{name}.png"));
    let out = browser()
        .arg("--window-size=1280,2400")
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("the browser runs");
    assert!(out.status.success(), "{out:?}");
    png
}

/// The page loaded, its script ran without an error, and it drew all of at
/// least `least` plots.
fn assert_drawn(page: &Path, least: usize) -> String {
    let (dom, log) = open(page);
    assert!(
        !log.contains("Uncaught") && !log.contains("SyntaxError"),
        "a script error: {log}"
    );
    let attr = |name: &str| -> usize {
        let at = dom
            .find(&format!("{name}=\""))
            .unwrap_or_else(|| panic!("the page's script set no {name}: {dom:.400}"));
        let rest = &dom[at + name.len() + 2..];
        rest[..rest.find('"').unwrap()].parse().unwrap()
    };
    let (plots, drawn) = (attr("data-plots"), attr("data-drawn"));
    assert!(plots >= least, "{plots} plots, at least {least} expected");
    assert_eq!(drawn, plots, "every plot has a size on screen");
    assert!(dom.contains(&format!("{plots} of {plots} plots drawn")));
    dom
}

/// The page (its DOM) shows each of `texts`.
fn assert_shows(dom: &str, what: &str, texts: &[&str]) {
    for text in texts {
        assert!(dom.contains(text), "the {what}'s page shows {text}");
    }
}

fn run(c: &mut Command) -> std::process::Output {
    let out = c.output().expect("weft runs");
    assert!(out.status.success(), "{out:?}");
    out
}

#[test]
fn a_sweep_a_fit_and_a_comparison_show_their_plots_in_a_browser() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep = tmp.path().join("sweep");
    run(weft()
        .args([
            "sweep",
            "hanging_sheet",
            "--set",
            "solver.weights.curvature=0.05,0.2",
            "--set",
            "solver.iterations=3,5",
            "--frames",
            "20",
            "--out",
        ])
        .arg(&sweep));
    let page = sweep.join("report.html");
    let dom = assert_drawn(&page, 16);
    // Each figure against each key and over both, the best point by each,
    // every point with its verdict and recording, the command that made it.
    assert_shows(
        &dom,
        "sweep",
        &[
            "max strain by curvature",
            "max strain over curvature and iterations",
            "The best point by each figure",
            "3_curvature=0.2_iterations=5.rrd",
            "weft sweep hanging_sheet --set solver.weights.curvature=0.05,0.2",
            "solver revision",
        ],
    );
    assert!(!dom.contains("Partial"));
    screenshot(&page, "sweep");

    let fit = tmp.path().join("fit");
    run(weft()
        .args([
            "fit",
            "hanging_sheet",
            "--vary",
            "solver.weights.curvature=0.05..0.5",
            "--target",
            "max_strain=0.006",
            "--budget",
            "6",
            "--seconds",
            "0.3",
            "--out",
        ])
        .arg(&fit));
    let page = fit.join("report.html");
    let dom = assert_drawn(&page, 3);
    assert_shows(
        &dom,
        "fit",
        &[
            "distance by run",
            "distance by generation",
            "solver.weights.curvature by run",
            "Start, fit and reference",
            "fitted.toml",
        ],
    );
    screenshot(&page, "fit");
    // Made again from the directory alone, the same page.
    let first = std::fs::read_to_string(&page).unwrap();
    run(weft().arg("report").arg(&fit));
    assert_eq!(std::fs::read_to_string(&page).unwrap(), first);

    let cmp = tmp.path().join("cmp");
    run(weft()
        .arg("compare")
        .arg(sweep.join("0_curvature=0.05_iterations=3.rrd"))
        .arg(sweep.join("3_curvature=0.2_iterations=5.rrd"))
        .arg("--out")
        .arg(&cmp));
    let page = cmp.join("report.html");
    let dom = assert_drawn(&page, 8);
    assert_shows(
        &dom,
        "comparison",
        &[
            "Where the runs part",
            "first frame its particles differ from A",
            "solver.iterations",
            "kinetic energy",
            "comparison.rrd",
        ],
    );
    screenshot(&page, "comparison");
}

#[test]
fn a_directory_without_results_says_what_makes_them() {
    let tmp = tempfile::tempdir().unwrap();
    let out = weft().arg("report").arg(tmp.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    for text in [
        "no finished sweep, fit or comparison",
        "weft sweep",
        "weft fit",
        "weft compare",
    ] {
        assert!(err.contains(text), "{text} in {err}");
    }
}

#[test]
fn a_sweep_not_finished_gives_a_page_of_what_is_done_labelled_partial() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    run(weft()
        .args([
            "sweep",
            "hanging_sheet",
            "--set",
            "solver.iterations=3,4,5",
            "--frames",
            "10",
            "--out",
        ])
        .arg(&dir));
    // A point lost (a shard that has not run yet looks the same).
    for ext in ["json", "rrd"] {
        std::fs::remove_file(dir.join(format!("1_iterations=4.{ext}"))).unwrap();
    }
    run(weft().arg("report").arg(&dir));
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("<b>Partial:</b> 2 of 3 points are finished"));
    assert!(html.contains("Not finished: 1_iterations=4"));
}
