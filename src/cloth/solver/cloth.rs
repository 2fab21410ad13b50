//! The cloth model of §3.1: a woven grid of oriented surface elements.
//!
//! A cloth is `weft × warp` particles laid on a rectangle. Particle `(i, j)`
//! (column `i` along the weft, row `j` along the warp) has index `j * weft + i`.
//! Each particle is a small thin disc whose area is the cloth's area shared
//! equally, so every particle has the same mass `m = ρ_A · W · H / N` and the
//! same disc inertia. The disc radius `r` satisfies `π r² = W · H / N`; its
//! moment of inertia about an in-plane axis is `I = m r² / 4` (about the
//! normal it is `m r² / 2`, which no corrective rotation uses, because turning
//! about the normal does not move the normal).
//!
//! State is kept as structure of arrays ([`ClothState`]) so that the update
//! loop streams through memory and constraint batches touch plain slices.

use glam::{Quat, Vec3};

use super::rotation::normal_of;

use super::range::{Range, RangeError};

/// Smallest and largest grid side, in particles.
pub const MIN_RESOLUTION: u32 = 2;
/// Largest grid side, in particles.
pub const MAX_RESOLUTION: u32 = 512;

/// The default [`ClothSpec::imperfection`]: a tenth of a millimetre.
pub const DEFAULT_IMPERFECTION: f32 = 1e-4;

/// The default [`ClothSpec::friction`] of cloth on cloth.
pub const DEFAULT_FRICTION: f32 = 0.3;

/// What a cloth is made of and how it is laid out at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClothSpec {
    /// Size along the weft (local X), in metres.
    pub width: f32,
    /// Size along the warp (local Y), in metres.
    pub height: f32,
    /// Particles along the weft, in `[2, 512]`.
    pub weft: u32,
    /// Particles along the warp, in `[2, 512]`.
    pub warp: u32,
    /// Areal density `ρ_A`, in kg/m².
    pub density: f32,
    /// Thickness of the cloth, in metres; colliders keep particles half of it
    /// away, and self-collision keeps the cloth's layers all of it apart.
    pub thickness: f32,
    /// Coulomb friction coefficient `μ ≥ 0` of the cloth on itself, where
    /// self-collision presses two layers together.
    pub friction: f32,
    /// How far, at most, each particle of the rest layout sits off the flat
    /// plane along the normal, in metres: a fixed, seeded pattern (the same
    /// for every run) standing for the unevenness of real cloth. A perfectly
    /// flat grid under forces in its own plane never buckles, however soft;
    /// real cloth does. 0 gives an exactly flat cloth.
    pub imperfection: f32,
    /// Position of particle `(0, 0)` at rest, in metres.
    pub origin: Vec3,
    /// Orientation of the rest layout: the grid spans local X (weft) and local
    /// Y (warp); local +Z is the rest normal.
    pub rotation: Quat,
}

impl Default for ClothSpec {
    fn default() -> Self {
        Self {
            width: 1.0,
            height: 1.0,
            weft: 32,
            warp: 32,
            density: 0.2,
            thickness: 0.004,
            friction: DEFAULT_FRICTION,
            imperfection: DEFAULT_IMPERFECTION,
            origin: Vec3::ZERO,
            rotation: Quat::IDENTITY,
        }
    }
}

impl ClothSpec {
    /// Checks sizes, resolution and material against their ranges.
    pub fn validate(&self) -> Result<(), RangeError> {
        let size = Range::new(1e-3, 1e3).unit(" m");
        size.check("cloth.width", self.width)?;
        size.check("cloth.height", self.height)?;
        let side =
            Range::new(MIN_RESOLUTION as f32, MAX_RESOLUTION as f32).of("particles per side");
        side.check_count("cloth.weft", self.weft)?;
        side.check_count("cloth.warp", self.warp)?;
        let density = Range::new(1e-4, 1e3).unit(" kg/m²");
        density.check("cloth.density", self.density)?;
        Range::new(0.0, 0.1)
            .unit(" m")
            .check("cloth.thickness", self.thickness)?;
        Range::new(0.0, 10.0)
            .of("μ")
            .check("cloth.friction", self.friction)?;
        let imperfection = Range::new(0.0, 0.01).unit(" m");
        imperfection.check("cloth.imperfection", self.imperfection)?;
        Range::components(1e6).check_each("cloth.origin", &self.origin.to_array())?;
        Range::components(1e6).check_each("cloth.rotation", &self.rotation.to_array())?;
        Range::new(1.0 - 1e-3, 1.0 + 1e-3)
            .of("length")
            .unit(" (a unit quaternion)")
            .check("cloth.rotation", self.rotation.length())?;
        Ok(())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.weft as usize * self.warp as usize
    }

    /// Whether the cloth has no particles (never, once validated).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of particle `(i, j)`.
    pub fn index(&self, i: u32, j: u32) -> usize {
        (j * self.weft + i) as usize
    }

    /// The grid cell `(i, j)` of particle `index`: the inverse of
    /// [`ClothSpec::index`].
    pub fn cell(&self, index: usize) -> (u32, u32) {
        let index = index as u32;
        (index % self.weft, index / self.weft)
    }

    /// Rest spacing along the weft and along the warp, in metres.
    pub fn spacing(&self) -> (f32, f32) {
        (
            self.width / (self.weft - 1) as f32,
            self.height / (self.warp - 1) as f32,
        )
    }

    /// Mass of one particle, in kg.
    pub fn particle_mass(&self) -> f32 {
        self.density * self.width * self.height / self.len() as f32
    }

    /// In-plane moment of inertia of one particle's disc, in kg·m².
    pub fn particle_inertia(&self) -> f32 {
        let area = self.width * self.height / self.len() as f32;
        let r2 = area / std::f32::consts::PI;
        self.particle_mass() * r2 / 4.0
    }

    /// Rest position of particle `(i, j)` on the flat layout.
    pub fn rest_position(&self, i: u32, j: u32) -> Vec3 {
        let (dx, dy) = self.spacing();
        self.origin + self.rotation * Vec3::new(i as f32 * dx, j as f32 * dy, 0.0)
    }

    /// Where particle `(i, j)` starts: its rest position, moved off the flat
    /// plane by the seeded [`imperfection`](Self::imperfection).
    pub fn start_position(&self, i: u32, j: u32) -> Vec3 {
        let off = self.imperfection * unit_noise(self.index(i, j) as u64);
        self.rest_position(i, j) + self.rotation * Vec3::new(0.0, 0.0, off)
    }
}

/// The dynamic state of every particle, as structure of arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClothState {
    /// Position `x(t)`.
    pub position: Vec<Vec3>,
    /// Position one substep ago, `x(t − Δt)`; `x − x_prev` is the Störmer velocity.
    pub prev_position: Vec<Vec3>,
    /// Orientation; the element's normal is its local +Z.
    pub orientation: Vec<Quat>,
    /// Orientation one substep ago.
    pub prev_orientation: Vec<Quat>,
}

impl ClothState {
    /// The rest layout of `spec`, at rest.
    pub fn at_rest(spec: &ClothSpec) -> Self {
        let mut position = Vec::with_capacity(spec.len());
        for j in 0..spec.warp {
            for i in 0..spec.weft {
                position.push(spec.start_position(i, j));
            }
        }
        let orientation = vec![spec.rotation.normalize(); spec.len()];
        Self {
            prev_position: position.clone(),
            position,
            prev_orientation: orientation.clone(),
            orientation,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// The normal of particle `i` (local +Z of its orientation).
    #[inline]
    pub fn normal(&self, i: usize) -> Vec3 {
        normal_of(self.orientation[i])
    }

    /// A 64-bit FNV-1a digest of every bit of the state: equal digests mean
    /// (barring collisions) bit-identical states.
    pub fn digest(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |v: f32| {
            for b in v.to_bits().to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for v in self.position.iter().chain(&self.prev_position) {
            v.to_array().into_iter().for_each(&mut eat);
        }
        for q in self.orientation.iter().chain(&self.prev_orientation) {
            q.to_array().into_iter().for_each(&mut eat);
        }
        h
    }

    /// Copies `other` into `self` without reallocating.
    pub fn copy_from(&mut self, other: &ClothState) {
        self.position.clone_from(&other.position);
        self.prev_position.clone_from(&other.prev_position);
        self.orientation.clone_from(&other.orientation);
        self.prev_orientation.clone_from(&other.prev_orientation);
    }
}

/// A fixed pseudo-random number in `[−1, 1)` for `key` (SplitMix64).
fn unit_noise(key: u64) -> f32 {
    let mut z = key.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}
