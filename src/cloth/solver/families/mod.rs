//! The constraint families of the adjust phase (§3.3), one file each.
//!
//! A family is one kind of geometric constraint with its own weight `λ`,
//! violation measure, corrections, colour and timing. Each implements
//! `ConstraintFamily` in its own file here, beside its kernel; the list
//! at the bottom of this file names them once, in the order a sweep
//! projects them, and everything else (the solver's sweep,
//! presets and their validation, telemetry paths and plots, the panel's
//! sliders and toggles, `[expect]` bounds, figures) walks [`Family::ALL`]
//! in that order and stores per-family values in a [`PerFamily`].
//!
//! Every family is a scalar violation `C` of two or three particles whose
//! gradient reproduces the vectors printed in the paper:
//!
//! | family | violation `C` | gradient in position | gradient in rotation |
//! |---|---|---|---|
//! | stretch | `|s| − L` (and tethers, one-sided) | `∓ ŝ` | — |
//! | planarity | `α = asin(n_a · ŝ)`, zero iff `n_a · s = 0` | `∓ n⊥ / |s|` | unit `n_a × ŝ` (the paper's `v`) |
//! | normality | `∠(n_a, n_b)`; shear: diagonal `|s| − L` | —; `∓ ŝ` | `n_a × n_b`; — |
//! | curvature | sagitta angle `2 n̂⊥ · (x_m − ½(x_a + x_b)) / L`; bend angle | `n̂⊥`, `−½ n̂⊥` | `(n_a + n_b) × s` |
//! | facing | `∠(n, g)`, `g` the normal of the particle's patch ([`facing`]) | — (the surface leads) | `−(n × g) / |n × g|` |
//! | self | `s (x_p − y) · n̄ − h ≥ 0`, one-sided: a particle against a triangle's foot `y` ([`self_collision`]) | `s n̄`, `−β_k s n̄` | — |
//!
//! with `s = x_b − x_a`, `n⊥` the normal made perpendicular to the edge and
//! `n̂⊥` the normalised `n_a + n_b` made perpendicular to the chord.
//!
//! **Projection (§3.4, in compliance form).** A correction changes positions
//! and orientations as little as possible in the metric of mass and inertia.
//! With inverse masses `w`, inverse inertias `β` and gradients `g`, each
//! constraint keeps a multiplier `μ` over the substep (XPBD, Macklin et al.
//! 2016) and every sweep applies
//!
//! ```text
//! Δμ = (−C − α̃ μ) / (Σ w|g_x|² + Σ β|g_θ|² + α̃),   α̃ = α / Δt²
//! ```
//!
//! moving each particle by `w g_x Δμ` and turning it by `β g_θ Δμ`. The
//! compliance `α` comes from the family's weight `λ` (see
//! [`Weights`](super::Weights)): `λ = 1` is rigid (`α = 0`, plain projection),
//! smaller weights are softer. Because `α` is a physical compliance, the
//! stiffness a weight gives does not change with iterations or substeps.
//! Every turn is shaped by Eq. 3 ([`ForcedRotation::scale`]); when Eq. 3 cuts
//! a turn, the constraint's `Δμ`, and with it its translations, is cut by
//! the same fraction.
//!
//! **Adding a family**: a file here with a type implementing
//! `ConstraintFamily` (its kernel beside it), one line in the list, and
//! its tests. See ARCHITECTURE.md ("How to add a constraint family").

mod measure;
mod per_family;
mod violation;

use std::fmt;

#[cfg(doc)]
use super::forced_rotation::ForcedRotation;
use super::forced_rotation::ForcedRotation as Eq3;
use super::kernels::{Particles, Recorder, Shared};
use super::self_collision::SelfContact;
use super::team::Crew;
use super::topology::{Batched, Topology};

pub(crate) use measure::{Measure, each_pair, each_triple};
pub use measure::{particle_violation, particle_violation_at, violation, violations};
pub use per_family::{Entry, PerFamily};
pub use violation::Violation;

/// How a weight scales its family's reference compliance: `((1 − λ) / λ)²`
/// (0 at `λ = 1`, 1 at `λ = ½`, unbounded as `λ → 0`).
#[inline]
pub fn compliance_factor(weight: f32) -> f32 {
    if weight >= 1.0 {
        return 0.0;
    }
    let r = (1.0 - weight) / weight.max(1e-6);
    r * r
}

/// One family of constraints of the adjust phase: what it is called and
/// drawn as, how stiff it is by default, the multipliers it keeps, how it
/// projects its constraints and how its violation is measured.
///
/// Families are types, not values: the solver calls them through
/// [`Family`], whose variants the list at the bottom of this file makes,
/// one per implementation, so every call is static (the kernels inline).
pub(crate) trait ConstraintFamily {
    /// Lower-case name, as used in presets, entity paths and the panel.
    const NAME: &'static str;
    /// Colour in plots, arrows and the panel (sRGB).
    const COLOR: [u8; 3];
    /// The default weight `λ` (see `docs/method.md`, section 13).
    const DEFAULT_WEIGHT: f32;
    /// Whether its projections turn elements; the others only move them.
    const TURNS: bool;
    /// The compliance `α_ref` of its constraints at `λ = ½`, for a square
    /// cell (a cell of aspect `w / L`, extent across the constraint over its
    /// length, divides it by `w / L`, so that the same physical cloth
    /// behaves the same at any resolution; see `docs/method.md`).
    const REFERENCE_COMPLIANCE: f32;
    /// Whether its violation is measured only while it is on (its weight
    /// above 0), for a family whose measure costs a search; the others are
    /// measured at any weight, so that their plots show what switching them
    /// on would correct.
    const MEASURED_ONLY_WHILE_ON: bool = false;
    /// How many times one sweep projects it.
    const PASSES: usize = 1;

    /// Its constraints' multipliers `μ` over a substep.
    type Multipliers: Clone + std::fmt::Debug + Default + Send;
    /// [`Self::Multipliers`] as the threads of the adjust phase share them.
    type Shared<'a>: Sync
    where
        Self: 'a;

    /// Sizes `mu` for the constraints of `sets`, all zero: each substep
    /// starts from no accumulated correction.
    fn reset(mu: &mut Self::Multipliers, sets: &Sets);

    /// The multipliers, for the threads of the adjust phase.
    fn share(mu: &mut Self::Multipliers) -> Self::Shared<'_>;

    /// Projects every constraint once, colour batch by colour batch, each
    /// with its multiplier in `mu`, at weight `weight`; `crew` shares the
    /// batches ([`project_batches`](super::kernels::project_batches)).
    fn project<R: Recorder>(
        sweep: &Sweep,
        crew: &Crew,
        weight: f32,
        mu: &Self::Shared<'_>,
        rec: &mut R,
    );

    /// Its violation over all its constraints, tallied on up to
    /// `m.threads` threads in blocks merged in order.
    fn violation(m: &Measure) -> Violation;

    /// Calls `put(i, v)` for every particle `i` of every constraint with
    /// the constraint's violation `v`; given `only`, for the constraints
    /// that involve that particle alone.
    fn each_violation(m: &Measure, only: Option<u32>, put: &mut dyn FnMut(u32, f32));
}

/// The constraint sets the families project: the grid's ([`Topology`]),
/// the tethers and this substep's self-contacts.
#[derive(Clone, Copy)]
pub(crate) struct Sets<'a> {
    pub topology: &'a Topology,
    pub tethers: &'a stretch::Tethers,
    pub contacts: &'a Batched<SelfContact>,
}

/// What every family's projection in one sweep reads: the constraints, the
/// state, the substep and Eq. 3.
pub(crate) struct Sweep<'a> {
    pub sets: Sets<'a>,
    /// The distance self-contacts keep.
    pub thickness: f32,
    pub p: &'a Particles<'a>,
    /// The substep `Δt`, s.
    pub dt: f32,
    pub rot: &'a Eq3,
    pub weights: &'a PerFamily<f32>,
}

impl Sweep<'_> {
    /// The compliance of a constraint kind for this substep,
    /// `α̃ = α_ref · ((1 − λ)/λ)² / Δt²` (for a square cell; each
    /// constraint divides by its aspect), from its reference compliance
    /// `α_ref` (at `λ = ½`) and the family's weight.
    pub fn compliance(&self, reference: f32, weight: f32) -> f32 {
        reference * compliance_factor(weight) / (self.dt * self.dt)
    }
}

/// Fills a multiplier set with `n` zeros.
pub(crate) fn zero<T: Default + Clone>(v: &mut Vec<T>, n: usize) {
    v.clear();
    v.resize(n, T::default());
}

impl<'a> SharedMultipliers<'a> {
    /// The self-contacts' multipliers, for friction between layers.
    pub(crate) fn self_contacts(&self) -> &Shared<'a, f32> {
        &self.self_collision
    }
}

/// Makes [`Family`] and the per-family dispatch from the list of families.
macro_rules! families {
    ($($(#[$doc:meta])* $module:ident :: $name:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// The constraint families of the adjust phase, in the order one
        /// sweep projects them and every list shows them.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Family {
            $($(#[$doc])* $name,)*
        }

        impl Family {
            /// How many families there are.
            pub const COUNT: usize = [$(Family::$name),*].len();

            /// Every family, in sweep order.
            pub const ALL: [Family; Self::COUNT] = [$(Family::$name),*];

            /// Every family's name, in [`Family::ALL`] order.
            pub const NAMES: [&'static str; Self::COUNT] =
                [$(<$module::$name as ConstraintFamily>::NAME),*];

            /// Lower-case name, as used in presets and entity paths.
            pub fn name(self) -> &'static str {
                Self::NAMES[self.index()]
            }

            /// Colour in plots, arrows and the panel (sRGB).
            pub fn color(self) -> [u8; 3] {
                match self { $(Family::$name => <$module::$name as ConstraintFamily>::COLOR,)* }
            }

            /// The default weight `λ` (see `docs/method.md`, section 13).
            pub fn default_weight(self) -> f32 {
                match self { $(Family::$name => <$module::$name as ConstraintFamily>::DEFAULT_WEIGHT,)* }
            }

            /// Whether the family's projections turn elements.
            pub fn turns(self) -> bool {
                match self { $(Family::$name => <$module::$name as ConstraintFamily>::TURNS,)* }
            }

            /// Whether its violation is measured only while it is on
            /// (`ConstraintFamily::MEASURED_ONLY_WHILE_ON`).
            pub fn measured_only_while_on(self) -> bool {
                match self {
                    $(Family::$name => <$module::$name as ConstraintFamily>::MEASURED_ONLY_WHILE_ON,)*
                }
            }

            /// How many times one sweep projects it.
            pub fn passes(self) -> usize {
                match self { $(Family::$name => <$module::$name as ConstraintFamily>::PASSES,)* }
            }

            /// Its violation ([`ConstraintFamily::violation`]).
            pub(crate) fn violation_in(self, m: &Measure) -> Violation {
                match self { $(Family::$name => $module::$name::violation(m),)* }
            }

            /// Its violation per constraint and particle
            /// ([`ConstraintFamily::each_violation`]).
            pub(crate) fn each_violation(
                self,
                m: &Measure,
                only: Option<u32>,
                put: &mut dyn FnMut(u32, f32),
            ) {
                match self { $(Family::$name => $module::$name::each_violation(m, only, put),)* }
            }
        }

        /// The multipliers `μ` of every family's constraints over the
        /// current substep.
        #[derive(Clone, Debug, Default)]
        pub(crate) struct Multipliers {
            $(pub(crate) $module: <$module::$name as ConstraintFamily>::Multipliers,)*
        }

        /// [`Multipliers`], written by the threads of the adjust phase, each
        /// constraint's by the thread that projects it.
        pub(crate) struct SharedMultipliers<'a> {
            $($module: <$module::$name as ConstraintFamily>::Shared<'a>,)*
        }

        impl Multipliers {
            /// All zero, sized for `sets`.
            pub(crate) fn reset(&mut self, sets: &Sets) {
                $($module::$name::reset(&mut self.$module, sets);)*
            }

            /// The multipliers as the threads of the adjust phase share them.
            pub(crate) fn shared(&mut self) -> SharedMultipliers<'_> {
                SharedMultipliers { $($module: $module::$name::share(&mut self.$module),)* }
            }
        }

        impl Sweep<'_> {
            /// Projects every constraint of `family` once
            /// ([`ConstraintFamily::project`]).
            pub(crate) fn project<R: Recorder>(
                &self,
                crew: &Crew,
                family: Family,
                mu: &SharedMultipliers,
                rec: &mut R,
            ) {
                let weight = self.weights[family];
                match family {
                    $(Family::$name => $module::$name::project(self, crew, weight, &mu.$module, rec),)*
                }
            }
        }
    };
}

impl Family {
    /// A stable index, `0..COUNT`, for per-family arrays: the position in
    /// [`Family::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The family of a name, as in presets.
    pub fn from_name(name: &str) -> Option<Family> {
        Family::ALL.into_iter().find(|f| f.name() == name)
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.name())
    }
}

// The list: every family, once, in the order one sweep projects them. The
// surface families come first, facing last among them (so that the normals
// end each sweep on the surface the others left), then the length limit,
// then self-collision, so that the layers are apart when the colliders
// take over.
families! {
    /// Co-planarity of neighbours.
    planarity::Planarity,
    /// Co-normality of neighbours, and in-plane shear.
    normality::Normality,
    /// Co-circularity of bend pairs.
    curvature::Curvature,
    /// Each element faces the way its surface does (weft's own).
    facing::Facing,
    /// Length limit on weft and warp edges, and the tethers.
    stretch::Stretch,
    /// Cloth–cloth contact: the layers stay the thickness apart.
    self_collision::SelfCollision,
}
