//! A spatial hash over particle positions: which particles lie near a box.
//!
//! Space is cut into cubic cells of side `cell` (the self-collision family
//! uses a little more than the cloth's rest spacing, so that a triangle's
//! box overlaps at most two cells along each axis). Each particle goes into the cell of its
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

use glam::{IVec3, Vec3};

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
    /// blown apart) visits every particle instead.
    pub(crate) fn query(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u32)) {
        let (a, b) = (cell_of(lo, self.inv_cell), cell_of(hi, self.inv_cell));
        let span = (b - a + IVec3::ONE).max(IVec3::ZERO).as_i64vec3();
        if span.x * span.y * span.z > self.cells.len() as i64 {
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
/// call). `as` saturates, so a far particle lands in an edge cell.
#[inline(always)]
fn floor(v: f32) -> i32 {
    let t = v as i32;
    t - i32::from(v < t as f32)
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
}
