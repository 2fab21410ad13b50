//! Helpers shared by the integration tests that run the `weft` binary.

// Each test file uses the helpers it needs.
#![allow(dead_code)]

pub mod crossings;
#[cfg(feature = "viewer")]
pub mod panel;

use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// The `weft` binary that `cargo test` built.
pub fn weft() -> Command {
    Command::new(env!("CARGO_BIN_EXE_weft"))
}

/// Waits (up to two minutes, else fails saying `what` never happened) until
/// `ready` holds, then sends the child a Ctrl-C (SIGINT) and returns its
/// exit code.
pub fn interrupt_when(child: &mut Child, what: &str, ready: impl Fn() -> bool) -> Option<i32> {
    let start = Instant::now();
    while !ready() {
        assert!(start.elapsed() < Duration::from_secs(120), "{what}");
        std::thread::sleep(Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    child.wait().expect("the child ends").code()
}

/// No gravity, no air: nothing acts on a cloth from outside.
pub fn calm() -> weft::solver::Environment {
    weft::solver::Environment {
        gravity: glam::Vec3::ZERO,
        air_density: 0.0,
        ..weft::solver::Environment::default()
    }
}
