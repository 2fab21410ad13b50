//! Each particle's corrections per family, read off the state around each
//! family's sweeps (the kernels record nothing).

use glam::{Quat, Vec3};

use super::FamilyDiagnostics;
use crate::solver::families::{Family, PerFamily};
use crate::solver::kernels::angles::atan2;
use crate::solver::kernels::{Particles, Shared};
use crate::solver::team::Crew;

/// What each particle was moved and turned by, read off its state around
/// each family's sweeps rather than recorded by the kernels: after a sweep,
/// the family is credited with each particle's position less the one it had
/// before the sweep, and with its orientation times the inverse of the one
/// before. The kernels stay as fast as with diagnostics off; one pass over
/// the particles per sweep does the bookkeeping.
///
/// `δx` is then the sum of the family's moves over the phase, and `δθ` the
/// rotation its turns compose to, as axis × angle. The buffers are kept
/// between phases.
#[derive(Clone, Debug, Default)]
pub(crate) struct CorrectionTrack {
    /// Each particle's position and orientation when last credited.
    x: Vec<Vec3>,
    q: Vec<Quat>,
    /// Per family, the turns composed so far.
    turns: PerFamily<Vec<Quat>>,
}

impl CorrectionTrack {
    /// Starts tracking an adjust phase from the particles' state: zeroes
    /// every family's corrections in `families`, which the returned view
    /// writes until it is dropped.
    pub(crate) fn begin<'a>(
        &'a mut self,
        p: &Particles,
        families: &'a mut PerFamily<FamilyDiagnostics>,
    ) -> Tracking<'a> {
        let n = p.inv_mass.len();
        self.x.clear();
        self.x.extend((0..n).map(|i| p.x(i)));
        self.q.clear();
        self.q.extend((0..n).map(|i| p.q(i)));
        for turns in self.turns.iter_mut() {
            turns.clear();
            turns.resize(n, Quat::IDENTITY);
        }
        let mut fds = families.iter_mut();
        let mut turns = self.turns.iter_mut();
        let sides = PerFamily::from_fn(|_| {
            let fd = fds.next().expect("one per family");
            // The crew writes these through raw views: one slot per particle.
            assert!(
                fd.dx.len() == n && fd.dtheta.len() == n,
                "corrections for {n} particles"
            );
            fd.dx.fill(Vec3::ZERO);
            fd.dtheta.fill(Vec3::ZERO);
            Sides {
                dx: Shared::new(&mut fd.dx),
                dtheta: Shared::new(&mut fd.dtheta),
                turns: Shared::new(turns.next().expect("one per family")),
            }
        });
        Tracking {
            x: Shared::new(&mut self.x),
            q: Shared::new(&mut self.q),
            families: sides,
        }
    }
}

/// One family's arrays, as a phase's crew writes them.
struct Sides<'a> {
    dx: Shared<'a, Vec3>,
    dtheta: Shared<'a, Vec3>,
    turns: Shared<'a, Quat>,
}

/// An adjust phase's view of a [`CorrectionTrack`]. Each thread of the
/// crew credits its own share of the particles ([`Crew::share`]), the same
/// share every time, so no two threads touch the same element.
pub(crate) struct Tracking<'a> {
    x: Shared<'a, Vec3>,
    q: Shared<'a, Quat>,
    families: PerFamily<Sides<'a>>,
}

impl Tracking<'_> {
    /// Credits `family` with what happened to this thread's share since it
    /// was last credited, then waits for the crew (the next sweep may move
    /// any particle). Called after the family's sweep (after the last of
    /// consecutive sweeps of one family). A family that never turns an
    /// element ([`Family::turns`]) is credited with the moves alone: the
    /// orientations are as they were last credited.
    pub(crate) fn credit(&self, crew: &Crew, family: Family, p: &Particles) {
        let f = &self.families[family];
        let turns = family.turns();
        for i in crew.share(self.x.len()) {
            let x = p.x(i);
            // SAFETY: in bounds (a share of the particles); this thread's
            // share only, and the same share on every call.
            unsafe {
                let x0 = self.x.get(i);
                *f.dx.get(i) += x - *x0;
                *x0 = x;
                if turns {
                    let (q, q0) = (p.q(i), self.q.get(i));
                    let composed = f.turns.get(i);
                    *composed = q * q0.conjugate() * *composed;
                    *q0 = q;
                }
            }
        }
        crew.barrier();
    }

    /// Takes this thread's share of the positions as they are, crediting no
    /// family (after the colliders, which only move particles).
    pub(crate) fn skip(&self, crew: &Crew, p: &Particles) {
        for i in crew.share(self.x.len()) {
            // SAFETY: as in `credit`.
            unsafe { *self.x.get(i) = p.x(i) }
        }
    }

    /// Writes this thread's share of every family's `δθ`, the phase over.
    pub(crate) fn finish(&self, crew: &Crew) {
        for f in self.families.iter().map(|(_, f)| f) {
            for i in crew.share(self.x.len()) {
                // SAFETY: as in `credit`.
                unsafe { *f.dtheta.get(i) = rotation_vector(*f.turns.get(i)) }
            }
        }
    }
}

/// The rotation vector (axis × angle, the angle in `[0, π]`) of the
/// rotation `q` stands for; `q` need not be exactly of unit length. The
/// angle comes from `atan2`, which keeps full precision for the tiny angles
/// a sweep turns by (an `acos` of `w` would round them to 0).
fn rotation_vector(q: Quat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let axis = q.xyz();
    let s = axis.length();
    if s == 0.0 {
        return Vec3::ZERO;
    }
    axis * (2.0 * atan2(s, q.w) / s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::kernels::{NoRecord, shift, turn};
    use crate::solver::team;

    #[test]
    fn corrections_are_credited_to_the_family_whose_sweep_made_them() {
        let n = 3;
        let (mut x, mut q) = (vec![Vec3::ZERO; n], vec![Quat::IDENTITY; n]);
        let ones = vec![1.0; n];
        // Stale corrections from an earlier phase, which `begin` clears.
        let mut families = PerFamily::from_fn(|_| FamilyDiagnostics {
            dx: vec![Vec3::ONE; n],
            dtheta: vec![Vec3::ONE; n],
            ..FamilyDiagnostics::default()
        });
        let about_z = |angle: f32| Vec3::new(0.0, 0.0, angle);
        let mut track = CorrectionTrack::default();
        let p = Particles::new(&mut x, &mut q, &ones, &ones);
        {
            let t = track.begin(&p, &mut families);
            team::run(1, |crew| {
                shift(&p, 0, Vec3::X);
                turn(&p, 1, about_z(0.1), &mut NoRecord);
                t.credit(crew, Family::Normality, &p);
                shift(&p, 0, Vec3::Y);
                turn(&p, 1, about_z(0.2), &mut NoRecord);
                t.credit(crew, Family::Planarity, &p);
                // A collider's move: no family's.
                shift(&p, 2, Vec3::Z);
                t.skip(crew, &p);
                shift(&p, 0, Vec3::X);
                turn(&p, 1, about_z(0.3), &mut NoRecord);
                t.credit(crew, Family::Normality, &p);
                // Stretch only moves: its credit takes the moves alone.
                shift(&p, 2, Vec3::X);
                t.credit(crew, Family::Stretch, &p);
                t.finish(crew);
            });
        }
        let (normality, planarity) = (&families[Family::Normality], &families[Family::Planarity]);
        assert_eq!(normality.dx, [2.0 * Vec3::X, Vec3::ZERO, Vec3::ZERO]);
        assert_eq!(planarity.dx, [Vec3::Y, Vec3::ZERO, Vec3::ZERO]);
        assert_eq!(
            families[Family::Stretch].dx,
            [Vec3::ZERO, Vec3::ZERO, Vec3::X]
        );
        assert!(
            normality.dtheta[1].abs_diff_eq(about_z(0.4), 1e-6),
            "{:?}",
            normality.dtheta
        );
        assert!(
            planarity.dtheta[1].abs_diff_eq(about_z(0.2), 1e-6),
            "{:?}",
            planarity.dtheta
        );
        assert_eq!(normality.dtheta[0], Vec3::ZERO);
        // Stretch only moved; the families that did not run were credited
        // nothing (their stale corrections cleared).
        assert!(
            families[Family::Stretch]
                .dtheta
                .iter()
                .all(|v| *v == Vec3::ZERO)
        );
        let ran = [Family::Normality, Family::Planarity, Family::Stretch];
        for f in Family::ALL.into_iter().filter(|f| !ran.contains(f)) {
            assert!(families[f].dtheta.iter().all(|v| *v == Vec3::ZERO));
            assert!(families[f].dx.iter().all(|v| *v == Vec3::ZERO));
        }
    }

    #[test]
    fn rotation_vectors_keep_tiny_angles() {
        for angle in [1e-7f32, 1e-3, 0.5, 3.0] {
            let q = Quat::from_axis_angle(Vec3::Y, angle);
            let r = rotation_vector(q);
            assert!(
                (r.y - angle).abs() <= 1e-6 * angle.max(1.0),
                "{angle}: {r:?}"
            );
            // The same rotation, as the other of its two quaternions.
            assert!(rotation_vector(-q).abs_diff_eq(r, 1e-6 * angle.max(1.0)));
        }
        assert_eq!(rotation_vector(Quat::IDENTITY), Vec3::ZERO);
    }
}
