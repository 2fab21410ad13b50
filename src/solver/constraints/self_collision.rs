//! Self-collision: the cloth's two sides stay apart at its thickness.
//!
//! A **contact** is a particle `p` and a triangle `(a, b, c)` of the grid
//! that `p` is not a corner of. (A triangle beside `p` in a flat or gently
//! bent cloth has `p`'s foot outside it; only a crease sharper than a right
//! angle within one cell brings a neighbour's triangle over `p`, and then the
//! contact is what keeps the crease from passing through itself.) Let
//! `y = β_a x_a + β_b x_b + β_c x_c` be the foot of `p` on the triangle's plane (barycentric `β`), and `n̄` the elements' own normals
//! interpolated there, `n̄ ∝ β_a n_a + β_b n_b + β_c n_c`. The constraint is
//! planarity's `(x_b − x_a) · n_a = 0`, made one-sided and offset by the
//! thickness `h`:
//!
//! ```text
//! C = s (x_p − y) · n̄ − h ≥ 0,   gradients  s n̄  (p),  −β_k s n̄  (k = a, b, c)
//! ```
//!
//! active while the foot lies in the triangle. The side `s = ±1` is the one
//! `p` was on at the **start** of the substep, before the update moved it: a
//! particle that the update carried through the other layer is pushed back
//! to where it came from, not on through. The interpolated element normal is
//! smooth across triangle edges (the flat triangles' normals jump), so a
//! particle sliding over the other layer is pushed in a direction that does
//! not flip from one triangle to the next; where the elements disagree with
//! the triangle (a crumpled cell) the triangle's own normal is used.
//! Positions only: no element is turned.
//!
//! Contacts are picked once per substep (`SelfContacts::build`) over the
//! predicted positions, from the near particle–triangle pairs that the
//! broad phase keeps while the cloth has not moved apart by more than a
//! skin (`broad_phase::NearTriangles`), and kept for all the substep's
//! sweeps; they are coloured like every other constraint set, so the
//! threads share them bit-identically. For a second after a jerk, particles
//! of edges that cross a triangle (`SelfContacts::find_tangles`) are left
//! out, so that a cloth dragged through itself comes apart instead of being
//! held tangled. Friction between layers is the colliders' Coulomb model
//! (`apply_friction`).
//!
//! The violation reported is the penetration `h − |(x_p − y) · n|` of the
//! pairs closer than `h` ([`for_each_close`]), and separately the number of
//! grid edges that cross a triangle they share no vertex with
//! ([`crossings`]), which a crossing-free cloth keeps at zero.

use glam::Vec3;

use super::lanes::{LANES, Sse as F, each};
use super::{Particles, delta_mu, shift};
use crate::solver::broad_phase::{self, NearTriangles, SpatialHash};
use crate::solver::cloth::{ClothSpec, normal_of};
use crate::solver::team;
use crate::solver::topology::{Batched, Topology, Touches};

/// Positions of a contact search, in lanes.
type V3 = super::lanes::V3<F>;

/// One particle against one triangle, with the side it keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelfContact {
    /// The particle.
    pub particle: u32,
    /// The triangle's particles.
    pub triangle: [u32; 3],
    /// `+1` or `−1`: the side of the triangle the particle was on at the
    /// substep's start (along its normal `(x_b − x_a) × (x_c − x_a)`).
    pub side: f32,
    /// Which of the triangle's edges lie on the cloth's border: bit `k` for
    /// the edge opposite corner `k` (used by `least`).
    pub rim: u8,
}

impl Touches for SelfContact {
    fn particles(&self) -> impl Iterator<Item = u32> {
        [
            self.particle,
            self.triangle[0],
            self.triangle[1],
            self.triangle[2],
        ]
        .into_iter()
    }
}

/// How far a barycentric coordinate may fall below 0 with the foot still in
/// the triangle: neighbouring triangles overlap by a sliver, so a particle
/// crossing the edge between two is always under one.
const INSIDE: f32 = 0.01;
/// The same beyond an edge on the cloth's border: half a cell, a hem
/// around the cloth, so that a layer lying along another's border does
/// not slip round it edge first (no face is under either edge there).
const INSIDE_RIM: f32 = 0.5;

/// How much farther beyond a triangle's edges than [`INSIDE`] or
/// [`INSIDE_RIM`] a particle may be, in barycentric terms, to be a contact
/// of the substep: room to come over the triangle during the sweeps. A grid
/// neighbour beside a triangle sits at about −1. A twentieth of the
/// triangle: a quarter made three times the contacts on a folded sheet
/// (every particle near an edge took the triangles beyond it too, whose
/// extended planes can put the particle on the wrong side), cost a third
/// more of the step, and let `folding_sheet` at 32 × 32 and
/// `furling_banner` at 48 × 36 cross where a twentieth does not
/// (BENCHMARKS.md).
const CANDIDATE: f32 = 0.05;

/// A triangle, with what every foot on it needs.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    corner: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// The unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    normal: Vec3,
    /// `1 / |(x_b − x_a) × (x_c − x_a)|`, one over twice the area.
    inv_area2: f32,
}

impl Triangle {
    /// The triangle with corners `t`; `None` if it is degenerate.
    #[inline(always)]
    fn new(t: [Vec3; 3]) -> Option<Self> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let cross = e1.cross(e2);
        let area2 = cross.length();
        if area2 <= 1e-12 {
            return None;
        }
        let inv_area2 = area2.recip();
        Some(Self {
            corner: t[0],
            e1,
            e2,
            normal: cross * inv_area2,
            inv_area2,
        })
    }

    /// Signed distance of `p` from the plane, along the normal.
    #[inline(always)]
    fn distance(&self, p: Vec3) -> f32 {
        (p - self.corner).dot(self.normal)
    }

    /// The foot of `p`.
    #[inline(always)]
    fn foot(&self, p: Vec3) -> Foot {
        let v = p - self.corner;
        // Cross products with the normal drop v's normal part: the foot's
        // coordinates.
        let bb = v.cross(self.e2).dot(self.normal) * self.inv_area2;
        let bc = self.e1.cross(v).dot(self.normal) * self.inv_area2;
        Foot {
            bary: [1.0 - bb - bc, bb, bc],
            point: self.corner + self.e1 * bb + self.e2 * bc,
            normal: self.normal,
            distance: v.dot(self.normal),
        }
    }
}

/// The lowest barycentric coordinate at corner `k` of a foot within the
/// triangle: below 0 by [`INSIDE`], or [`INSIDE_RIM`] if the edge opposite
/// `k` is on the border (`rim`), and by `more`.
#[inline(always)]
fn least(rim: u8, k: usize, more: f32) -> f32 {
    let slack = if rim & (1 << k) != 0 {
        INSIDE_RIM
    } else {
        INSIDE
    };
    -(slack + more)
}

/// A point's foot on a triangle's plane.
#[derive(Clone, Copy, Debug)]
struct Foot {
    /// Barycentric coordinates of the foot.
    bary: [f32; 3],
    /// The foot.
    point: Vec3,
    /// The triangle's unit normal, `(x_b − x_a) × (x_c − x_a)` normalised.
    normal: Vec3,
    /// Signed distance of the point from the plane, along `normal`.
    distance: f32,
}

impl Foot {
    /// The foot of `p` on triangle `t`; `None` for a degenerate triangle.
    #[inline(always)]
    fn of(p: Vec3, t: [Vec3; 3]) -> Option<Self> {
        Triangle::new(t).map(|t| t.foot(p))
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem, and every edge by `more`.
    #[inline(always)]
    fn within(&self, rim: u8, more: f32) -> bool {
        (0..3).all(|k| self.bary[k] >= least(rim, k, more))
    }

    /// Whether the foot is on the triangle, its border edges (`rim`) grown
    /// by a hem.
    #[inline(always)]
    fn inside(&self, rim: u8) -> bool {
        self.within(rim, 0.0)
    }

    /// The elements' normals `n` interpolated at the foot, or the
    /// triangle's where they disagree with it by more than 60°.
    #[inline(always)]
    fn smooth_normal(&self, n: [Vec3; 3]) -> Vec3 {
        let [ba, bb, bc] = self.bary;
        let m = n[0] * ba + n[1] * bb + n[2] * bc;
        let len = m.length();
        if len > 1e-6 && m.dot(self.normal) > 0.5 * len {
            m * len.recip()
        } else {
            self.normal
        }
    }
}

/// Projects one contact, keeping the layers `thickness` apart, with
/// compliance `alpha_t` (`α / Δt²`).
#[inline]
pub(crate) fn project(p: &Particles, c: SelfContact, mu: &mut f32, thickness: f32, alpha_t: f32) {
    let i = c.particle as usize;
    let t = c.triangle.map(|k| k as usize);
    let Some(foot) = Foot::of(p.x(i), t.map(|k| p.x(k))) else {
        return;
    };
    if !foot.inside(c.rim) {
        return;
    }
    let n = foot.smooth_normal(t.map(|k| normal_of(p.q(k))));
    let violation = c.side * (p.x(i) - foot.point).dot(n) - thickness;
    if violation >= 0.0 {
        return;
    }
    let wp = p.inv_mass[i];
    let wt = t.map(|k| p.inv_mass[k]);
    let b = foot.bary;
    let w = generalised_inverse_mass(wp, wt, b);
    if w == 0.0 {
        return;
    }
    // One-sided: the multiplier only ever pushes the layers apart.
    let d = delta_mu(violation, w, alpha_t, *mu).max(-*mu);
    *mu += d;
    let dir = n * (c.side * d);
    if wp > 0.0 {
        shift(p, i, dir * wp);
    }
    for k in 0..3 {
        if wt[k] > 0.0 {
            shift(p, t[k], dir * (-b[k] * wt[k]));
        }
    }
}

/// `w_p + Σ β_k² w_k`: how far a contact's separation moves per unit of its
/// multiplier, for the particle's inverse mass `wp`, the corners' `wt` and
/// the foot's barycentric `b`.
#[inline(always)]
fn generalised_inverse_mass(wp: f32, wt: [f32; 3], b: [f32; 3]) -> f32 {
    wp + b[0] * b[0] * wt[0] + b[1] * b[1] * wt[1] + b[2] * b[2] * wt[2]
}

/// The box around a triangle's corners, grown by `margin`.
#[inline]
fn bounds(t: [Vec3; 3], margin: f32) -> (Vec3, Vec3) {
    (
        t[0].min(t[1]).min(t[2]) - Vec3::splat(margin),
        t[0].max(t[1]).max(t[2]) + Vec3::splat(margin),
    )
}

/// The contact search's test for one triangle, on [`LANES`] particles at a
/// time: is the particle inside the triangle's box grown by the reach, with
/// its foot within the triangle grown by [`CANDIDATE`] (and the hem, as
/// [`Foot::within`])? Each barycentric coordinate is one dot product,
/// `β_b = (x − x_a) · ĝ_b` and `β_c = (x − x_a) · ĝ_c` with the gradients of
/// the foot's coordinates `ĝ_b = (e₂ × c) / |c|²` and `ĝ_c = (c × e₁) / |c|²`
/// (`c = e₁ × e₂`, twice the area along the normal), and
/// `β_a = 1 − β_b − β_c`. This is the search's own definition of a
/// candidate: the particles it lets through are picked without a second
/// test, so one particle alone would be judged by the same operations.
struct Candidates {
    corner: V3,
    to_b: V3,
    to_c: V3,
    /// The lowest barycentric coordinate let through at each corner.
    least: [F; 3],
    /// The triangle's box grown by the reach.
    lo: V3,
    hi: V3,
}

impl Candidates {
    /// The test for the triangle with corners `t`, whose border edges are
    /// `rim`; `None` if it is degenerate (twice its area at most `1e-12`).
    #[inline(always)]
    fn new(t: [Vec3; 3], rim: u8, reach: f32) -> Option<Self> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let cross = e1.cross(e2);
        let area2_squared = cross.length_squared();
        if area2_squared.is_nan() || area2_squared <= 1e-24 {
            return None;
        }
        let inv = area2_squared.recip();
        let (lo, hi) = bounds(t, reach);
        Some(Self {
            corner: V3::splat(t[0]),
            to_b: V3::splat(e2.cross(cross) * inv),
            to_c: V3::splat(cross.cross(e1) * inv),
            least: std::array::from_fn(|k| F::splat(least(rim, k, CANDIDATE))),
            lo: V3::splat(lo),
            hi: V3::splat(hi),
        })
    }

    /// Bit `k` set where lane `k`'s point `x` passes.
    #[inline(always)]
    fn of(&self, x: V3) -> u32 {
        let v = x - self.corner;
        let bb = v.dot(self.to_b);
        let bc = v.dot(self.to_c);
        let ba = F::ONE - bb - bc;
        (x.in_box(self.lo, self.hi)
            & ba.simd_ge(self.least[0])
            & bb.simd_ge(self.least[1])
            & bc.simd_ge(self.least[2]))
        .to_bitmask()
    }
}

/// Up to [`LANES`] particles and their positions, in lanes.
struct Gathered {
    idx: [u32; LANES],
    x: V3,
    /// Bit `k` set if lane `k` holds a particle.
    live: u32,
}

impl Gathered {
    /// The particles `chunk` (at most [`LANES`]) at positions `x`. A short
    /// chunk is padded with its first particle, whose lanes are then masked
    /// off.
    #[inline]
    fn of(chunk: &[u32], x: &[Vec3]) -> Self {
        let idx = each(|k| chunk.get(k).copied().unwrap_or(chunk[0]));
        Self {
            idx,
            x: V3::gather(x, &idx),
            live: (1 << chunk.len()) - 1,
        }
    }
}

/// One triangle's contact search within a substep: its [`Candidates`]
/// test, and the triangle now and at the substep's start, made once a
/// particle passes.
struct Picker {
    tri: [u32; 3],
    rim: u8,
    lanes: Candidates,
    /// Every corner driven: a driven particle is no contact of it.
    driven: bool,
    now: Option<Option<Triangle>>,
    start: Option<Option<Triangle>>,
}

impl Picker {
    /// The search for triangle `tri` (border edges `rim`); `None` if it is
    /// degenerate.
    #[inline]
    fn new(tri: [u32; 3], rim: u8, layers: &Layers, reach: f32) -> Option<Self> {
        let corners = tri.map(|k| layers.now[k as usize]);
        Some(Self {
            tri,
            rim,
            lanes: Candidates::new(corners, rim, reach)?,
            driven: tri.iter().all(|&k| layers.inv_mass[k as usize] == 0.0),
            now: None,
            start: None,
        })
    }

    /// Appends the contacts among the lanes `hits` of particles `idx` that
    /// passed [`Candidates`]: not a corner, not a driven particle of a
    /// driven triangle, not tangled, and closer than `reach` to the plane or
    /// on the other side than it started on. `false` if the triangle turned
    /// out degenerate (now or at the substep's start): no more contacts.
    #[inline]
    fn take(
        &mut self,
        mut hits: u32,
        idx: &[u32; LANES],
        layers: &Layers,
        reach: f32,
        tangled: &impl Fn(u32) -> bool,
        found: &mut Vec<SelfContact>,
    ) -> bool {
        let Layers {
            now,
            start,
            inv_mass,
        } = *layers;
        let tri = self.tri;
        while hits != 0 {
            let p = idx[hits.trailing_zeros() as usize];
            hits &= hits - 1;
            if tri.contains(&p) || (self.driven && inv_mass[p as usize] == 0.0) || tangled(p) {
                continue;
            }
            let t_now = self
                .now
                .get_or_insert_with(|| Triangle::new(tri.map(|k| now[k as usize])));
            let t_start = self
                .start
                .get_or_insert_with(|| Triangle::new(tri.map(|k| start[k as usize])));
            let (Some(t_now), Some(t_start)) = (t_now, t_start) else {
                return false;
            };
            let side = if t_start.distance(start[p as usize]) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let distance = t_now.distance(now[p as usize]);
            if distance.abs() < reach || distance * side < 0.0 {
                found.push(SelfContact {
                    particle: p,
                    triangle: tri,
                    side,
                    rim: self.rim,
                });
            }
        }
        true
    }
}

/// The contacts of one substep, coloured, and the near pairs they were
/// picked from.
#[derive(Clone, Debug, Default)]
pub(crate) struct SelfContacts {
    /// The contacts, colour by colour.
    pub set: Batched<SelfContact>,
    near: NearTriangles,
    /// Per particle: an end of an edge that crosses a triangle, or a corner
    /// of a crossed triangle, where they were last looked for
    /// ([`SelfContacts::find_tangles`]); empty until they are.
    tangled: Vec<bool>,
    /// How many more substeps leave tangled particles out.
    watch: u32,
    /// Whether this substep does.
    leaving: bool,
}

/// The positions and orientations a contact search reads.
pub(crate) struct Layers<'a> {
    /// Predicted positions (after the update).
    pub now: &'a [Vec3],
    /// Positions at the substep's start.
    pub start: &'a [Vec3],
    /// Inverse masses: a contact between driven particles only is left out.
    pub inv_mass: &'a [f32],
}

/// Triangle groups a thread checks for contacts at a time: a few dozen
/// microseconds' work.
const PICK_BLOCK: usize = 32;

/// The near pairs' skin, in rest spacings: how far the particles may move
/// (beyond their common motion) between two searches, twice over. Larger
/// keeps more pairs to check each substep, smaller searches more often.
const SKIN: f32 = 1.0;

impl SelfContacts {
    /// Finds every particle–triangle pair closer than `reach` (or on the
    /// other side than it started on) at the predicted positions, with the
    /// side each started on, and colours them. The pairs are checked among
    /// the near pairs ([`NearTriangles`]), searched again only when the
    /// cloth has moved enough to need it.
    pub(crate) fn build(
        &mut self,
        layers: &Layers,
        mesh: &Topology,
        spec: &ClothSpec,
        reach: f32,
        threads: usize,
    ) {
        let now = layers.now;
        let (dx, dy) = spec.spacing();
        let triangles = &mesh.triangles;
        self.near.update(
            now,
            triangles,
            (reach, SKIN * dx.min(dy)),
            dx.max(dy),
            threads,
        );
        // The threads check blocks of triangle groups; the blocks' finds,
        // joined in order, are what one thread would find alone.
        let this = &*self;
        let groups = broad_phase::groups(triangles.len());
        let blocks = team::run_blocks(threads, groups, PICK_BLOCK, |range| {
            let (mut found, mut gathered) = (Vec::new(), Vec::new());
            for g in range {
                this.pick(g, mesh, layers, reach, &mut found, &mut gathered);
            }
            found
        });
        let found = blocks.concat();
        self.set = Batched::coloured(found, now.len());
    }

    /// Appends the contacts of the triangles of group `g`
    /// ([`NearTriangles`]) among the group's near particles, triangle by
    /// triangle, each in the particles' (ascending) order: each particle
    /// inside the triangle's box grown by `reach`, with its foot over the
    /// triangle (or near enough to come over it in the sweeps:
    /// [`Candidates`]), and closer than `reach` to its plane or on the other
    /// side than it started on. A grid neighbour beside the triangle (a
    /// coordinate near −1) is not. The group's particles are gathered into
    /// lanes once (`gathered`, scratch space) for all its triangles.
    fn pick(
        &self,
        g: usize,
        mesh: &Topology,
        layers: &Layers,
        reach: f32,
        found: &mut Vec<SelfContact>,
        gathered: &mut Vec<Gathered>,
    ) {
        let near = self.near.of_group(g);
        if near.is_empty() {
            return;
        }
        let tangled = |k: u32| self.leaving && self.tangled.get(k as usize) == Some(&true);
        gathered.clear();
        for t in broad_phase::group(g, mesh.triangles.len()) {
            let tri = mesh.triangles[t];
            if tri.into_iter().any(tangled) {
                continue;
            }
            let Some(mut picker) = Picker::new(tri, mesh.rims[t], layers, reach) else {
                continue;
            };
            if gathered.is_empty() {
                gathered.extend(
                    near.chunks(LANES)
                        .map(|chunk| Gathered::of(chunk, layers.now)),
                );
            }
            for chunk in gathered.iter() {
                let hits = picker.lanes.of(chunk.x) & chunk.live;
                if hits != 0 && !picker.take(hits, &chunk.idx, layers, reach, &tangled, found) {
                    break;
                }
            }
        }
    }

    /// Drops the contacts and the near pairs (the family was turned off).
    pub(crate) fn clear(&mut self) {
        self.set = Batched::default();
        self.near.clear();
        self.tangled.clear();
        self.watch = 0;
        self.leaving = false;
    }
}

/// Friction between layers: the colliders' Coulomb model. Each contact that
/// pushed in the substep (multiplier `mu > 0`) removes the tangential motion
/// of its particle relative to the triangle's point under it, up to
/// `friction` times the distance it pushed them apart, shared in proportion
/// to inverse mass. One thread, in contact order.
pub(crate) fn apply_friction(
    x: &mut [Vec3],
    start: &[Vec3],
    inv_mass: &[f32],
    contacts: &[SelfContact],
    mu: &[f32],
    friction: f32,
) {
    if friction <= 0.0 {
        return;
    }
    for (c, &m) in contacts.iter().zip(mu) {
        if m <= 0.0 {
            continue;
        }
        let i = c.particle as usize;
        let t = c.triangle.map(|k| k as usize);
        let Some(foot) = Foot::of(x[i], t.map(|k| x[k])) else {
            continue;
        };
        if !foot.inside(c.rim) {
            continue;
        }
        let b = foot.bary;
        let (wp, wt) = (inv_mass[i], t.map(|k| inv_mass[k]));
        let w = generalised_inverse_mass(wp, wt, b);
        if w == 0.0 {
            continue;
        }
        let moved = |k: usize| x[k] - start[k];
        let rel = moved(i) - (moved(t[0]) * b[0] + moved(t[1]) * b[1] + moved(t[2]) * b[2]);
        let n = foot.normal;
        let tangential = rel - n * rel.dot(n);
        let len = tangential.length();
        if len <= 1e-12 {
            continue;
        }
        let limit = friction * m * w;
        let slip = tangential * ((limit / len).min(1.0) / w);
        x[i] -= slip * wp;
        for k in 0..3 {
            x[t[k]] += slip * (b[k] * wt[k]);
        }
    }
}

/// Calls `f(p, triangle, depth)` for every particle–triangle pair (`p` not
/// a corner) closer than `thickness`, with its foot in the triangle:
/// `depth = thickness − |distance|`, how far the pair is inside the
/// thickness. Only positions are read.
pub fn for_each_close(
    x: &[Vec3],
    mesh: &Topology,
    spec: &ClothSpec,
    mut f: impl FnMut(u32, [u32; 3], f32),
) {
    let h = spec.thickness;
    if h <= 0.0 {
        return;
    }
    let (dx, dy) = spec.spacing();
    let mut hash = SpatialHash::default();
    hash.build(x, dx.max(dy));
    for (&tri, &rim) in mesh.triangles.iter().zip(&mesh.rims) {
        let corners = tri.map(|k| x[k as usize]);
        let (lo, hi) = bounds(corners, h);
        hash.query(lo, hi, |p| {
            if tri.contains(&p) {
                return;
            }
            if let Some(foot) = Foot::of(x[p as usize], corners)
                && foot.inside(rim)
                && foot.distance.abs() < h
            {
                f(p, tri, h - foot.distance.abs());
            }
        });
    }
}

/// Where segment `u → v` crosses triangle `t`, as the fraction of the way
/// from `u`, given the ends' signed distances `(du, dv)` from its plane and
/// its [`edge_margins`]: the ends on opposite sides of the plane and the
/// crossing point inside the triangle, each by more than [`ON_PLANE`].
/// `None` otherwise: an edge that only touches the triangle, or lies in its
/// plane (two layers pressed flat on the ground), does not cross.
#[inline]
fn crosses_at(
    u: Vec3,
    v: Vec3,
    (du, dv): (f32, f32),
    t: &Triangle,
    margins: &[f32; 3],
) -> Option<f32> {
    if du * dv >= 0.0 || du.abs() <= ON_PLANE || dv.abs() <= ON_PLANE {
        return None;
    }
    let at = du / (du - dv);
    let foot = t.foot(u + (v - u) * at);
    (0..3).all(|k| foot.bary[k] > margins[k]).then_some(at)
}

/// [`ON_PLANE`] in barycentric terms at each corner: a point's coordinate
/// `b_k` times twice the area over the opposite edge is its distance from
/// that edge.
fn edge_margins(t: &Triangle) -> [f32; 3] {
    let corners = [t.corner, t.corner + t.e1, t.corner + t.e2];
    std::array::from_fn(|k| {
        let edge = corners[(k + 2) % 3].distance(corners[(k + 1) % 3]);
        ON_PLANE * edge * t.inv_area2
    })
}

/// How close to a triangle's plane or edges, in metres, a point counts as
/// on them rather than on a side: 1 µm, far below any thickness and far
/// above `f32` rounding at the scale of a cloth.
pub const ON_PLANE: f32 = 1e-6;

/// The grid's edges (weft, warp, and the diagonal that splits each cell into
/// its two triangles) that leave particle `p` towards higher indices, then
/// towards lower ones: every edge of the triangle mesh at `p`.
#[inline]
fn edges_at(p: u32, spec: &ClothSpec) -> impl Iterator<Item = u32> {
    let (w, h) = (spec.weft, spec.warp);
    let (i, j) = (p % w, p / w);
    let (right, up, left, down) = (i + 1 < w, j + 1 < h, i > 0, j > 0);
    [
        (right, p.wrapping_add(1)),
        (up, p.wrapping_add(w)),
        (right && up, p.wrapping_add(w + 1)),
        (left, p.wrapping_sub(1)),
        (down, p.wrapping_sub(w)),
        (left && down, p.wrapping_sub(w + 1)),
    ]
    .into_iter()
    .filter_map(|(there, o)| there.then_some(o))
}

/// How many (edge, triangle) pairs of the cloth's mesh cross, among pairs
/// that share no particle: 0 for a cloth that does not pass through itself.
/// Each crossing is found from the edge's end nearer the crossing point,
/// which lies within half the longest edge of the triangle's box.
pub fn crossings(x: &[Vec3], triangles: &[[u32; 3]], spec: &ClothSpec) -> usize {
    let mut count = 0;
    scan_crossings(x, triangles, spec, None, |_, _| count += 1);
    count
}

impl SelfContacts {
    /// Finds which particles are tangled at positions `x`, the ends of the
    /// edges that cross a triangle and the triangle's corners, and returns
    /// how many (edge, triangle) pairs cross ([`crossings`]). The near
    /// pairs of the last substep are the candidates while they still cover
    /// `x`; the result is the same either way.
    pub(crate) fn find_tangles(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
    ) -> usize {
        self.tangled.clear();
        self.tangled.resize(x.len(), false);
        let tangled = &mut self.tangled;
        let mut count = 0;
        scan_crossings(x, triangles, spec, Some(&self.near), |edge, tri| {
            count += 1;
            for k in edge.into_iter().chain(tri) {
                tangled[k as usize] = true;
            }
        });
        count
    }

    /// Leaves tangled particles out of the contacts for the next `substeps`
    /// substeps.
    pub(crate) fn watch_for_tangles(&mut self, substeps: u32) {
        self.watch = self.watch.max(substeps);
    }

    /// Whether this substep leaves tangled particles out of the contacts:
    /// while a watch is on ([`SelfContacts::watch_for_tangles`]; this call
    /// counts one substep of it).
    pub(crate) fn leave_tangles_this_substep(&mut self) -> bool {
        self.leaving = self.watch > 0;
        self.watch = self.watch.saturating_sub(1);
        self.leaving
    }
}

/// The hash's cells for counting crossings: a cell's rest diagonal, about
/// one triangle. (Cells sized from the longest edge would hold the whole
/// cloth once one edge is pulled long; small cells keep a query's cost to
/// the particles really near.)
fn crossing_cell(spec: &ClothSpec) -> f32 {
    let (dx, dy) = spec.spacing();
    dx.hypot(dy)
}

/// Calls `crossing(edge, triangle)` for every (edge, triangle) pair that
/// crosses ([`crossings`]). Each crossing is found from the edge's nearer
/// end `p`, which lies within half the edge `|po|` of the crossing point,
/// and so of the triangle's box: the candidates for a triangle are the
/// particles in its box grown by half the longest edge. Particles with an
/// edge longer than a cell's rest diagonal (pulled long by a jerk) are
/// checked against every triangle instead, so that one long edge does not
/// grow every query to the whole cloth. The candidates come from `near`
/// while its pairs cover that growth, else from a new hash.
fn scan_crossings(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    spec: &ClothSpec,
    near: Option<&NearTriangles>,
    mut crossing: impl FnMut([u32; 2], [u32; 3]),
) {
    // Half the longest edge at each particle.
    let half: Vec<f32> = (0..x.len() as u32)
        .map(|p| {
            let xp = x[p as usize];
            edges_at(p, spec).fold(0.0f32, |m, o| m.max(xp.distance(x[o as usize])))
        })
        .map(|l| 0.5 * l)
        .collect();
    let longest = half.iter().copied().fold(0.0f32, f32::max);
    if longest <= 0.0 || !longest.is_finite() {
        return;
    }
    let grow = longest.min(crossing_cell(spec));
    let near = near.filter(|n| n.covers(x, grow));
    let mut hash = SpatialHash::default();
    if near.is_none() {
        hash.build(x, crossing_cell(spec));
    }
    for (k, &tri) in triangles.iter().enumerate() {
        let Some(mut t) = TriangleCrossing::new(x, tri) else {
            continue;
        };
        let (lo, hi) = (t.lo - Vec3::splat(grow), t.hi + Vec3::splat(grow));
        let mut visit = |p: u32| {
            if half[p as usize] > grow {
                return; // in the pass below
            }
            let xp = x[p as usize];
            if xp.cmpge(lo).all() && xp.cmple(hi).all() {
                t.edges_from(p, x, spec, &mut crossing);
            }
        };
        match near {
            Some(n) => n.of(k).iter().copied().for_each(&mut visit),
            None => hash.query(lo, hi, &mut visit),
        }
    }
    let far: Vec<u32> = (0..x.len() as u32)
        .filter(|&p| half[p as usize] > grow)
        .collect();
    if far.is_empty() {
        return;
    }
    for &tri in triangles {
        let Some(mut t) = TriangleCrossing::new(x, tri) else {
            continue;
        };
        for &p in &far {
            t.edges_from(p, x, spec, &mut crossing);
        }
    }
}

/// A triangle, with what counting the edges that cross it needs.
struct TriangleCrossing {
    corners: [u32; 3],
    t: Triangle,
    /// Its bounding box.
    lo: Vec3,
    hi: Vec3,
    /// [`edge_margins`], once needed.
    margins: Option<[f32; 3]>,
}

impl TriangleCrossing {
    /// The triangle with corners `tri`; `None` if it is degenerate.
    fn new(x: &[Vec3], tri: [u32; 3]) -> Option<Self> {
        let c = tri.map(|k| x[k as usize]);
        let (lo, hi) = bounds(c, 0.0);
        Some(Self {
            corners: tri,
            t: Triangle::new(c)?,
            lo,
            hi,
            margins: None,
        })
    }

    /// Calls `crossing` for every edge of particle `p` that crosses the
    /// triangle, `p` being its nearer end (or as near, and the lower index),
    /// so that each crossing is counted once.
    #[inline]
    fn edges_from(
        &mut self,
        p: u32,
        x: &[Vec3],
        spec: &ClothSpec,
        crossing: &mut impl FnMut([u32; 2], [u32; 3]),
    ) {
        let tri = self.corners;
        if tri.contains(&p) {
            return;
        }
        let xp = x[p as usize];
        let dp = self.t.distance(xp);
        if dp.abs() <= ON_PLANE {
            return;
        }
        for o in edges_at(p, spec) {
            let xo = x[o as usize];
            let d_o = self.t.distance(xo);
            if dp * d_o >= 0.0
                || dp.abs() > d_o.abs()
                || (dp.abs() == d_o.abs() && p > o)
                || tri.contains(&o)
            {
                continue;
            }
            let half = Vec3::splat(0.5 * xp.distance(xo));
            if !(xp.cmpge(self.lo - half).all() && xp.cmple(self.hi + half).all()) {
                continue;
            }
            let t = &self.t;
            let margins = self.margins.get_or_insert_with(|| edge_margins(t));
            if crosses_at(xp, xo, (dp, d_o), t, margins).is_some() {
                crossing([p, o], tri);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_in_lanes_are_the_particles_in_the_box_over_the_grown_triangle() {
        let mut seed = 11u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0
        };
        let reach = 0.01;
        // Coordinates this close to a bound may round either way.
        let near_bound = 1e-4;
        let (mut taken, mut left) = (0, 0);
        for round in 0..2000 {
            // Cells of a 1 cm grid, far from the origin or not, bent.
            let origin =
                Vec3::new(next(), next(), next()) * if round % 2 == 0 { 1.0 } else { 50.0 };
            let a = origin;
            let b = origin + Vec3::new(0.01, 0.002 * next(), 0.004 * next());
            let c = origin + Vec3::new(0.01 * next(), 0.01, 0.004 * next());
            let Some(t) = Triangle::new([a, b, c]) else {
                continue;
            };
            let rim = (round % 8) as u8;
            let Some(lanes) = Candidates::new([a, b, c], rim, reach) else {
                continue;
            };
            // Points in the box grown by a little more than the reach: some
            // outside it.
            let (lo, hi) = bounds([a, b, c], 1.2 * reach);
            let points: [Vec3; LANES] = std::array::from_fn(|_| {
                lo + (hi - lo) * (Vec3::new(next(), next(), next()) * 0.5 + 0.5)
            });
            let hits = lanes.of(V3::gather(&points, &each(|k| k as u32)));
            let (lo, hi) = bounds([a, b, c], reach);
            for (k, &x) in points.iter().enumerate() {
                let in_box = x.cmpge(lo).all() && x.cmple(hi).all();
                let foot = t.foot(x);
                let hit = hits & (1 << k) != 0;
                if in_box && foot.within(rim, CANDIDATE - near_bound) {
                    taken += 1;
                    assert!(hit, "round {round}: lane {k} dropped a candidate");
                }
                if !in_box || !foot.within(rim, CANDIDATE + near_bound) {
                    left += 1;
                    assert!(!hit, "round {round}: lane {k} took a particle too far");
                }
            }
        }
        assert!(taken > 1000 && left > 1000, "{taken} taken, {left} left");
    }
}
