//! weft: an oriented-particle cloth simulator and live-telemetry debugger.
//!
//! - [`solver`]: the paper's method; depends on neither Rerun nor egui.
//!
//! See `ARCHITECTURE.md` for the map of the crate.

pub mod solver;
