//! Motion scripts: where each body is at time `t`.
//!
//! - static: one pose;
//! - keyframes: linear, eased or stepped (teleporting) between keys;
//! - car: speed and yaw-rate profiles integrated along a road whose bumps
//!   and rough stretches lift, pitch and roll the car through a simple
//!   suspension (a damped spring at each wheel);
//! - runner: constant speed, a stride bob, a forward lean and abrupt turns.
//!
//! Car and runner paths are integrated once, at a fixed rate, into a table
//! that grows as time advances, so any time is evaluated deterministically.
//! The world is Z-up; a body's local +X is forward, +Y left.
//!
//! Positions are in double precision ([`Placement`]), and a path is
//! integrated from its start (at zero) and placed there last: so a body's
//! motion, measured from the solver's floating origin, has the same bits
//! wherever in the world it runs ([`crate::solver::frame`]).

use glam::{DVec3, Quat};

use super::preset::{BodySection, CarMotion, Interpolation, KeyframeMotion, RunnerMotion, euler};
use crate::solver::Pose;
use crate::solver::portable::{atan2, cos, rotation_x, rotation_y, rotation_z, sin};

/// Rate at which car and runner paths are integrated, in samples per second.
const PATH_RATE: f32 = 960.0;

/// A body's pose in world coordinates, its position in double precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Position, in metres.
    pub translation: DVec3,
    /// Orientation.
    pub rotation: Quat,
}

impl Placement {
    /// The pose measured from `origin` (world coordinates), as the solver
    /// takes it.
    pub fn from(&self, origin: DVec3) -> Pose {
        Pose::new((self.translation - origin).as_vec3(), self.rotation)
    }

    /// The pose in world coordinates, in single precision (for drawing).
    pub fn world(&self) -> Pose {
        Pose::new(self.translation.as_vec3(), self.rotation)
    }
}

/// A body's motion, ready to evaluate.
#[derive(Clone, Debug)]
pub enum Motion {
    /// Never moves.
    Static(Placement),
    /// Keyframes.
    Keyframes(KeyframeMotion),
    /// A car or a runner.
    Path(Path),
}

impl Motion {
    /// The motion a body section describes (validated).
    pub fn new(body: &BodySection) -> Self {
        if let Some(m) = &body.fixed {
            Motion::Static(Placement {
                translation: m.position,
                rotation: euler(m.rotation),
            })
        } else if let Some(m) = &body.keyframes {
            Motion::Keyframes(m.clone())
        } else if let Some(m) = &body.car {
            Motion::Path(Path::new(Driver::Car(m.clone())))
        } else if let Some(m) = &body.runner {
            Motion::Path(Path::new(Driver::Runner(m.clone())))
        } else {
            Motion::Static(Placement {
                translation: DVec3::ZERO,
                rotation: Quat::IDENTITY,
            })
        }
    }

    /// The pose at time `t ≥ 0`.
    pub fn pose(&mut self, t: f64) -> Placement {
        match self {
            Motion::Static(p) => *p,
            Motion::Keyframes(k) => keyframe_pose(k, t as f32),
            Motion::Path(p) => p.pose(t),
        }
    }
}

fn key_pose(k: &super::preset::Key) -> Placement {
    Placement {
        translation: k.position,
        rotation: euler(k.rotation),
    }
}

fn keyframe_pose(m: &KeyframeMotion, t: f32) -> Placement {
    let keys = &m.keys;
    let last = keys[keys.len() - 1].t;
    let t = if m.looped && last > 0.0 { t % last } else { t };
    let Some(n) = keys.iter().position(|k| k.t > t) else {
        return key_pose(&keys[keys.len() - 1]);
    };
    if n == 0 {
        return key_pose(&keys[0]);
    }
    let (a, b) = (&keys[n - 1], &keys[n]);
    let u = (t - a.t) / (b.t - a.t);
    let u = match m.interpolation {
        Interpolation::Linear => u,
        Interpolation::Smooth => u * u * (3.0 - 2.0 * u),
        Interpolation::Step => 0.0,
    };
    let (a, b) = (key_pose(a), key_pose(b));
    Placement {
        translation: a.translation.lerp(b.translation, u as f64),
        rotation: a.rotation.slerp(b.rotation, u).normalize(),
    }
}

/// What drives a path.
#[derive(Clone, Debug)]
pub enum Driver {
    /// A car.
    Car(CarMotion),
    /// A runner.
    Runner(RunnerMotion),
}

/// One integrated sample of a path.
#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    /// From the start (each step's increment is single precision; their
    /// sum is exact in double).
    xy: [f64; 2],
    heading: f32,
    distance: f32,
    /// Car body height over the front, rear, left and right wheels.
    body: [f32; 4],
    /// Their vertical velocities.
    body_v: [f32; 4],
}

/// Suspension natural frequency (Hz) and damping ratio: the car body follows
/// the road through a damped spring at each wheel, so a bump lifts it over a
/// few tenths of a second instead of in one frame.
const SUSPENSION_HZ: f32 = 1.5;
const SUSPENSION_DAMPING: f32 = 0.4;

/// Below this offset from the road (m) and speed (m/s) a wheel's spring is
/// at rest. Left alone, its oscillation after a bump decays for ever: about
/// 20 s later the car's pitch and roll reach 1e-21 rad, their products in
/// every collider transform and attachment fall below `f32`'s normal range,
/// and subnormal arithmetic made a step of `flag_on_car` twice as slow
/// (BENCHMARKS.md, "Measured design choices"). A femtometre is far below
/// anything visible, and is reached only after the shipped 16 s, so the
/// shipped run is unchanged.
const SETTLED: f32 = 1e-15;

/// A path integrated from speed and heading.
#[derive(Clone, Debug)]
pub struct Path {
    driver: Driver,
    start: DVec3,
    samples: Vec<Sample>,
}

/// Piecewise-linear interpolation of `[t, v]` keys, held flat outside them.
fn profile(keys: &[[f32; 2]], t: f32) -> f32 {
    match keys.iter().position(|k| k[0] > t) {
        None => keys.last().map_or(0.0, |k| k[1]),
        Some(0) => keys[0][1],
        Some(n) => {
            let ([t0, v0], [t1, v1]) = (keys[n - 1], keys[n]);
            v0 + (v1 - v0) * (t - t0) / (t1 - t0)
        }
    }
}

fn smoothstep(u: f32) -> f32 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

impl Path {
    fn new(driver: Driver) -> Self {
        let (start, heading) = match &driver {
            Driver::Car(c) => (c.start, c.heading),
            Driver::Runner(r) => (r.start, r.heading),
        };
        Self {
            samples: vec![Sample {
                heading: heading.to_radians(),
                ..Sample::default()
            }],
            start,
            driver,
        }
    }

    fn speed(&self, t: f32) -> f32 {
        match &self.driver {
            Driver::Car(c) => profile(&c.speed, t),
            Driver::Runner(r) => r.speed,
        }
    }

    /// Heading rate (rad/s) for a car; the runner's heading is closed-form.
    fn heading_at(&self, t: f32, integrated: f32, dt: f32) -> f32 {
        match &self.driver {
            Driver::Car(c) => integrated + profile(&c.yaw_rate, t).to_radians() * dt,
            Driver::Runner(r) => {
                let turned: f32 = r
                    .turns
                    .iter()
                    .map(|[at, deg]| deg.to_radians() * smoothstep((t - at) / r.turn_time))
                    .sum();
                r.heading.to_radians() + turned
            }
        }
    }

    fn extend_to(&mut self, t: f64) {
        let dt = 1.0 / PATH_RATE;
        let needed = (t * PATH_RATE as f64).ceil() as usize + 2;
        while self.samples.len() < needed {
            let k = self.samples.len() - 1;
            let s = self.samples[k];
            let t0 = k as f32 * dt;
            let tm = t0 + 0.5 * dt;
            let v = self.speed(tm);
            let heading = self.heading_at(t0 + dt, s.heading, dt);
            let mid = 0.5 * (s.heading + heading);
            let distance = s.distance + v * dt;
            let (mut body, mut body_v) = (s.body, s.body_v);
            if let Driver::Car(c) = &self.driver {
                let (half, lat) = (0.5 * c.wheelbase, 0.5 * c.track);
                let road = [
                    road_height(c, distance + half, 0.0),
                    road_height(c, distance - half, 0.0),
                    road_height(c, distance, lat),
                    road_height(c, distance, -lat),
                ];
                let w = std::f32::consts::TAU * SUSPENSION_HZ;
                for k in 0..4 {
                    let acc =
                        w * w * (road[k] - body[k]) - 2.0 * SUSPENSION_DAMPING * w * body_v[k];
                    body_v[k] += acc * dt;
                    body[k] += body_v[k] * dt;
                    // Settled: at rest on the road (see `SETTLED`).
                    if (body[k] - road[k]).abs() < SETTLED && body_v[k].abs() < SETTLED {
                        (body[k], body_v[k]) = (road[k], 0.0);
                    }
                }
            }
            self.samples.push(Sample {
                xy: [
                    s.xy[0] + (v * cos(mid) * dt) as f64,
                    s.xy[1] + (v * sin(mid) * dt) as f64,
                ],
                heading,
                distance,
                body,
                body_v,
            });
        }
    }

    fn pose(&mut self, t: f64) -> Placement {
        let t = t.max(0.0);
        self.extend_to(t);
        let f = t * PATH_RATE as f64;
        let k = (f.floor() as usize).min(self.samples.len() - 2);
        let along = f - k as f64;
        let u = along as f32;
        let (a, b) = (self.samples[k], self.samples[k + 1]);
        let x = a.xy[0] + (b.xy[0] - a.xy[0]) * along;
        let y = a.xy[1] + (b.xy[1] - a.xy[1]) * along;
        let heading = a.heading + (b.heading - a.heading) * u;
        let body: [f32; 4] = std::array::from_fn(|k| a.body[k] + (b.body[k] - a.body[k]) * u);
        match &self.driver {
            Driver::Car(c) => {
                let [front, rear, left, right] = body;
                let pitch = atan2(front - rear, c.wheelbase);
                let roll = atan2(left - right, c.track);
                let rotation = rotation_z(heading) * rotation_y(-pitch) * rotation_x(roll);
                Placement {
                    translation: self.start + DVec3::new(x, y, (0.5 * (front + rear)) as f64),
                    rotation: rotation.normalize(),
                }
            }
            Driver::Runner(r) => {
                let phase = std::f32::consts::PI * r.stride_frequency * t as f32;
                let z = r.bob * sin(phase).abs();
                let sway = 0.05 * sin(phase);
                let rotation =
                    rotation_z(heading) * rotation_y(r.lean.to_radians()) * rotation_x(sway);
                Placement {
                    translation: self.start + DVec3::new(x, y, z as f64),
                    rotation: rotation.normalize(),
                }
            }
        }
    }
}

/// Road height at distance `s` along the road and `lateral` metres to the left.
pub fn road_height(car: &CarMotion, s: f32, lateral: f32) -> f32 {
    use std::f32::consts::TAU;
    let mut z = 0.0;
    for b in &car.road.bumps {
        let u = (s - b.at) / b.length;
        if (0.0..=1.0).contains(&u) {
            z += b.height * 0.5 * (1.0 - cos(TAU * u));
        }
    }
    for r in &car.road.rough {
        // Fade in and out over one wavelength so the stretch has no step.
        let fade = smoothstep((s - r.from) / r.wavelength) * smoothstep((r.to - s) / r.wavelength);
        if fade > 0.0 {
            let p = TAU * s / r.wavelength;
            let q = 1.3 * lateral;
            z += r.amplitude * fade * (0.6 * sin(p + q) + 0.4 * sin(2.71 * p + 1.1 + 2.0 * q));
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// After its bumps and rough stretch the car's springs come to rest, so
    /// the car drives on level, its pitch and roll exactly 0, and no pose
    /// component ever decays into `f32`'s subnormal range (slow arithmetic
    /// in every collider transform).
    #[test]
    fn the_car_comes_to_rest_level_after_the_rough_road() {
        let preset = crate::scene::load::load("flag_on_car", &[]).unwrap().preset;
        let mut motion = Motion::new(&preset.bodies[0]);
        for frame in 0..=60 * 60 {
            let pose = motion.pose(frame as f64 / 60.0).world();
            let parts = pose.rotation.to_array().into_iter();
            for v in parts.chain(pose.translation.to_array()) {
                assert!(!v.is_subnormal(), "frame {frame}: {pose:?}");
            }
        }
        // The last rough stretch ends at 95 m, some 10 s in.
        let level = motion.pose(60.0).rotation;
        assert_eq!((level.x, level.y), (0.0, 0.0), "{level:?}");
    }
}
