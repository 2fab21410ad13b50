//! The constraint families, and everything that is written once per family.
//!
//! A family is one kind of geometric constraint of the adjust phase, with its
//! own weight `λ`, violation measure, corrections and timing. [`Family`]
//! lists them; [`PerFamily`] holds one value per family (weights, bounds,
//! toggles, diagnostics), indexed by [`Family`] and read and written in
//! presets as a table keyed by [`Family::name`]. `Sweep::project` says which
//! constraint sets each family projects, and [`violation`] how each is
//! measured.
//!
//! Adding a family: its kernel in `constraints/<family>.rs`, a variant here
//! (with its name, weight key and default weight), its arm in
//! `Sweep::project` and [`violation`], and its colour in the telemetry.
//! Everything else (presets, validation, telemetry paths, the panel's
//! sliders and toggles, `[expect]` bounds, figures) iterates [`Family::ALL`].

use std::fmt;
use std::ops::{Index, IndexMut};

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::cloth::{ClothSpec, ClothState};
use super::constraints::self_collision::{self, SelfContact};
use super::constraints::{
    Particles, Recorder, Shared, curvature, facing, kernel, normality, planarity, project_batches,
    stretch,
};
use super::diagnostics::{Tally, Violation};
use super::forced_rotation::ForcedRotation;
use super::params::{REFERENCE_COMPLIANCE, compliance_factor};
use super::team::{self, Crew};
use super::topology::{Batched, Pair, Topology};

/// The constraint families of the adjust phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Family {
    /// Length limit on weft and warp edges, and the tethers.
    Stretch,
    /// Co-planarity of neighbours.
    Planarity,
    /// Co-normality of neighbours, and in-plane shear.
    Normality,
    /// Co-circularity of bend pairs.
    Curvature,
    /// Cloth–cloth contact: the layers stay the thickness apart.
    SelfCollision,
    /// Each element faces the way its surface does (weft's own).
    Facing,
}

impl Family {
    /// How many families there are.
    pub const COUNT: usize = 6;

    /// All families, in the order reports list them (the order the adjust
    /// phase projects them, see [`SWEEP`]).
    pub const ALL: [Family; Self::COUNT] = [
        Family::Planarity,
        Family::Normality,
        Family::Curvature,
        Family::Facing,
        Family::Stretch,
        Family::SelfCollision,
    ];

    /// A stable index, `0..COUNT`, for per-family arrays.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Lower-case name, as used in presets and entity paths.
    pub fn name(self) -> &'static str {
        match self {
            Family::Stretch => "stretch",
            Family::Planarity => "planarity",
            Family::Normality => "normality",
            Family::Curvature => "curvature",
            Family::SelfCollision => "self",
            Family::Facing => "facing",
        }
    }

    /// Whether the family's projections turn elements (planarity,
    /// normality, curvature, facing); the others only move them.
    pub fn turns(self) -> bool {
        matches!(
            self,
            Family::Planarity | Family::Normality | Family::Curvature | Family::Facing
        )
    }

    /// The default weight `λ` (see `docs/method.md`, section 13).
    pub fn default_weight(self) -> f32 {
        match self {
            Family::Stretch => 1.0,
            Family::Planarity => 0.5,
            Family::Normality => 0.2,
            Family::Curvature => 0.1,
            Family::SelfCollision => 0.0,
            Family::Facing => 0.99,
        }
    }

    /// Whether the family's violation is measured only while the family is
    /// on (its weight above 0): self-collision, whose measure is a contact
    /// search, and facing, whose measure the debugger already takes as the
    /// normals against the surface. The others are measured at any weight,
    /// so that their plots show what switching them on would correct.
    pub fn measured_only_while_on(self) -> bool {
        matches!(self, Family::SelfCollision | Family::Facing)
    }

    /// The family of a name, as in presets.
    pub fn from_name(name: &str) -> Option<Family> {
        Family::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Every family, in [`Family::index`] order: the order presets write
    /// them in and the panel lists them in.
    pub const BY_INDEX: [Family; Self::COUNT] = [
        Family::Stretch,
        Family::Planarity,
        Family::Normality,
        Family::Curvature,
        Family::SelfCollision,
        Family::Facing,
    ];

    /// Every family's name, in [`Family::index`] order (for "did you mean").
    pub const NAMES: [&'static str; Self::COUNT] = [
        "stretch",
        "planarity",
        "normality",
        "curvature",
        "self",
        "facing",
    ];
}

/// How many times one adjust sweep projects the length limit.
///
/// Stretch is the firm limit and the cheapest family (no angles, no turns),
/// and the only rigid one at the default weights: a rigid constraint needs
/// more Gauss–Seidel passes than a soft one, which XPBD settles in about one.
/// Three passes per sweep bought a flag on a braking car from 0.20 to 0.085
/// peak strain at 8 substeps × 2 iterations, for 7 % more time per sweep.
pub const STRETCH_PASSES: usize = 3;

/// The order of one adjust sweep: the surface families, facing last among
/// them (so that the normals end each sweep on the surface the others left),
/// then the length limit [`STRETCH_PASSES`] times, then self-collision, so
/// that the layers are apart when the colliders take over. (Running the
/// stretch passes' colours in alternating orders, symmetric Gauss–Seidel,
/// was measured and raised peak strain on every preset.)
pub const SWEEP: [Family; 5 + STRETCH_PASSES] = {
    let mut sweep = [Family::Stretch; 5 + STRETCH_PASSES];
    sweep[0] = Family::Planarity;
    sweep[1] = Family::Normality;
    sweep[2] = Family::Curvature;
    sweep[3] = Family::Facing;
    sweep[4 + STRETCH_PASSES] = Family::SelfCollision;
    sweep
};

/// One value per family, indexed by [`Family`].
///
/// In presets it is a table keyed by [`Family::name`]; a missing key keeps
/// its default, an unknown key is an error naming the families. `None`
/// entries are left out when written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PerFamily<T>([T; Family::COUNT]);

impl<T> PerFamily<T> {
    /// A value for each family from `f`.
    pub fn from_fn(f: impl FnMut(Family) -> T) -> Self {
        Self(Family::BY_INDEX.map(f))
    }

    /// The same value for every family.
    pub fn splat(value: T) -> Self
    where
        T: Clone,
    {
        Self::from_fn(|_| value.clone())
    }

    /// Every family with its value, in [`Family::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Family, &T)> {
        Family::ALL.into_iter().map(|f| (f, &self[f]))
    }

    /// Every family with its value, mutably, in [`Family::index`] order.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.0.iter_mut()
    }

    /// A value for each family from this one's.
    pub fn map<U>(&self, mut f: impl FnMut(Family, &T) -> U) -> PerFamily<U> {
        PerFamily::from_fn(|fam| f(fam, &self[fam]))
    }

    /// This, with `family`'s value replaced.
    pub fn with(mut self, family: Family, value: T) -> Self {
        self[family] = value;
        self
    }

    /// Reads a preset table over `base`: the keys given replace their
    /// family's value, the others keep `base`'s.
    pub fn deserialize_over<'de, D>(base: Self, d: D) -> Result<Self, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        struct Over<T>(PerFamily<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for Over<T> {
            type Value = PerFamily<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a table with keys among {}", Family::NAMES.join(", "))
            }
            fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<Self::Value, A::Error> {
                while let Some(Key(family)) = map.next_key()? {
                    self.0[family] = map.next_value()?;
                }
                Ok(self.0)
            }
        }
        d.deserialize_map(Over(base))
    }
}

/// A family's name as a table key: an unknown one is refused while the key
/// is read (as a struct's unknown field is), so the error's path ends in it.
struct Key(Family);

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Name;
        impl Visitor<'_> for Name {
            type Value = Key;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "one of {}", Family::NAMES.join(", "))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Key, E> {
                Family::from_name(v)
                    .map(Key)
                    .ok_or_else(|| E::unknown_field(v, &Family::NAMES))
            }
        }
        d.deserialize_identifier(Name)
    }
}

impl PerFamily<f32> {
    /// Every family's default weight ([`Family::default_weight`]).
    pub fn default_weights() -> Self {
        Self::from_fn(Family::default_weight)
    }
}

impl<T: Default> Default for PerFamily<T> {
    fn default() -> Self {
        Self::from_fn(|_| T::default())
    }
}

impl<T> IntoIterator for PerFamily<T> {
    type Item = T;
    type IntoIter = std::array::IntoIter<T, { Family::COUNT }>;

    /// The values in [`Family::index`] order (as [`PerFamily::iter_mut`]).
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<T> Index<Family> for PerFamily<T> {
    type Output = T;
    fn index(&self, f: Family) -> &T {
        &self.0[f.index()]
    }
}

impl<T> IndexMut<Family> for PerFamily<T> {
    fn index_mut(&mut self, f: Family) -> &mut T {
        &mut self.0[f.index()]
    }
}

/// A value a [`PerFamily`] table can hold in a preset; `present` is false
/// for values left out when written (`None`).
pub trait Entry: Serialize {
    /// Whether the value is written.
    fn present(&self) -> bool {
        true
    }
}

impl Entry for f32 {}
impl Entry for bool {}
impl<T: Serialize> Entry for Option<T> {
    fn present(&self) -> bool {
        self.is_some()
    }
}

impl<T: Entry> Serialize for PerFamily<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        // In index order, as the families were once written by hand.
        for (name, v) in Family::NAMES.iter().zip(&self.0) {
            if v.present() {
                map.serialize_entry(name, v)?;
            }
        }
        map.end()
    }
}

impl<'de, T: Deserialize<'de> + Default> Deserialize<'de> for PerFamily<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Self::deserialize_over(Self::default(), d)
    }
}

/// Each family's compliance for one substep, `α̃ = α_ref · ((1 − λ)/λ)² / Δt²`
/// (for a square cell; each constraint divides by its aspect).
pub(crate) struct Compliance {
    stretch: f32,
    shear: f32,
    planarity: f32,
    normality: f32,
    curvature: f32,
    facing: f32,
    self_contact: f32,
}

impl Compliance {
    pub(crate) fn new(w: &PerFamily<f32>, dt: f32) -> Self {
        let r = &REFERENCE_COMPLIANCE;
        let of = |reference: f32, f: Family| reference * compliance_factor(w[f]) / (dt * dt);
        Self {
            stretch: of(r.stretch, Family::Stretch),
            shear: of(r.shear, Family::Normality),
            planarity: of(r.planarity, Family::Planarity),
            normality: of(r.normality, Family::Normality),
            curvature: of(r.curvature, Family::Curvature),
            facing: of(r.facing, Family::Facing),
            self_contact: of(r.self_contact, Family::SelfCollision),
        }
    }
}

/// The multipliers `μ` of every constraint over the current substep, in the
/// same order as the constraints.
#[derive(Clone, Debug, Default)]
pub(crate) struct Multipliers {
    structural: Vec<f32>,
    tethers: Vec<f32>,
    shear: Vec<f32>,
    normality: Vec<f32>,
    planarity: Vec<[f32; 2]>,
    curvature: Vec<[f32; 2]>,
    facing: Vec<f32>,
    pub(crate) self_contact: Vec<f32>,
}

impl Multipliers {
    /// All zero, sized for `topology`, `tethers` tethers and `contacts`
    /// self-contacts: each substep starts from no accumulated correction.
    pub(crate) fn reset(&mut self, topology: &Topology, tethers: usize, contacts: usize) {
        let zero = |v: &mut Vec<f32>, n: usize| {
            v.clear();
            v.resize(n, 0.0);
        };
        let zero2 = |v: &mut Vec<[f32; 2]>, n: usize| {
            v.clear();
            v.resize(n, [0.0; 2]);
        };
        zero(&mut self.structural, topology.structural.len());
        zero(&mut self.tethers, tethers);
        zero(&mut self.shear, topology.shear.len());
        zero(&mut self.normality, topology.structural.len());
        zero2(&mut self.planarity, topology.structural.len());
        zero2(&mut self.curvature, topology.bend.len());
        zero(&mut self.facing, topology.patches.len());
        zero(&mut self.self_contact, contacts);
    }

    /// The multipliers as the threads of the adjust phase share them.
    pub(crate) fn shared(&mut self) -> SharedMultipliers<'_> {
        SharedMultipliers {
            structural: Shared::new(&mut self.structural),
            tethers: Shared::new(&mut self.tethers),
            shear: Shared::new(&mut self.shear),
            normality: Shared::new(&mut self.normality),
            planarity: Shared::new(&mut self.planarity),
            curvature: Shared::new(&mut self.curvature),
            facing: Shared::new(&mut self.facing),
            self_contact: Shared::new(&mut self.self_contact),
        }
    }
}

/// [`Multipliers`], written by the threads of the adjust phase, each
/// constraint's by the thread that projects it.
pub(crate) struct SharedMultipliers<'a> {
    structural: Shared<'a, f32>,
    tethers: Shared<'a, f32>,
    shear: Shared<'a, f32>,
    normality: Shared<'a, f32>,
    planarity: Shared<'a, [f32; 2]>,
    curvature: Shared<'a, [f32; 2]>,
    facing: Shared<'a, f32>,
    self_contact: Shared<'a, f32>,
}

/// What every family's projection in one sweep reads: the constraints, the
/// state, the compliances and Eq. 3.
pub(crate) struct Sweep<'a> {
    pub topology: &'a Topology,
    pub tethers: &'a stretch::Tethers,
    /// This substep's self-contacts, and the distance they keep.
    pub contacts: &'a Batched<SelfContact>,
    pub thickness: f32,
    pub p: &'a Particles<'a>,
    pub k: &'a Compliance,
    pub rot: &'a ForcedRotation,
}

impl Sweep<'_> {
    /// Projects every constraint of one family once, colour batch by colour
    /// batch, each with its multiplier in `mu`; `crew` shares the batches.
    pub(crate) fn project<R: Recorder>(
        &self,
        crew: &Crew,
        family: Family,
        mu: &SharedMultipliers,
        rec: &mut R,
    ) {
        let Self {
            topology,
            tethers,
            contacts,
            thickness,
            p,
            k,
            rot,
        } = *self;
        let (structural, shear, bend) = (&topology.structural, &topology.shear, &topology.bend);
        match family {
            Family::Stretch => {
                project_batches(
                    crew,
                    &structural.items,
                    &mu.structural,
                    &structural.batches,
                    rec,
                    kernel!(|c, m, n, _| stretch::project::<F>(p, c, m, n, k.stretch)),
                );
                // Each particle appears once per tether batch.
                project_batches(
                    crew,
                    &tethers.items,
                    &mu.tethers,
                    &tethers.batches,
                    rec,
                    kernel!(|t, m, n, _| stretch::project_tethers::<F>(p, t, m, n, k.stretch)),
                );
            }
            Family::Planarity => {
                project_batches(
                    crew,
                    &structural.items,
                    &mu.planarity,
                    &structural.batches,
                    rec,
                    kernel!(|c, m, n, r| planarity::project::<F, _>(
                        p,
                        c,
                        m,
                        n,
                        k.planarity,
                        rot,
                        r
                    )),
                );
            }
            Family::Normality => {
                project_batches(
                    crew,
                    &structural.items,
                    &mu.normality,
                    &structural.batches,
                    rec,
                    kernel!(|c, m, n, r| normality::project::<F, _>(
                        p,
                        c,
                        m,
                        n,
                        k.normality,
                        rot,
                        r
                    )),
                );
                project_batches(
                    crew,
                    &shear.items,
                    &mu.shear,
                    &shear.batches,
                    rec,
                    kernel!(|c, m, n, _| stretch::project::<F>(p, c, m, n, k.shear)),
                );
            }
            Family::Curvature => {
                project_batches(
                    crew,
                    &bend.items,
                    &mu.curvature,
                    &bend.batches,
                    rec,
                    kernel!(|c, m, n, r| curvature::project::<F, _>(
                        p,
                        c,
                        m,
                        n,
                        k.curvature,
                        rot,
                        r
                    )),
                );
            }
            Family::Facing => {
                let patches = &topology.patches;
                project_batches(
                    crew,
                    &patches.items,
                    &mu.facing,
                    &patches.batches,
                    rec,
                    kernel!(|c, m, n, r| facing::project::<F, _>(p, c, m, n, k.facing, rot, r)),
                );
            }
            Family::SelfCollision => {
                project_batches(
                    crew,
                    &contacts.items,
                    &mu.self_contact,
                    &contacts.batches,
                    rec,
                    kernel!(|cs, ms, n, _| {
                        for (&c, m) in cs.iter().zip(ms).take(n) {
                            self_collision::project(p, c, m, thickness, k.self_contact);
                        }
                    }),
                );
            }
        }
    }
}

fn stats<T: Copy>(sets: &[&Batched<T>], f: impl Fn(T) -> f32) -> Violation {
    Violation::of(sets.iter().flat_map(|s| s.items.iter()).map(|&p| f(p)))
}

/// The violation of one family over the constraints it projects (for
/// self-collision: the penetration of the pairs closer than the thickness).
pub fn violation(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
) -> Violation {
    let x = &state.position;
    let normal = |i| state.normal(i);
    match family {
        Family::Stretch => stats(&[&topology.structural], |p| stretch::violation(x, p)),
        Family::Planarity => stats(&[&topology.structural], |p| {
            planarity::violation(x, normal, p)
        }),
        Family::Normality => stats(&[&topology.structural], |p| normality::violation(normal, p)),
        Family::Curvature => stats(&[&topology.bend], |p| curvature::violation(x, p)),
        Family::Facing => stats(&[&topology.patches], |p| facing::violation(x, normal, p)),
        Family::SelfCollision => {
            let mut depths = Vec::new();
            self_collision::for_each_close(x, topology, spec, |_, _, d| depths.push(d));
            Violation::of(depths.into_iter())
        }
    }
}

/// Every family's violation, as [`violation`] measures each, on up to
/// `threads` threads, for the families `measured` names (0 for the others);
/// facing's is tallied from `offsets`, each element's angle to its surface
/// ([`normal_offsets`](super::diagnostics::normal_offsets), its measure),
/// and is 0 without them. The structural pairs are measured once for the
/// three families that share them, and every set in blocks whose tallies
/// merge in block order, so the figures do not depend on the threads.
pub fn violations(
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
    threads: usize,
    measured: impl Fn(Family) -> bool,
    offsets: Option<&[f32]>,
) -> PerFamily<Violation> {
    let x = &state.position;
    let normal = |i| state.normal(i);
    let of_pairs = tallies(threads, &topology.structural.items, |p| {
        [
            stretch::violation(x, p),
            planarity::violation(x, normal, p),
            normality::violation(normal, p),
        ]
    });
    let [of_bends] = tallies(threads, &topology.bend.items, |b| {
        [curvature::violation(x, b)]
    });
    // Already measured: tallied on this thread.
    let of_patches = offsets.map(|o| tallies(1, o, |a| [a])[0]);
    PerFamily::from_fn(|family| match family {
        _ if !measured(family) => Violation::default(),
        Family::Stretch => of_pairs[0].violation(),
        Family::Planarity => of_pairs[1].violation(),
        Family::Normality => of_pairs[2].violation(),
        Family::Curvature => of_bends.violation(),
        Family::Facing => of_patches.unwrap_or_default().violation(),
        Family::SelfCollision => violation(family, state, topology, spec),
    })
}

/// `N` violations of each item, each tallied in blocks on up to `threads`
/// threads and merged in block order.
fn tallies<T: Copy + Sync, const N: usize>(
    threads: usize,
    items: &[T],
    f: impl Fn(T) -> [f32; N] + Sync,
) -> [Tally; N] {
    const BLOCK: usize = 1024;
    let mut all = [Tally::default(); N];
    for block in team::run_blocks(threads, items.len(), BLOCK, |r| {
        let mut t = [Tally::default(); N];
        for &item in &items[r] {
            for (t, v) in t.iter_mut().zip(f(item)) {
                t.add(v);
            }
        }
        t
    }) {
        for (all, t) in all.iter_mut().zip(block) {
            all.merge(t);
        }
    }
    all
}

/// Per particle, the largest violation of `family` over the constraints
/// that involve it (pairs: both ends; bend triples: all three), as in
/// [`violation`]. For colouring or labelling every particle.
pub fn particle_violation(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
) -> Vec<f32> {
    let mut out = vec![0.0f32; state.len()];
    each_violation(family, state, topology, spec, None, &mut |i, v| {
        let slot = &mut out[i as usize];
        *slot = slot.max(v);
    });
    out
}

/// Particle `i`'s entry of [`particle_violation`], the same bit for bit,
/// from the constraints that involve `i` alone (for inspecting one
/// particle: the others are not measured).
pub fn particle_violation_at(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
    i: usize,
) -> f32 {
    let mut largest = 0.0f32;
    each_violation(
        family,
        state,
        topology,
        spec,
        Some(i as u32),
        &mut |j, v| {
            if j as usize == i {
                largest = largest.max(v);
            }
        },
    );
    largest
}

/// Calls `put(i, v)` for every particle `i` of every constraint of `family`
/// with the constraint's violation `v`; given `only`, measures only the
/// constraints that involve that particle (self-collision's contact search
/// still runs over the whole cloth).
fn each_violation(
    family: Family,
    state: &ClothState,
    topology: &Topology,
    spec: &ClothSpec,
    only: Option<u32>,
    put: &mut dyn FnMut(u32, f32),
) {
    let x = &state.position;
    let normal = |i| state.normal(i);
    let wanted = |members: &[u32]| only.is_none_or(|i| members.contains(&i));
    let mut pairs = |set: &Batched<Pair>, f: &dyn Fn(Pair) -> f32| {
        for &p in set.items.iter().filter(|p| wanted(&[p.a, p.b])) {
            let v = f(p);
            put(p.a, v);
            put(p.b, v);
        }
    };
    match family {
        Family::Stretch => pairs(&topology.structural, &|p| stretch::violation(x, p)),
        Family::Planarity => pairs(&topology.structural, &|p| {
            planarity::violation(x, normal, p)
        }),
        Family::Normality => pairs(&topology.structural, &|p| normality::violation(normal, p)),
        Family::Facing => {
            for &p in topology.patches.items.iter().filter(|p| wanted(&[p.at])) {
                put(p.at, facing::violation(x, normal, p));
            }
        }
        Family::Curvature => {
            for &t in topology
                .bend
                .items
                .iter()
                .filter(|t| wanted(&[t.a, t.mid, t.b]))
            {
                let v = curvature::violation(x, t);
                put(t.a, v);
                put(t.mid, v);
                put(t.b, v);
            }
        }
        Family::SelfCollision => {
            self_collision::for_each_close(x, topology, spec, |p, tri, d| {
                for i in [p, tri[0], tri[1], tri[2]] {
                    put(i, d);
                }
            });
        }
    }
}
