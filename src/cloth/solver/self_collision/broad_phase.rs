//! Self-collision's broad phase: the particle–triangle pairs near enough
//! to become contacts, kept from substep to substep while the motion
//! allows ([`NearTriangles`], found by sorting the particles along an axis:
//! `prune.rs`), and a spatial hash over particle positions (which particles
//! lie near a box), which the crossing count uses.
//!
//! The hash cuts space into cubic cells of side `cell` (for the crossing
//! count, a rest diagonal). Each particle goes into the cell of its
//! position; cells are hashed into `2^k ≥ 2N` buckets and the particles are
//! counting-sorted by bucket, in index order within a bucket. Building is
//! linear in the number of particles, and a query visits the cells its box
//! overlaps and returns the particles of those cells, each once, in an order
//! fixed by the positions alone, so everything built from it is
//! deterministic.
//!
//! ```ignore
//! let mut hash = SpatialHash::default();
//! hash.build(&positions, spacing);
//! hash.query(lo, hi, |p| { /* p's cell overlaps [lo, hi] */ });
//! ```

use super::prune::{SortedBoxes, widest_axis};
use crate::solver::team;
use glam::{I64Vec3, IVec3, Vec3};

/// Which particles lie near each triangle of a mesh: every particle inside
/// the triangle's bounding box grown by `reach + skin`, found among the
/// particles sorted along an axis ([`SortedBoxes`]) and then kept (a Verlet
/// list) until the particles have moved too far for it to hold.
///
/// **Why it holds.** A box test is a test per axis, so it does not change
/// when every particle moves by the same vector. Let `δ` be how far, per
/// axis, the particles have moved since the search beyond their common
/// motion (half the spread of their displacements along the axis). Then a
/// particle inside a triangle's box grown by `reach` now was inside the box
/// grown by `reach + 2δ` at the search. So while `2δ < skin` the kept pairs
/// include every pair a new search with `reach` would find. A cloth carried
/// along (a flag on a car) keeps its pairs however fast it goes; a flap, a
/// fold or a turn searches again.
///
/// **Groups.** Consecutive triangles come in groups of [`GROUP`] that share
/// one list: the particles in the union of their grown boxes. A grid
/// cloth lists a cell's two halves one after the other
/// ([`Topology::grid`](super::topology::Topology::grid)), whose boxes are
/// the cell's, so a group's list is each half's: one search and one
/// gather of positions serve both. A list leaves out the corners that
/// every triangle of its group shares (the cell's diagonal); a triangle's
/// other corners may be in it, and its users skip them.
///
/// The particles of each group are kept in ascending order, so what is
/// built from them does not depend on when the last search was.
#[derive(Clone, Debug, Default)]
pub(crate) struct NearTriangles {
    /// The particles, sorted for a search.
    points: SortedBoxes,
    /// Group `g`'s particles are `particles[start[g]..start[g + 1]]`.
    start: Vec<u32>,
    particles: Vec<u32>,
    /// The positions the search was made at; empty: no search yet.
    searched_at: Vec<Vec3>,
    /// The reach and skin of the last search.
    reach_skin: (f32, f32),
    searches: u64,
}

/// Triangles per group of [`NearTriangles`]: a grid cell's two halves.
pub(crate) const GROUP: usize = 2;

/// The groups of `triangles` triangles.
pub(crate) fn groups(triangles: usize) -> usize {
    triangles.div_ceil(GROUP)
}

/// The triangles of group `g`, among `triangles`.
pub(crate) fn group(g: usize, triangles: usize) -> std::ops::Range<usize> {
    g * GROUP..((g + 1) * GROUP).min(triangles)
}

impl NearTriangles {
    /// Makes sure the pairs hold for positions `x`: keeps them if the last
    /// search had the same `reach` and `skin` and the particles have since
    /// moved apart by less than the skin (see the type), else searches
    /// again.
    pub(crate) fn update(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        (reach, skin): (f32, f32),
        threads: usize,
    ) {
        let same =
            self.reach_skin == (reach, skin) && self.start.len() == groups(triangles.len()) + 1;
        if same && self.holds(x) {
            return;
        }
        self.search(x, triangles, (reach, skin), threads);
    }

    /// The particles near the triangles of group `g` ([`group`]), in
    /// ascending order.
    pub(crate) fn of_group(&self, g: usize) -> &[u32] {
        &self.particles[self.start[g] as usize..self.start[g + 1] as usize]
    }

    /// The particles near triangle `t` (those of its group), in ascending
    /// order.
    #[cfg(test)]
    pub(crate) fn of(&self, t: usize) -> &[u32] {
        self.of_group(t / GROUP)
    }

    /// How many searches have been made (the rest of the updates reused one).
    #[cfg(test)]
    fn searches(&self) -> u64 {
        self.searches
    }

    /// Forgets the pairs: the next update searches.
    pub(crate) fn clear(&mut self) {
        self.searched_at.clear();
    }

    /// Whether `2δ` (see the type) is still below the skin, with a tenth of
    /// it to spare for rounding.
    fn holds(&self, x: &[Vec3]) -> bool {
        self.covers(x, self.reach_skin.0)
    }

    /// Whether the kept pairs include every particle inside a triangle's
    /// box grown by `r` at positions `x`: `r + 2δ` within the search's
    /// `reach + skin`, with a tenth of the skin to spare for rounding.
    pub(crate) fn covers(&self, x: &[Vec3], r: f32) -> bool {
        if self.searched_at.len() != x.len() || x.is_empty() {
            return false;
        }
        let spread = spread(x, &self.searched_at);
        let (reach, skin) = self.reach_skin;
        spread.is_finite() && r + spread < reach + 0.9 * skin
    }

    fn search(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        (reach, skin): (f32, f32),
        threads: usize,
    ) {
        let grow = Vec3::splat(reach + skin);
        self.points.build(widest_axis(x), x.iter().map(|&p| (p, p)));
        // Each thread searches its share of the groups; the shares, joined
        // in order, are what one thread would find alone.
        let points = &self.points;
        let shares = team::run(threads, |crew| {
            let (mut particles, mut ends) = (Vec::new(), Vec::new());
            for g in crew.share(groups(triangles.len())) {
                let tris = &triangles[group(g, triangles.len())];
                let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for c in tris.iter().flatten().map(|&k| x[k as usize]) {
                    (lo, hi) = (lo.min(c), hi.max(c));
                }
                let (lo, hi) = (lo - grow, hi + grow);
                let shared = |p: u32| tris.iter().all(|t| t.contains(&p));
                let from = particles.len();
                points.within(lo, hi, |p| {
                    let xp = x[p as usize];
                    if xp.cmpge(lo).all() && xp.cmple(hi).all() && !shared(p) {
                        particles.push(p);
                    }
                });
                particles[from..].sort_unstable();
                ends.push(particles.len() as u32);
            }
            (particles, ends)
        });
        self.start.clear();
        self.particles.clear();
        self.start.push(0);
        for (particles, ends) in shares {
            let base = self.particles.len() as u32;
            self.start.extend(ends.into_iter().map(|end| base + end));
            self.particles.extend(particles);
        }
        self.searched_at.clear();
        self.searched_at.extend_from_slice(x);
        self.reach_skin = (reach, skin);
        self.searches += 1;
    }
}

/// How far apart the particles have moved from `then` to `now`, beyond
/// their common motion: the largest spread of their displacements along an
/// axis (`2δ` of [`NearTriangles`]). NaN if a position is not finite.
fn spread(now: &[Vec3], then: &[Vec3]) -> f32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let mut finite = true;
    for (a, b) in now.iter().zip(then) {
        let d = *a - *b;
        finite &= d.is_finite();
        lo = lo.min(d);
        hi = hi.max(d);
    }
    if finite {
        (hi - lo).max_element().max(0.0)
    } else {
        f32::NAN
    }
}

/// Particles sorted into hashed cells.
#[derive(Clone, Debug, Default)]
pub(crate) struct SpatialHash {
    inv_cell: f32,
    /// `buckets − 1`, a power of two minus one.
    mask: usize,
    /// Where each bucket's particles start in `items` (one more entry than buckets).
    start: Vec<u32>,
    /// The particles, bucket by bucket.
    items: Vec<u32>,
    /// Each particle's cell.
    cells: Vec<IVec3>,
}

impl SpatialHash {
    /// Sorts the particles at `x` into cells of side `cell` (> 0).
    pub(crate) fn build(&mut self, x: &[Vec3], cell: f32) {
        self.inv_cell = cell.recip();
        let buckets = (2 * x.len()).next_power_of_two().max(16);
        self.mask = buckets - 1;
        self.cells.clear();
        let inv_cell = self.inv_cell;
        self.cells.extend(x.iter().map(|&p| cell_of(p, inv_cell)));
        self.start.clear();
        self.start.resize(buckets + 1, 0);
        for &c in &self.cells {
            self.start[bucket(c, self.mask) + 1] += 1;
        }
        for b in 0..buckets {
            self.start[b + 1] += self.start[b];
        }
        self.items.clear();
        self.items.resize(x.len(), 0);
        // `start[b]` runs ahead while bucket b fills, then is moved back.
        let mut next = self.start.clone();
        for (i, &c) in self.cells.iter().enumerate() {
            let b = bucket(c, self.mask);
            self.items[next[b] as usize] = i as u32;
            next[b] += 1;
        }
    }

    /// Calls `f` with every particle whose cell overlaps the box `[lo, hi]`,
    /// each once. A box over more cells than there are particles (a cloth
    /// blown apart, a box reaching infinity) visits every particle instead.
    pub(crate) fn query(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u32)) {
        let (a, b) = (cell_of(lo, self.inv_cell), cell_of(hi, self.inv_cell));
        // In 64 bits: from the lowest cell to the highest, 32 would wrap.
        let span = (b.as_i64vec3() - a.as_i64vec3() + I64Vec3::ONE).max(I64Vec3::ZERO);
        if span.x.saturating_mul(span.y).saturating_mul(span.z) > self.cells.len() as i64 {
            (0..self.cells.len() as u32).for_each(f);
            return;
        }
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let cell = IVec3::new(x, y, z);
                    let b = bucket(cell, self.mask);
                    let range = self.start[b] as usize..self.start[b + 1] as usize;
                    for &p in &self.items[range] {
                        // Other cells share the bucket; each particle is
                        // reported from its own cell only.
                        if self.cells[p as usize] == cell {
                            f(p);
                        }
                    }
                }
            }
        }
    }
}

/// The cell of a point, for cells of side `1 / inv_cell`.
#[inline]
fn cell_of(p: Vec3, inv_cell: f32) -> IVec3 {
    let v = p * inv_cell;
    IVec3::new(floor(v.x), floor(v.y), floor(v.z))
}

/// `⌊v⌋` as an integer, inline (without SSE4.1, `f32::floor` is a library
/// call). Saturating, so a far particle lands in an edge cell.
#[inline(always)]
fn floor(v: f32) -> i32 {
    let t = v as i32;
    t.saturating_sub(i32::from(v < t as f32))
}

/// The bucket of a cell, among `mask + 1`.
#[inline]
fn bucket(c: IVec3, mask: usize) -> usize {
    let h = (c.x as u32).wrapping_mul(73_856_093)
        ^ (c.y as u32).wrapping_mul(19_349_663)
        ^ (c.z as u32).wrapping_mul(83_492_791);
    h as usize & mask
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wavy 12 × 12 grid's points and triangles, moved by `f`.
    fn sheet(f: impl Fn(Vec3) -> Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let n = 12u32;
        let x = (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f32, (k / n) as f32);
                f(Vec3::new(
                    i * 0.1,
                    j * 0.1,
                    0.03 * (i * 0.9).sin() * (j * 0.7).cos(),
                ))
            })
            .collect();
        let mut t = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                t.push([a, a + 1, a + n + 1]);
                t.push([a, a + n + 1, a + n]);
            }
        }
        (x, t)
    }

    /// The particles in triangle `t`'s box grown by `r`, by brute force.
    fn in_box(x: &[Vec3], t: [u32; 3], r: f32) -> Vec<u32> {
        let c = t.map(|k| x[k as usize]);
        let lo = c[0].min(c[1]).min(c[2]) - Vec3::splat(r);
        let hi = c[0].max(c[1]).max(c[2]) + Vec3::splat(r);
        (0..x.len() as u32)
            .filter(|&p| !t.contains(&p))
            .filter(|&p| x[p as usize].cmpge(lo).all() && x[p as usize].cmple(hi).all())
            .collect()
    }

    #[test]
    fn kept_pairs_cover_a_new_search_and_a_carried_cloth_keeps_them() {
        let (reach, skin) = (0.03, 0.1);
        let (x0, tris) = sheet(|p| p);
        let mut near = NearTriangles::default();
        near.update(&x0, &tris, (reach, skin), 1);
        // Carried far (a car's flag): the same pairs, no new search.
        let (x1, _) = sheet(|p| p + Vec3::new(40.0, -3.0, 7.0));
        near.update(&x1, &tris, (reach, skin), 1);
        assert_eq!(near.searches(), 1);
        // Bent a little more than the skin allows: searched again. Bent a
        // little less: kept. Either way every particle in a box grown by the
        // reach is among the kept pairs, in ascending order.
        for (bend, searches) in [(0.04, 1), (0.2, 2)] {
            let (x, _) = sheet(|p| p + Vec3::new(40.0, -3.0, 7.0 + bend * p.x * p.x));
            near.update(&x, &tris, (reach, skin), 2);
            assert_eq!(near.searches(), searches, "bend {bend}");
            // Two threads search exactly what one does.
            let mut alone = NearTriangles::default();
            alone.update(&x, &tris, (reach, skin), 1);
            if searches == 2 {
                assert_eq!(
                    (&alone.start, &alone.particles),
                    (&near.start, &near.particles)
                );
            }
            for (k, &t) in tris.iter().enumerate() {
                let kept = near.of(k);
                assert!(kept.is_sorted());
                for p in in_box(&x, t, reach) {
                    assert!(kept.contains(&p), "triangle {k} lost particle {p}");
                }
                // A cell's diagonal is in neither half's list.
                let group = &tris[group(k / GROUP, tris.len())];
                assert!(kept.iter().all(|p| !group.iter().all(|t| t.contains(p))));
            }
        }
    }

    #[test]
    fn a_query_finds_exactly_the_particles_in_its_cells() {
        let mut x = Vec::new();
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 4.0 - 2.0
        };
        for _ in 0..500 {
            x.push(Vec3::new(next(), next(), next()));
        }
        let mut hash = SpatialHash::default();
        hash.build(&x, 0.3);
        let (lo, hi) = (Vec3::new(-0.5, -0.2, 0.1), Vec3::new(0.4, 0.7, 0.5));
        let mut found = Vec::new();
        hash.query(lo, hi, |p| found.push(p));
        let mut sorted = found.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), found.len(), "a particle was reported twice");
        let cell = |p: Vec3| (p / 0.3).floor();
        let (a, b) = (cell(lo), cell(hi));
        let expected: Vec<u32> = (0..x.len() as u32)
            .filter(|&i| {
                let c = cell(x[i as usize]);
                c.cmpge(a).all() && c.cmple(b).all()
            })
            .collect();
        assert_eq!(sorted, expected);
    }

    #[test]
    fn a_query_reaching_infinity_visits_every_particle_once() {
        let x: Vec<Vec3> = (0..50).map(|k| Vec3::splat(k as f32 * 0.1)).collect();
        let mut hash = SpatialHash::default();
        hash.build(&x, 0.3);
        let mut found = Vec::new();
        hash.query(Vec3::NEG_INFINITY, Vec3::INFINITY, |p| found.push(p));
        assert_eq!(found, (0..50).collect::<Vec<u32>>());
    }
}
