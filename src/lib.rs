//! weft: an oriented-particle cloth simulator and live-telemetry debugger.
//!
//! - [`solver`]: the paper's method; depends on neither Rerun nor egui.
//! - [`scene`]: presets (TOML) and the scenes they describe: moving bodies,
//!   wind, colliders, on top of the solver.
//!
//! Both are the library crate `weft-cloth` (`src/cloth/`), re-exported here;
//! the rest is the application on top of it:
//! - [`telemetry`]: streams a scene to Rerun; reads recordings back.
//! - [`record`], [`replay`]: headless runs with CI verdicts, and their
//!   bit-for-bit reproduction.
//! - [`compare`], [`sweep`]: recorded runs side by side, and grids of runs
//!   (also sharded over a batch engine's array jobs).
//! - [`fit`]: the values of live keys that bring a preset closest to a
//!   reference run or to target figures, searched on sweeps.
//! - [`report`]: a sweep's, a fit's or a comparison's results as one HTML
//!   page with plots.
//! - [`interrupt`]: Ctrl-C for long headless jobs (a clean stop, then a quit).
//! - [`cli`]: the `weft` command line.
//! - `app` (feature `viewer`, on by default): the desktop debugger, the Rerun
//!   viewer embedded beside an egui tuning panel.
//!
//! See `ARCHITECTURE.md` for the map of the crate.

// Unit tests compare with the platform's math library and set scenes up
// with glam's rotations; only the code they test must avoid them
// (`solver::portable`, `clippy.toml`).
#![cfg_attr(test, allow(clippy::disallowed_methods))]

#[cfg(feature = "viewer")]
pub mod app;
pub mod cli;
pub mod compare;
pub mod fit;
pub mod interrupt;
pub mod record;
pub mod replay;
pub mod report;
pub use weft_cloth::{scene, solver};
pub mod sweep;
pub mod telemetry;
