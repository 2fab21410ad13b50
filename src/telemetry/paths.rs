//! Entity paths and timeline names, in one place.

use crate::solver::Family;

/// Sequence timeline: frame number.
pub const FRAME: &str = "frame";
/// Duration timeline: simulated seconds.
pub const SIM_TIME: &str = "sim_time";

/// Root of the 3D scene.
pub const WORLD: &str = "world";
/// Particles.
pub const PARTICLES: &str = "world/cloth/particles";
/// What the desktop debugger's camera tracks: two points about the cloth
/// that set how far back it stands (`framing.rs`).
pub const FRAMING: &str = "world/cloth/framing";
/// The cloth surface.
pub const MESH: &str = "world/cloth/mesh";
/// Where the cloth passes through itself: a point where each crossing
/// edge meets its triangle.
pub const CROSSINGS: &str = "world/cloth/crossings";
/// Another run's cloth drawn faint beside this one (in the desktop
/// debugger, a branch's parent).
pub const GHOST: &str = "world/ghost/mesh";
/// Element normals.
pub const NORMALS: &str = "world/cloth/normals";
/// The debugger's pull: a line from the pulled particle to its target.
pub const PULL: &str = "world/pull";
/// Static topology (index arrays).
pub const TOPOLOGY: &str = "cloth/topology";
/// Solver parameters, logged at every change.
pub const PARAMS: &str = "params";
/// Parameter changes and failures.
pub const EVENTS: &str = "events";
/// The resolved preset (static).
pub const PRESET: &str = "preset";
/// The weft version (static).
pub const VERSION: &str = "weft";
/// End-of-run summary (static): frames, final-state hash.
pub const SUMMARY: &str = "summary";
/// Largest edge strain.
pub const STRAIN: &str = "metrics/strain/max";
/// How many edges of the mesh cross a triangle (self-collision's second measure).
pub const SELF_CROSSINGS: &str = "metrics/violation/self/crossings";
/// The share of elements whose normal faces against the surface.
pub const NORMALS_FLIPPED: &str = "metrics/normals/flipped";
/// The RMS angle between the elements' normals and the surface's normal
/// line (either way), radians.
pub const NORMALS_OFFSET: &str = "metrics/normals/offset_rms";
/// Kinetic energy.
pub const ENERGY: &str = "metrics/energy/kinetic";
/// Update phase wall time.
pub const TIME_UPDATE: &str = "metrics/time/update";
/// Collisions wall time.
pub const TIME_COLLISIONS: &str = "metrics/time/collisions";
/// Telemetry wall time (of the previous logged frame).
pub const TIME_TELEMETRY: &str = "metrics/time/telemetry";
/// Whole step wall time.
pub const TIME_TOTAL: &str = "metrics/time/total";

/// `metrics/violation/{family}/{stat}`.
pub fn violation(f: Family, stat: &str) -> String {
    format!("metrics/violation/{}/{stat}", f.name())
}

/// `metrics/time/adjust/{family}`.
pub fn adjust_time(f: Family) -> String {
    format!("metrics/time/adjust/{}", f.name())
}

/// `world/corrections/{family}/{dx|dtheta}`.
pub fn correction(f: Family, kind: &str) -> String {
    format!("world/corrections/{}/{kind}", f.name())
}

/// `world/bodies/{name}`.
pub fn body(name: &str) -> String {
    format!("world/bodies/{name}")
}

/// `world/bodies/{name}/colliders/{k}`.
pub fn body_collider(name: &str, k: usize) -> String {
    format!("world/bodies/{name}/colliders/{k}")
}

/// `world/colliders/{k}`.
pub fn world_collider(k: usize) -> String {
    format!("world/colliders/{k}")
}
