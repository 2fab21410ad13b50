//! Checking a preset: every range and reference, in one place.
//!
//! [`Preset::validate`] returns the first problem as an [`Invalid`]: the
//! dotted key it is about and what is wrong. Range checks go through the
//! solver's [`Range`], so a preset, `--set` and the panel write the same
//! `value … is out of range; allowed: …` text from the same numbers.
//! Names echoed in messages are
//! [`clip`]ped, and "did you mean" ([`nearest`]) skips absurdly long names.

use std::{borrow::Cow, collections::HashSet};

use super::{BodySection, Preset, ShapeKind};
use crate::scene::Tuning;
use crate::solver::{Family, Range, RangeError};

/// A semantic problem, at a dotted key path.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Dotted key path, e.g. `cloth.weft` or `bodies[0].car.speed`.
    pub key: String,
    /// What is wrong, including the allowed range.
    pub message: String,
}

impl Invalid {
    fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl From<RangeError> for Invalid {
    fn from(e: RangeError) -> Self {
        let message = e.detail();
        Self {
            key: e.key,
            message,
        }
    }
}

/// Positions, in metres.
const POSITION: Range = Range::components(1e6).unit(" m");
/// XYZ Euler angles, in degrees.
const EULER: Range = Range::components(1e4).unit("°");
/// Times of keys, in seconds.
const TIME: Range = Range::new(0.0, 1e5).of("t").unit(" s");
/// Headings, in degrees.
const HEADING: Range = Range::new(-1e4, 1e4).unit("°");
/// Distances along a road, in metres.
const ROAD: Range = Range::new(-1e6, 1e6).unit(" m");

impl Preset {
    /// Checks every range and reference; returns the first problem.
    pub fn validate(&self) -> Result<(), Invalid> {
        if !(1..=super::FORMAT).contains(&self.format) {
            return Err(Invalid::new(
                "format",
                format!(
                    "preset format {} is not one this weft reads (1 to {}): {}",
                    self.format,
                    super::FORMAT,
                    if self.format > super::FORMAT {
                        "it was written by a newer weft; update weft to load it"
                    } else {
                        "formats start at 1"
                    }
                ),
            ));
        }
        Range::new(0.0, 86_400.0)
            .unit(" s")
            .check("duration", self.duration)?;
        let cloth = &self.cloth;
        POSITION.check_each("cloth.position", &cloth.position.as_vec3().to_array())?;
        EULER.check_each("cloth.rotation", &cloth.rotation)?;
        cloth.spec().validate()?;
        let env = &self.environment;
        let gravity = Range::components(1e4).unit(" m/s²");
        gravity.check_each("environment.gravity", &env.gravity.to_array())?;
        let air = Range::new(0.0, 100.0).unit(" kg/m³");
        air.check("environment.air_density", env.air_density)?;
        let drag = Range::new(0.0, 10.0);
        drag.check("environment.drag_normal", env.drag_normal)?;
        drag.check("environment.drag_tangent", env.drag_tangent)?;
        // The solver parameters and the wind: what may change while it runs.
        Tuning::of(self).validate()?;
        let mut names = HashSet::new();
        for (b, body) in self.bodies.iter().enumerate() {
            if !names.insert(body.name.as_str()) {
                return Err(Invalid::new(
                    format!("bodies[{b}].name"),
                    format!("body name `{}` is used twice", clip(&body.name)),
                ));
            }
            validate_body(&format!("bodies[{b}]"), body)?;
        }
        self.validate_links()?;
        let t = &self.telemetry;
        let every = Range::new(1.0, 1e6);
        every.check_count("telemetry.log_every", t.log_every)?;
        let threshold = Range::new(0.0, 1e3);
        threshold.check("telemetry.arrow_threshold", t.arrow_threshold)?;
        let scale = Range::new(1e-6, 1e6);
        scale.check("telemetry.arrow_scale", t.arrow_scale)?;
        if let Some(e) = &self.expect {
            let bound = |key: &str, v: Option<f32>| match v {
                Some(v) => Range::at_least(0.0).check(key, v),
                None => Ok(()),
            };
            bound("expect.max_strain", e.max_strain)?;
            bound("expect.settle_energy", e.settle_energy)?;
            if let Some(n) = e.max_crossings {
                let key = "expect.max_crossings";
                Range::new(0.0, 1e9)
                    .unit(" crossing edges")
                    .check(key, n as f32)?;
                if n.fract() != 0.0 {
                    return Err(Invalid::new(
                        key,
                        format!(
                            "{n} is not a whole number of crossing edges (allowed: 0, 1, 2, …)"
                        ),
                    ));
                }
            }
            for f in Family::ALL {
                let key = format!("expect.max_violation.{}", f.name());
                bound(&key, e.max_violation[f])?;
            }
        }
        Ok(())
    }

    fn validate_links(&self) -> Result<(), Invalid> {
        let names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        let known = |key: String, name: &str| {
            if names.contains(&name) {
                return Ok(());
            }
            let hint = nearest(name, names.iter().copied())
                .map(|n| format!("; did you mean `{}`?", clip(n)))
                .unwrap_or_default();
            let listed = names.iter().take(MAX_LISTED).map(|n| clip(n));
            let mut list = listed.collect::<Vec<_>>().join(", ");
            if names.len() > MAX_LISTED {
                list += &format!(" and {} more", names.len() - MAX_LISTED);
            }
            let name = clip(name);
            let message = format!("no body is named `{name}`; bodies: [{list}]{hint}");
            Err(Invalid::new(key, message))
        };
        for (a, att) in self.attachments.iter().enumerate() {
            known(format!("attachments[{a}].body"), &att.body)?;
            if att.select.is_empty() && att.particles.is_empty() {
                return Err(Invalid::new(
                    format!("attachments[{a}]"),
                    "an attachment needs `select` or `particles`",
                ));
            }
            let (weft, warp) = (self.cloth.weft, self.cloth.warp);
            for (k, [i, j]) in att.particles.iter().enumerate() {
                if *i >= weft || *j >= warp {
                    return Err(Invalid::new(
                        format!("attachments[{a}].particles[{k}]"),
                        format!(
                            "particle [{i}, {j}] is outside the grid; allowed: 0 ≤ i < {weft}, 0 ≤ j < {warp}"
                        ),
                    ));
                }
            }
        }
        for (c, col) in self.colliders.iter().enumerate() {
            let key = |k: &str| format!("colliders[{c}].{k}");
            if let Some(b) = &col.body {
                known(key("body"), b)?;
            }
            POSITION.check_each(key("position"), &col.position.to_array())?;
            EULER.check_each(key("rotation"), &col.rotation)?;
            Range::new(0.0, 10.0).check(key("friction"), col.friction)?;
            let need = |field: &str, v: bool| match v {
                true => Ok(()),
                false => Err(Invalid::new(
                    key(field),
                    format!("a {:?} collider needs `{field}`", col.shape).to_lowercase(),
                )),
            };
            match col.shape {
                ShapeKind::Plane => {}
                ShapeKind::Sphere => need("radius", col.radius.is_some())?,
                ShapeKind::Capsule | ShapeKind::Cylinder => {
                    need("radius", col.radius.is_some())?;
                    need("half_length", col.half_length.is_some())?;
                }
                ShapeKind::Box => need("half_extents", col.half_extents.is_some())?,
            }
            if let Some(r) = col.radius {
                Range::new(1e-4, 1e3).unit(" m").check(key("radius"), r)?;
            }
            if let Some(h) = col.half_length {
                Range::new(0.0, 1e3)
                    .unit(" m")
                    .check(key("half_length"), h)?;
            }
            if let Some(h) = col.half_extents {
                let extents = Range::components(1e3).unit(" m");
                extents.check_each(key("half_extents"), &h.to_array())?;
                if h.min_element() <= 0.0 {
                    return Err(Invalid::new(
                        key("half_extents"),
                        "half extents must be > 0",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Checks one body's motion script, under `at` (`bodies[3]`).
fn validate_body(at: &str, body: &BodySection) -> Result<(), Invalid> {
    let key = |k: &str| format!("{at}.{k}");
    if body.name.trim().is_empty() {
        return Err(Invalid::new(key("name"), "a body needs a non-empty name"));
    }
    let scripts = [
        body.fixed.is_some(),
        body.keyframes.is_some(),
        body.car.is_some(),
        body.runner.is_some(),
    ];
    if scripts.iter().filter(|s| **s).count() != 1 {
        return Err(Invalid::new(
            at,
            "a body needs exactly one motion table: [bodies.static], [bodies.keyframes], [bodies.car] or [bodies.runner]",
        ));
    }
    if let Some(m) = &body.fixed {
        POSITION.check_each(key("static.position"), &m.position.as_vec3().to_array())?;
        EULER.check_each(key("static.rotation"), &m.rotation)?;
    }
    if let Some(m) = &body.keyframes {
        if m.keys.is_empty() {
            return Err(Invalid::new(
                key("keyframes.keys"),
                "at least one key is needed",
            ));
        }
        let mut last = f32::NEG_INFINITY;
        for (k, pose) in m.keys.iter().enumerate() {
            let key = |f: &str| key(&format!("keyframes.keys[{k}].{f}"));
            TIME.check(key("t"), pose.t)?;
            if pose.t <= last {
                return Err(Invalid::new(
                    key("t"),
                    "keys must be in strictly increasing time",
                ));
            }
            last = pose.t;
            POSITION.check_each(key("position"), &pose.position.as_vec3().to_array())?;
            EULER.check_each(key("rotation"), &pose.rotation)?;
        }
    }
    if let Some(m) = &body.car {
        POSITION.check_each(key("car.start"), &m.start.as_vec3().to_array())?;
        HEADING.check(key("car.heading"), m.heading)?;
        if m.speed.is_empty() {
            return Err(Invalid::new(
                key("car.speed"),
                "at least one speed key is needed",
            ));
        }
        let speed = Range::new(-100.0, 100.0).unit(" m/s");
        keyframes_ok(key("car.speed"), &m.speed, speed)?;
        let yaw_rate = Range::new(-720.0, 720.0).unit(" °/s");
        keyframes_ok(key("car.yaw_rate"), &m.yaw_rate, yaw_rate)?;
        let wheelbase = Range::new(0.1, 20.0).unit(" m");
        wheelbase.check(key("car.wheelbase"), m.wheelbase)?;
        Range::new(0.1, 10.0)
            .unit(" m")
            .check(key("car.track"), m.track)?;
        for (k, bump) in m.road.bumps.iter().enumerate() {
            let key = |f: &str| key(&format!("car.road.bumps[{k}].{f}"));
            ROAD.check(key("at"), bump.at)?;
            let height = Range::new(-1.0, 1.0).unit(" m");
            height.check(key("height"), bump.height)?;
            let length = Range::new(0.01, 100.0).unit(" m");
            length.check(key("length"), bump.length)?;
        }
        for (k, r) in m.road.rough.iter().enumerate() {
            let key = |f: &str| key(&format!("car.road.rough[{k}].{f}"));
            ROAD.check(key("from"), r.from)?;
            Range::new(r.from, 1e6).unit(" m").check(key("to"), r.to)?;
            let amplitude = Range::new(0.0, 0.5).unit(" m");
            amplitude.check(key("amplitude"), r.amplitude)?;
            let wavelength = Range::new(0.05, 100.0).unit(" m");
            wavelength.check(key("wavelength"), r.wavelength)?;
        }
    }
    if let Some(m) = &body.runner {
        POSITION.check_each(key("runner.start"), &m.start.as_vec3().to_array())?;
        HEADING.check(key("runner.heading"), m.heading)?;
        let speed = Range::new(0.0, 15.0).unit(" m/s");
        speed.check(key("runner.speed"), m.speed)?;
        let stride = Range::new(0.0, 5.0).unit(" Hz");
        stride.check(key("runner.stride_frequency"), m.stride_frequency)?;
        Range::new(0.0, 0.5)
            .unit(" m")
            .check(key("runner.bob"), m.bob)?;
        Range::new(-45.0, 45.0)
            .unit("°")
            .check(key("runner.lean"), m.lean)?;
        let turn_time = Range::new(0.01, 10.0).unit(" s");
        turn_time.check(key("runner.turn_time"), m.turn_time)?;
        let turns = Range::new(-360.0, 360.0).unit("°");
        keyframes_ok(key("runner.turns"), &m.turns, turns)?;
    }
    Ok(())
}

/// Checks `[t, value]` keys: times in [`TIME`] and non-decreasing, values in `range`.
fn keyframes_ok(key: String, keys: &[[f32; 2]], range: Range) -> Result<(), Invalid> {
    let mut last = f32::NEG_INFINITY;
    for (k, [t, v]) in keys.iter().enumerate() {
        let at = format!("{key}[{k}]");
        TIME.check(at.as_str(), *t)?;
        range.check(at.as_str(), *v)?;
        if *t < last {
            return Err(Invalid::new(at, "keys must be in increasing time"));
        }
        last = *t;
    }
    Ok(())
}

/// How many names a message lists before `and N more`.
const MAX_LISTED: usize = 12;
/// Longest name, in characters, that a message shows whole.
const MAX_SHOWN: usize = 48;
/// Longest name, in characters, that "did you mean" compares (edit distance
/// is quadratic in length; nobody mistypes a 10,000-character name).
const MAX_COMPARED: usize = 64;

/// `name` as a message shows it: whole when short, else its start and its length.
pub fn clip(name: &str) -> Cow<'_, str> {
    if name.len() <= MAX_SHOWN {
        return Cow::Borrowed(name);
    }
    let chars = name.chars().count();
    if chars <= MAX_SHOWN {
        return Cow::Borrowed(name);
    }
    let start: String = name.chars().take(MAX_SHOWN - 16).collect();
    Cow::Owned(format!("{start}… ({chars} characters)"))
}

/// The candidate closest to `word` by edit distance, if close enough. Names
/// longer than `MAX_COMPARED` characters are not compared.
pub fn nearest<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let chars = |s: &str| {
        if s.len() > 4 * MAX_COMPARED {
            None
        } else {
            Some(s.chars().count()).filter(|n| *n <= MAX_COMPARED)
        }
    };
    let n = chars(word)?;
    candidates
        .filter_map(|c| {
            let m = chars(c)?;
            let limit = (c.len().max(word.len()) / 3).max(1) + 1;
            if m.abs_diff(n) > limit {
                return None;
            }
            let d = strsim::damerau_levenshtein(word, c);
            (d <= limit).then_some((d, c))
        })
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}
