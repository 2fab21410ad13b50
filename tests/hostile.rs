//! Hostile presets and `--set` arguments, as a careless user or an attacker
//! would write them: each is refused (or warned about) quickly, with a
//! message that says where and what.

use std::path::Path;
use std::process::Command;
use std::sync::mpsc;
use std::time::Duration;

use weft::scene::load::{self, Override, PresetError};

fn sets(list: &[&str]) -> Vec<Override> {
    list.iter().map(|s| s.parse().unwrap()).collect()
}

fn load_path(path: &Path, overrides: &[Override]) -> Result<load::Loaded, PresetError> {
    load::load(path.to_str().unwrap(), overrides)
}

/// Runs `f` on a thread; fails instead of hanging if it has not answered in
/// 10 s (the unbounded versions took minutes or ate the machine's memory).
fn answers<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || tx.send(f()).unwrap());
    rx.recv_timeout(Duration::from_secs(10))
        .expect("no answer within 10 s")
}

/// An `extend` naming something that is not a small regular file is refused
/// before it is read, at the `extend` line that named it.
#[test]
fn extend_reads_only_small_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let huge = dir.path().join("huge.toml");
    // Sparse: two gigabytes that take no disk.
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(2 << 30)
        .unwrap();
    std::fs::create_dir(dir.path().join("folder.toml")).unwrap();
    let child = dir.path().join("child.toml");
    let cases = [
        ("/dev/zero", "not a regular file"),
        ("huge.toml", "too large"),
        ("folder.toml", "is a directory"),
        ("missing.toml", "cannot be read"),
    ];
    for (target, needle) in cases {
        std::fs::write(
            &child,
            format!("description = \"c\"\n\nextend = \"{target}\"\n"),
        )
        .unwrap();
        let path = child.clone();
        let err = answers(move || load_path(&path, &[])).unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with(child.to_str().unwrap()), "{msg}");
        assert_eq!(err.position, Some((3, 1)), "{msg}");
        assert_eq!(err.key.as_deref(), Some("extend"), "{msg}");
        assert!(msg.contains(target) && msg.contains(needle), "{msg}");
    }
    // Named directly, the same limits hold.
    let err = answers(|| load::load("/dev/zero", &[])).unwrap_err();
    assert!(err.to_string().contains("not a regular file"), "{err}");
}

/// A cycle written through `../` is found on the resolved paths, and the
/// message shows tidy paths.
#[test]
fn extend_cycles_are_found_on_resolved_paths() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    std::fs::create_dir(&a).unwrap();
    std::fs::write(
        a.join("x.toml"),
        "description = \"x\"\nextend = \"../a/../a/y.toml\"\n",
    )
    .unwrap();
    std::fs::write(
        a.join("y.toml"),
        "extend = \"../a/./x.toml\"\ndescription = \"y\"\n",
    )
    .unwrap();
    let err = load_path(&a.join("x.toml"), &[]).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("forms a cycle"), "{msg}");
    assert!(!msg.contains(".."), "untidy path in: {msg}");
    assert!(
        msg.contains("x.toml → ") && msg.contains("y.toml → "),
        "{msg}"
    );
    assert_eq!(err.position, Some((1, 1)), "{msg}");
    assert!(err.source.ends_with("y.toml"), "{msg}");
}

/// "Did you mean" on absurdly long names answers at once, and messages show
/// such names clipped.
#[test]
fn long_names_are_compared_and_shown_within_bounds() {
    let name = "a".repeat(100_000);
    let typo = format!("{}b", &name[1..]);
    let text = format!(
        "description = \"x\"\n[cloth]\n[[bodies]]\nname = \"{name}\"\n[bodies.static]\n[[attachments]]\nbody = \"{typo}\"\nselect = [\"top\"]\n"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.toml");
    std::fs::write(&path, text).unwrap();
    let err = answers(move || load_path(&path, &[])).unwrap_err();
    let msg = err.to_string();
    assert!(msg.len() < 500, "{} characters: {}", msg.len(), &msg[..500]);
    assert!(msg.contains("no body is named"), "{msg}");
    assert!(msg.contains("(100000 characters)"), "{msg}");
    assert_eq!(err.position.map(|p| p.0), Some(7), "{msg}");

    // An unknown key of that length, too.
    let text = format!("description = \"x\"\n[cloth]\n{name} = 1\n");
    let err = answers(move || load::parse("long.toml", &text)).unwrap_err();
    let msg = err.to_string();
    assert!(msg.len() < 500, "{} characters", msg.len());
    assert!(msg.contains("unknown key"), "{msg}");
}

/// A `--set` whose key is deeper than any known one, or whose value is
/// checked together with others, is blamed on that `--set` with its key.
#[test]
fn set_errors_are_blamed_on_the_set() {
    let cases: &[(&str, &str, &[&str])] = &[
        // An unknown key below a new table.
        (
            "cloth.fabric.warp=3",
            "cloth.fabric",
            &["unknown key `fabric`"],
        ),
        // The preset's `cloth.position` is the solver's `cloth.origin`.
        (
            "cloth.position=[1e7, 0, 0]",
            "cloth.position",
            &["is out of range", "1000000"],
        ),
        // One value of a `[t, v]` key, checked as a pair.
        (
            "bodies[0].car.speed[1][1]=500",
            "bodies[0].car.speed[1]",
            &["|speed| ≤ 100 m/s"],
        ),
    ];
    for (set, key, needles) in cases {
        let err = load::load("flag_on_car", &sets(&[set])).unwrap_err();
        let msg = err.to_string();
        let written = set.split('=').next().unwrap();
        assert_eq!(err.source, format!("--set {written}"), "{msg}");
        assert_eq!(err.key.as_deref(), Some(*key), "{msg}");
        assert_eq!(err.position, None, "{msg}");
        for n in *needles {
            assert!(msg.contains(n), "`{n}` missing from: {msg}");
        }
        assert!(!msg.contains("not finite"), "{msg}");
    }
    // A problem already in the file stays the file's, whatever is set after it.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(
        &path,
        "description = \"x\"\n[cloth]\n[[attachments]]\nbody = \"hook\"\n[[bodies]]\nname = \"hook\"\n[bodies.static]\n",
    )
    .unwrap();
    let err = load_path(&path, &sets(&["attachments[0].clamp=true"])).unwrap_err();
    assert!(err.source.ends_with("bad.toml"), "{err}");
    assert_eq!(err.position.map(|p| p.0), Some(3), "{err}");
}

/// `extend` is resolved when a file is read: `--set extend=…` is refused.
#[test]
fn set_extend_is_refused() {
    let err = load::load("hanging_sheet", &sets(&["extend=flag_on_car"])).unwrap_err();
    let msg = err.to_string();
    assert!(msg.starts_with("--set extend:"), "{msg}");
    assert!(msg.contains("cannot be set with --set"), "{msg}");
}

/// A file that is not UTF-8 is reported with the line, column and byte offset
/// of the first bad byte.
#[test]
fn non_utf8_files_get_a_position() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latin1.toml");
    std::fs::write(&path, b"description = \"x\"\n[cloth]\nweft = 4 # caf\xe9\n").unwrap();
    let err = load_path(&path, &[]).unwrap_err();
    let msg = err.to_string();
    assert_eq!(err.position, Some((3, 15)), "{msg}");
    assert!(
        msg.contains("not UTF-8") && msg.contains("offset 40"),
        "{msg}"
    );
}

/// A grid far larger than the shipped ones loads, with a warning that
/// estimates its cost; `weft check` prints it to standard error.
#[test]
fn large_grids_are_warned_about_with_an_estimate() {
    for p in weft::scene::shipped::ALL {
        let loaded = load::load(p.name, &[]).unwrap();
        assert!(
            loaded.warnings.is_empty(),
            "{}: {:?}",
            p.name,
            loaded.warnings
        );
    }
    let big = ["cloth.weft=512", "cloth.warp=512"];
    let loaded = load::load("hanging_sheet", &sets(&big)).unwrap();
    // Self-collision is on by default, and 4 mm is more than half a
    // 512 × 512 grid's spacing: the thickness is warned about too.
    let [warning, thickness] = loaded.warnings.as_slice() else {
        panic!("{:?}", loaded.warnings)
    };
    assert!(
        thickness.contains("cloth.thickness = 0.004 m") && thickness.contains("up to 0.0010 m"),
        "{thickness}"
    );
    assert!(
        warning.contains("512 × 512") && warning.contains("per frame"),
        "{warning}"
    );
    assert!(warning.contains("min for the 10 s duration"), "{warning}");
    assert!(
        warning.contains("self-collision is 2.1 s of that"),
        "{warning}"
    );

    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["check", "hanging_sheet", "--set", big[0], "--set", big[1]])
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning: a 512 × 512 cloth"), "{stderr}");
}

/// A reader that goes away (`weft presets | head`, `weft show P | less`
/// quit early) ends the output quietly, not in a panic, and the command's
/// exit code is still its own: `check` of an invalid preset still exits 1
/// with nobody reading.
#[test]
fn a_reader_that_goes_away_is_not_a_panic() {
    let closed = || {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        writer
    };
    for args in [
        &["presets"][..],
        &["show", "flag_on_car"],
        &["check", "windy_flag"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_weft"))
            .args(args)
            .stdout(closed())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {:?} {stderr}", out.status);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    let invalid = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["check", "hanging_sheet", "--set", "cloth.weft=0"])
        .stdout(closed())
        .output()
        .unwrap();
    assert_eq!(
        invalid.status.code(),
        Some(1),
        "an invalid preset still fails"
    );
}
