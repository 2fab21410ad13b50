//! What a fit measures of a run: the features its distance compares and
//! the figures its targets name.
//!
//! A [`Probe`] watches a run frame by frame (it is the sweep's
//! [`Measure`]). It samples the cloth at a fixed [`Lattice`] of material
//! coordinates `(u, v)` ∈ [0, 1]² (the fitted preset's grid), so a
//! reference at another resolution is measured at the same material points,
//! by bilinear interpolation in its own grid. Positions are taken in the
//! carrier's frame (the body the cloth hangs from, [`Scene::carrier`]), so a
//! flag on a car that turns is measured as its driver sees it.
//!
//! Over the measured window (the last two thirds of the run: the first third
//! lets the cloth leave its flat start) the probe keeps, for every lattice
//! point, its mean position and its spread (RMS distance from that mean);
//! for the free edge (the lattice points farthest from any attached
//! particle) the flapping amplitude and dominant frequency; and the largest
//! edge strain, averaged over the window. At the last frame it measures the
//! drape coefficient (the Cusick test's), the mean drop and the sag.

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::scene::Scene;
use crate::sweep::Measure;

/// The share of the run before the measured window.
pub const SETTLE: f64 = 1.0 / 3.0;

/// Material points, the same for every run of a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lattice {
    /// Each point's `(u, v)`, along the weft and the warp, in [0, 1].
    pub uv: Vec<[f64; 2]>,
    /// The points of the free edge (indices into `uv`).
    pub edge: Vec<usize>,
    /// The cloth's larger side, in metres: the length distances are measured in.
    pub length: f64,
}

impl Lattice {
    /// The nodes of `scene`'s grid; the free edge is the points at least
    /// 95 % as far (in the cloth, in metres) from the nearest attached
    /// particle as the farthest point is.
    pub fn of(scene: &Scene) -> Self {
        let spec = scene.solver().spec();
        let (n, m) = (spec.weft as usize, spec.warp as usize);
        let mut uv = Vec::with_capacity(n * m);
        for j in 0..m {
            for i in 0..n {
                uv.push([
                    i as f64 / (n - 1).max(1) as f64,
                    j as f64 / (m - 1).max(1) as f64,
                ]);
            }
        }
        let (w, h) = (spec.width as f64, spec.height as f64);
        let pinned: Vec<[f64; 2]> = scene
            .solver()
            .masses()
            .iter()
            .enumerate()
            .filter(|(_, m)| **m == 0.0)
            .map(|(k, _)| [uv[k][0] * w, uv[k][1] * h])
            .collect();
        let far: Vec<f64> = uv
            .iter()
            .map(|p| {
                pinned
                    .iter()
                    .map(|q| (p[0] * w - q[0]).hypot(p[1] * h - q[1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let most = far.iter().copied().fold(0.0, f64::max);
        let edge = if most.is_finite() && most > 0.0 {
            (0..uv.len()).filter(|&k| far[k] >= 0.95 * most).collect()
        } else {
            Vec::new()
        };
        Self {
            uv,
            edge,
            length: w.max(h),
        }
    }
}

/// What a run measured, as stored in the point's file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Features {
    /// The grid measured (particles along the weft and the warp).
    pub grid: [u32; 2],
    /// Frames in the measured window.
    pub frames: u64,
    /// Whether every sampled position was finite.
    pub finite: bool,
    /// Each lattice point's mean position over the window, in the carrier's frame (m).
    pub mean: Vec<[f64; 3]>,
    /// Each lattice point's spread: RMS distance from its mean (m).
    pub spread: Vec<f64>,
    /// The free edge's flapping amplitude: its points' mean spread (m).
    pub edge_amplitude: f64,
    /// The free edge's dominant frequency (Hz; 0 if it does not move).
    pub edge_frequency: f64,
    /// The largest edge strain, averaged over the window.
    pub mean_strain: f64,
    /// The drape coefficient at the last frame: (shadow area − pinned cells'
    /// area) / (cloth area − pinned cells' area).
    pub drape_coefficient: f64,
    /// How far the free particles' mean height fell from the start (m).
    pub mean_drop: f64,
    /// How far the lowest free particle is below where it started (m).
    pub sag: f64,
    /// The short-horizon error from the reference's shared states (in the
    /// cloth's larger side), for a run on the reference's grid.
    pub horizon: Option<f64>,
}

/// The figures [`Features`] carry, by name, with what each is.
pub const MEASURED: [(&str, &str); 6] = [
    (
        "drape_coefficient",
        "the Cusick test's drape coefficient at the last frame",
    ),
    (
        "mean_drop",
        "how far the free particles' mean height fell (m)",
    ),
    (
        "sag",
        "how far the lowest free particle is below its start (m)",
    ),
    ("edge_amplitude", "the free edge's flapping amplitude (m)"),
    (
        "edge_frequency",
        "the free edge's dominant flapping frequency (Hz)",
    ),
    ("mean_strain", "the largest edge strain, averaged over time"),
];

impl Features {
    /// A measured figure by name (one of [`MEASURED`]).
    pub fn figure(&self, name: &str) -> Option<f64> {
        Some(match name {
            "drape_coefficient" => self.drape_coefficient,
            "mean_drop" => self.mean_drop,
            "sag" => self.sag,
            "edge_amplitude" => self.edge_amplitude,
            "edge_frequency" => self.edge_frequency,
            "mean_strain" => self.mean_strain,
            _ => return None,
        })
    }
}

/// Watches one run; see the module's description.
pub struct Probe {
    lattice: Lattice,
    /// Frames before the window.
    settle: u64,
    start: Vec<Vec3>,
    sum: Vec<DVec3>,
    sum_sq: Vec<f64>,
    /// The free edge's mean position at each frame of the window.
    edge: Vec<DVec3>,
    dt: f64,
    strain: f64,
    frames: u64,
    finite: bool,
    /// The reference's shared states, for a run on its grid.
    horizon: Option<std::sync::Arc<Horizon>>,
}

impl Probe {
    /// A probe for a run of `frames` frames of `scene`, sampling `lattice`.
    pub fn new(lattice: Lattice, frames: u64, scene: &Scene) -> Self {
        let n = lattice.uv.len();
        Self {
            settle: (frames as f64 * SETTLE).round() as u64,
            start: scene.world_positions().into_owned(),
            sum: vec![DVec3::ZERO; n],
            sum_sq: vec![0.0; n],
            edge: Vec::new(),
            dt: scene.solver().params().dt as f64,
            strain: 0.0,
            frames: 0,
            finite: true,
            horizon: None,
            lattice,
        }
    }

    /// Also measures the short-horizon error from the reference's shared states.
    pub fn with_horizon(mut self, horizon: Option<std::sync::Arc<Horizon>>) -> Self {
        self.horizon = horizon;
        self
    }

    /// The lattice points in the carrier's frame, at the scene's current frame.
    pub fn sample(&self, scene: &Scene) -> Vec<DVec3> {
        let spec = scene.solver().spec();
        let (n, m) = (spec.weft as usize, spec.warp as usize);
        let x = &scene.solver().state().position;
        // The solver measures from its origin, which is the carrier's
        // position when there is one: only the carrier's turn is left.
        let turn = scene
            .carrier()
            .map(|b| scene.body_placements()[b].rotation.inverse().as_dquat());
        let at = |i: usize, j: usize| x[j * n + i].as_dvec3();
        self.lattice
            .uv
            .iter()
            .map(|&[u, v]| {
                let (fu, fv) = (u * (n - 1) as f64, v * (m - 1) as f64);
                let (i, j) = (
                    (fu.floor() as usize).min(n.saturating_sub(2)),
                    (fv.floor() as usize).min(m.saturating_sub(2)),
                );
                let (a, b) = (fu - i as f64, fv - j as f64);
                let (i1, j1) = ((i + 1).min(n - 1), (j + 1).min(m - 1));
                let p = at(i, j) * (1.0 - a) * (1.0 - b)
                    + at(i1, j) * a * (1.0 - b)
                    + at(i, j1) * (1.0 - a) * b
                    + at(i1, j1) * a * b;
                match turn {
                    Some(q) => q * p,
                    None => p,
                }
            })
            .collect()
    }
}

impl Measure for Probe {
    fn frame(&mut self, scene: &Scene) {
        if scene.frame() <= self.settle {
            return;
        }
        let p = self.sample(scene);
        self.finite &= p.iter().all(|q| q.is_finite());
        for (k, q) in p.iter().enumerate() {
            self.sum[k] += *q;
            self.sum_sq[k] += q.length_squared();
        }
        if !self.lattice.edge.is_empty() {
            let e = self.lattice.edge.iter().map(|&k| p[k]).sum::<DVec3>()
                / self.lattice.edge.len() as f64;
            self.edge.push(e);
        }
        self.strain += scene.solver().max_strain() as f64;
        self.frames += 1;
    }

    fn finish(self: Box<Self>, scene: &Scene) -> serde_json::Value {
        let f = self.features(scene);
        serde_json::to_value(f).expect("features serialize")
    }
}

impl Probe {
    /// What the probe measured, the run being at its last frame.
    pub fn features(&self, scene: &Scene) -> Features {
        let count = self.frames.max(1) as f64;
        let mean: Vec<DVec3> = self.sum.iter().map(|s| *s / count).collect();
        let spread: Vec<f64> = self
            .sum_sq
            .iter()
            .zip(&mean)
            .map(|(s, m)| (s / count - m.length_squared()).max(0.0).sqrt())
            .collect();
        let edge_amplitude = if self.lattice.edge.is_empty() {
            0.0
        } else {
            self.lattice.edge.iter().map(|&k| spread[k]).sum::<f64>()
                / self.lattice.edge.len() as f64
        };
        let x = scene.world_positions();
        let masses = scene.solver().masses();
        let free: Vec<usize> = (0..x.len()).filter(|&i| masses[i] > 0.0).collect();
        let mean_drop = if free.is_empty() {
            0.0
        } else {
            free.iter()
                .map(|&i| (self.start[i].z - x[i].z) as f64)
                .sum::<f64>()
                / free.len() as f64
        };
        let sag = free
            .iter()
            .copied()
            .min_by(|&a, &b| x[a].z.total_cmp(&x[b].z))
            .map_or(0.0, |i| (self.start[i].z - x[i].z) as f64);
        let spec = scene.solver().spec();
        let features = Features {
            grid: [spec.weft, spec.warp],
            frames: self.frames,
            finite: self.finite,
            mean: mean.iter().map(|m| m.to_array()).collect(),
            spread,
            edge_amplitude,
            edge_frequency: dominant_frequency(&self.edge, self.dt),
            mean_strain: self.strain / count,
            drape_coefficient: drape_coefficient(scene),
            mean_drop,
            sag,
            horizon: self
                .horizon
                .as_ref()
                .and_then(|h| h.error(&self.lattice, &scene.tuning())),
        };
        if features.mean.iter().flatten().all(|v| v.is_finite()) {
            features
        } else {
            Features {
                finite: false,
                ..features
            }
        }
    }
}

/// Runs `preset` for `seconds` of simulated time without telemetry and
/// measures it at `lattice`, as a fit measures every run.
pub fn measure(
    preset: &crate::scene::Preset,
    lattice: &Lattice,
    seconds: f32,
) -> Result<Features, MeasureError> {
    Ok(measure_with(preset, lattice, seconds, false)?.0)
}

/// Starts of short horizons per run, and their length.
pub const HORIZONS: u64 = 4;
/// A short horizon, in seconds: shorter than the time two runs of a
/// flapping flag take to part.
pub const HORIZON_SECONDS: f32 = 0.25;

/// A reference's shared states: its scene at [`HORIZONS`] frames spread
/// over the measured window, and its lattice points (carrier's frame) a
/// short horizon later. A candidate on the same grid restarts from each
/// state with its own tuning, and its error after the horizon is measured.
#[derive(Clone, Debug)]
pub struct Horizon {
    /// The reference at each start.
    pub starts: Vec<Scene>,
    /// The reference's lattice points a horizon after each start.
    pub targets: Vec<Vec<DVec3>>,
    /// The horizon, in frames.
    pub frames: u64,
}

impl Horizon {
    /// The RMS distance (in `L`) between where `tuning` takes each shared
    /// state after the horizon and where the reference went, averaged over
    /// the starts; [`HORIZON_FAILED`] if a restart fails; none for a tuning
    /// of another frame length (its frames end at other times).
    pub fn error(&self, lattice: &Lattice, tuning: &crate::scene::Tuning) -> Option<f64> {
        let probe_of = |scene: &Scene| Probe::new(lattice.clone(), 0, scene);
        if self
            .starts
            .first()
            .is_some_and(|s| s.tuning().solver.dt != tuning.solver.dt)
        {
            return None;
        }
        let mut total = 0.0;
        for (start, target) in self.starts.iter().zip(&self.targets) {
            let mut scene = start.clone();
            if scene.tuning() != *tuning && scene.set_tuning(tuning).is_err() {
                return Some(HORIZON_FAILED);
            }
            for _ in 0..self.frames {
                if scene.step().is_err() {
                    return Some(HORIZON_FAILED);
                }
            }
            let at = probe_of(&scene).sample(&scene);
            let n = at.len().max(1) as f64;
            total += (at
                .iter()
                .zip(target)
                .map(|(p, q)| p.distance_squared(*q))
                .sum::<f64>()
                / n)
                .sqrt()
                / lattice.length;
        }
        Some(total / self.starts.len().max(1) as f64)
    }
}

/// The short-horizon error of a restart that failed (a finite number, so
/// that it is stored as one).
pub const HORIZON_FAILED: f64 = 1e3;

/// [`measure`], also keeping the run's shared states for short horizons
/// when `horizon` is set.
pub fn measure_with(
    preset: &crate::scene::Preset,
    lattice: &Lattice,
    seconds: f32,
    horizon: bool,
) -> Result<(Features, Option<Horizon>), MeasureError> {
    let mut scene = Scene::new(preset).map_err(|e| MeasureError(e.to_string()))?;
    let frames = scene.frames_in(seconds);
    let mut probe = Probe::new(lattice.clone(), frames, &scene);
    let length = scene.frames_in(HORIZON_SECONDS);
    let settle = probe.settle;
    // Starts spread over the window, each with a whole horizon after it.
    let starts: Vec<u64> = (0..HORIZONS)
        .map(|k| settle + k * frames.saturating_sub(settle + length) / HORIZONS)
        .filter(|f| f + length <= frames)
        .collect();
    let mut kept = Horizon {
        starts: Vec::new(),
        targets: Vec::new(),
        frames: length,
    };
    probe.frame(&scene);
    for _ in 0..frames {
        scene.step().map_err(|e| MeasureError(e.to_string()))?;
        probe.frame(&scene);
        if horizon {
            let f = scene.frame();
            if starts.contains(&f) {
                kept.starts.push(scene.clone());
            }
            if starts.iter().any(|s| s + length == f) {
                kept.targets.push(probe.sample(&scene));
            }
        }
    }
    let keep = horizon && !kept.starts.is_empty() && kept.starts.len() == kept.targets.len();
    Ok((probe.features(&scene), keep.then_some(kept)))
}

/// A run that could not be set up or stepped to its end.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct MeasureError(String);

/// The dominant frequency (Hz) of a trajectory sampled every `dt` seconds:
/// the centroid of the power spectrum of its motion along the direction it
/// moves most (trend removed, Hann window, 0.05 Hz steps), between two
/// cycles per window and 15 Hz (or the Nyquist frequency). A centroid,
/// unlike the highest peak, does not jump between a gust's slow swing and
/// the flapping when their peaks are close in height.
pub fn dominant_frequency(track: &[DVec3], dt: f64) -> f64 {
    let n = track.len();
    if n < 8 || dt <= 0.0 {
        return 0.0;
    }
    // The straight line from the first to the last sample's neighbourhood
    // (least squares) is the trend: a drift, not a flap.
    let t_mean = (n - 1) as f64 / 2.0;
    let mean = track.iter().sum::<DVec3>() / n as f64;
    let var_t: f64 = (0..n).map(|k| (k as f64 - t_mean).powi(2)).sum();
    let slope = track
        .iter()
        .enumerate()
        .map(|(k, p)| (*p - mean) * (k as f64 - t_mean))
        .sum::<DVec3>()
        / var_t;
    let detrended: Vec<DVec3> = track
        .iter()
        .enumerate()
        .map(|(k, p)| *p - mean - slope * (k as f64 - t_mean))
        .collect();
    // The direction of largest variance: power iteration on the covariance.
    let mut c = [[0.0f64; 3]; 3];
    for d in &detrended {
        let d = d.to_array();
        for (r, row) in c.iter_mut().enumerate() {
            for (s, v) in row.iter_mut().enumerate() {
                *v += d[r] * d[s];
            }
        }
    }
    let mut axis = DVec3::new(1.0, 0.7, 0.4).normalize();
    for _ in 0..50 {
        let a = axis.to_array();
        let next = DVec3::new(
            c[0][0] * a[0] + c[0][1] * a[1] + c[0][2] * a[2],
            c[1][0] * a[0] + c[1][1] * a[1] + c[1][2] * a[2],
            c[2][0] * a[0] + c[2][1] * a[1] + c[2][2] * a[2],
        );
        if next.length() <= 1e-300 {
            return 0.0;
        }
        axis = next.normalize();
    }
    let signal: Vec<f64> = detrended
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let hann = 0.5 - 0.5 * (std::f64::consts::TAU * k as f64 / (n - 1) as f64).cos();
            d.dot(axis) * hann
        })
        .collect();
    let span = n as f64 * dt;
    let top = (0.5 / dt).min(15.0);
    let (mut moment, mut total) = (0.0, 0.0);
    let mut step = 0;
    loop {
        let f = 2.0 / span + 0.05 * step as f64;
        if f > top {
            break;
        }
        let w = std::f64::consts::TAU * f * dt;
        let (mut re, mut im) = (0.0, 0.0);
        for (k, s) in signal.iter().enumerate() {
            re += s * (w * k as f64).cos();
            im -= s * (w * k as f64).sin();
        }
        let power = re * re + im * im;
        moment += f * power;
        total += power;
        step += 1;
    }
    if total > 0.0 { moment / total } else { 0.0 }
}

/// The drape coefficient of the cloth as it is now (a Cusick drape tester:
/// the specimen clamped between two discs, the clamped particles its
/// attached ones): the cloth's shadow on the ground beyond the disc over the
/// cloth's area beyond it, the disc being the pinned particles' cells.
pub fn drape_coefficient(scene: &Scene) -> f64 {
    let spec = scene.solver().spec();
    let (dx, dy) = spec.spacing();
    let pinned = scene
        .solver()
        .masses()
        .iter()
        .filter(|m| **m == 0.0)
        .count();
    let disc = pinned as f64 * dx as f64 * dy as f64;
    let area = spec.width as f64 * spec.height as f64;
    if area - disc <= 0.0 {
        return 0.0;
    }
    (projected_area(scene) - disc) / (area - disc)
}

/// The area (m²) of the cloth's shadow on the ground plane: its triangles
/// rasterised on a 2 mm grid around the cloth's centre.
pub fn projected_area(scene: &Scene) -> f64 {
    let x = scene.solver().state().position.as_slice();
    let (lo, hi) = x.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(l, h), p| (l.min(*p), h.max(*p)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return 0.0;
    }
    let cell = 0.002f32;
    let (nx, ny) = (
        ((hi.x - lo.x) / cell).ceil() as usize + 1,
        ((hi.y - lo.y) / cell).ceil() as usize + 1,
    );
    if nx.saturating_mul(ny) > 50_000_000 {
        return 0.0;
    }
    let mut covered = vec![false; nx * ny];
    let edge = |p: glam::Vec2, q: glam::Vec2, r: glam::Vec2| (q - p).perp_dot(r - p);
    for t in &scene.solver().topology().triangles {
        let [a, b, c] = t.map(|i| (x[i as usize] - lo).truncate());
        let area = edge(a, b, c);
        if area.abs() < 1e-12 {
            continue;
        }
        let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
        let ix = |v: f32| ((v / cell) as usize).min(nx - 1);
        let iy = |v: f32| ((v / cell) as usize).min(ny - 1);
        for y in iy(tl.y)..=iy(th.y) {
            for xx in ix(tl.x)..=ix(th.x) {
                let p = glam::Vec2::new((xx as f32 + 0.5) * cell, (y as f32 + 0.5) * cell);
                let (w0, w1, w2) = (edge(b, c, p), edge(c, a, p), edge(a, b, p));
                let inside = if area > 0.0 {
                    w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0
                } else {
                    w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0
                };
                if inside {
                    covered[y * nx + xx] = true;
                }
            }
        }
    }
    covered.iter().filter(|c| **c).count() as f64 * (cell * cell) as f64
}
