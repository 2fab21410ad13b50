//! weft's cloth as a library: the oriented-particle, position-based solver
//! of Bae, Baek, Lee and Ryu ([`solver`]), and the presets and scenes that
//! bring it to life ([`scene`]): a preset file (or one of the shipped ones)
//! loaded and validated with located errors, its bodies moved, its wind
//! blown, stepped frame by frame. It knows nothing of Rerun, egui or the
//! command line: the `weft` debugger is an application on top of it, and a
//! host program (a game, a tool) steps the same presets the same way, bit
//! for bit.
//!
//! ```
//! use weft_cloth::scene::{Scene, load};
//!
//! // A shipped preset, or a file the debugger saved: `load::load("my.toml", &[])`.
//! let loaded = load::load("flag_on_car", &[]).unwrap();
//! let mut scene = Scene::new(&loaded.preset).unwrap();
//! for _ in 0..60 {
//!     scene.step().unwrap();
//! }
//! let lowest = scene
//!     .world_positions()
//!     .iter()
//!     .map(|p| p.z)
//!     .fold(f32::INFINITY, f32::min);
//! assert!(lowest > 0.0, "the flag stays above the road");
//! ```
//!
//! Between steps a host changes the weights, the wind or the time step
//! (checked, as the debugger's panel checks them), moves a body itself
//! ([`scene::Scene::drive`]) and reads what the `[expect]` table judges:
//!
//! ```
//! use weft_cloth::scene::{Scene, load};
//! use weft_cloth::solver::Family;
//!
//! let text = r#"
//! description = "A sheet hanging from a pole"
//! [cloth]
//! weft = 12
//! warp = 12
//! [[bodies]]
//! name = "pole"
//! [bodies.static]
//! [[attachments]]
//! body = "pole"
//! select = ["top"]
//! "#;
//! let preset = load::parse("my_sheet", text).unwrap();
//! let mut scene = Scene::new(&preset).unwrap();
//! let mut tuning = scene.tuning();
//! tuning.solver.weights[Family::Curvature] = 0.3;
//! tuning.wind.velocity = glam::Vec3::new(4.0, 0.0, 0.0);
//! scene.set_tuning(&tuning).unwrap();
//! // Out of its range: refused, with the range, and nothing changes.
//! tuning.solver.weights[Family::Curvature] = 3.0;
//! let refused = scene.set_tuning(&tuning).unwrap_err().to_string();
//! assert!(refused.contains("allowed: 0 ≤ λ ≤ 1"), "{refused}");
//! assert_eq!(scene.tuning().solver.weights[Family::Curvature], 0.3);
//! for _ in 0..30 {
//!     scene.step().unwrap();
//! }
//! assert!(scene.solver().max_strain() < 0.1);
//! assert_eq!(scene.solver().self_crossings(), 0);
//! ```
//!
//! Which solver a host runs: [`solver::version`] (and [`solver::REVISION`],
//! raised whenever a preset would step to another state).

// Unit tests compare with the platform's math library and set scenes up
// with glam's rotations; only the code they test must avoid them
// (`solver::portable`, `clippy.toml`).
#![warn(missing_docs)]
#![cfg_attr(test, allow(clippy::disallowed_methods))]

pub mod scene;
pub mod solver;
