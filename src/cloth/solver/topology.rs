//! Which particles each constraint family connects, in colour batches.
//!
//! The grid has three kinds of pair:
//! - **structural** edges between direct neighbours along the weft and the warp;
//! - **shear** diagonals across every grid cell (both diagonals);
//! - **bend** triples: pairs two apart along the weft and the warp, with the
//!   particle between them;
//! - and, for facing, every particle's **patch**: the particle with its
//!   neighbours before and after it along the weft and the warp.
//!
//! Each set is graph-coloured: no two constraints in one colour share a
//! particle, so the constraints of a colour can be projected in any order, or
//! in parallel, with the same result. They are stored sorted by colour;
//! `batches` holds the range of each colour. Colouring is greedy in a fixed
//! order, so it is deterministic.

use std::ops::Range;

use glam::Vec3;

use super::cloth::ClothSpec;

/// Two particles joined by a constraint, with their rest distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Distance between them at rest, in metres.
    pub rest: f32,
    /// The cloth's extent across the constraint over its length, `w / L`
    /// (1 on a square grid): a constraint's compliance is divided by it, so
    /// the same cloth is equally stiff at any resolution.
    pub aspect: f32,
}

/// Three particles in a row, two edges long: the ends and the middle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triple {
    /// One end.
    pub a: u32,
    /// The particle between the ends.
    pub mid: u32,
    /// The other end.
    pub b: u32,
    /// Distance between the ends at rest, in metres.
    pub rest: f32,
    /// The cloth's extent across the run over one edge's length (see [`Pair::aspect`]).
    pub aspect: f32,
}

/// A particle and the neighbours its surface normal is taken from: before
/// and after it along the weft (`left`, `right`) and the warp (`down`,
/// `up`), the particle itself in place of a missing one at the border.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// The particle.
    pub at: u32,
    /// Its neighbour before it along the weft (or itself, at the border).
    pub left: u32,
    /// Its neighbour after it along the weft (or itself).
    pub right: u32,
    /// Its neighbour before it along the warp (or itself).
    pub down: u32,
    /// Its neighbour after it along the warp (or itself).
    pub up: u32,
}

impl Patch {
    /// Particle `k`'s patch on `spec`'s grid.
    pub fn of(spec: &ClothSpec, k: usize) -> Self {
        let (i, j) = spec.cell(k);
        let at = |i: u32, j: u32| spec.index(i, j) as u32;
        Self {
            at: k as u32,
            left: at(i.saturating_sub(1), j),
            right: at((i + 1).min(spec.weft - 1), j),
            down: at(i, j.saturating_sub(1)),
            up: at(i, (j + 1).min(spec.warp - 1)),
        }
    }

    /// The normal of the surface around the particle, unnormalised: the
    /// cross product of its chords along the weft and the warp,
    ///
    /// ```text
    /// g = (x(i+1, j) − x(i−1, j)) × (x(i, j+1) − x(i, j−1))
    /// ```
    ///
    /// one-sided at the border. It faces the way every element faced at
    /// rest, and is zero where the chords are parallel or vanish.
    #[inline]
    pub fn surface_normal(&self, x: &[Vec3]) -> Vec3 {
        let at = |i: u32| x[i as usize];
        (at(self.right) - at(self.left)).cross(at(self.up) - at(self.down))
    }
}

/// A constraint's particles, for colouring.
pub trait Touches {
    /// The particles the constraint reads and writes.
    fn particles(&self) -> impl Iterator<Item = u32>;
}

impl Touches for Pair {
    fn particles(&self) -> impl Iterator<Item = u32> {
        [self.a, self.b].into_iter()
    }
}

/// Facing turns the particle's element alone and moves nothing, so the
/// patches of a sweep share no particle they write.
impl Touches for Patch {
    fn particles(&self) -> impl Iterator<Item = u32> {
        std::iter::once(self.at)
    }
}

impl Touches for Triple {
    fn particles(&self) -> impl Iterator<Item = u32> {
        [self.a, self.mid, self.b].into_iter()
    }
}

/// A colour-sorted set of constraints.
#[derive(Clone, Debug, PartialEq)]
pub struct Batched<T> {
    /// The constraints, colour by colour.
    pub items: Vec<T>,
    /// The range of `items` that holds each colour.
    pub batches: Vec<Range<usize>>,
}

impl<T> Default for Batched<T> {
    fn default() -> Self {
        Self {
            items: Vec::new(),
            batches: Vec::new(),
        }
    }
}

/// Weft, warp and shear edges.
pub type PairSet = Batched<Pair>;
/// Bend triples.
pub type TripleSet = Batched<Triple>;

impl<T: Touches + Copy> Batched<T> {
    /// Colours `items` greedily (first colour used by none of its particles)
    /// and sorts them by colour, keeping the original order within a colour.
    /// A grid's sets need at most 6 colours; contacts in a heap of folds may
    /// need more than the 64 of one round, and the rest are coloured in
    /// further rounds, each after the last.
    pub fn coloured(items: Vec<T>, particles: usize) -> Self {
        let mut out = Self {
            items: Vec::with_capacity(items.len()),
            batches: Vec::new(),
        };
        // A bit mask of the colours already used at each particle.
        let mut used = vec![0u64; particles];
        let mut left = items;
        while !left.is_empty() {
            used.fill(0);
            let mut colour_of = Vec::with_capacity(left.len());
            for item in &left {
                let taken = item.particles().fold(0, |m, i| m | used[i as usize]);
                let c = (!taken).trailing_zeros();
                if c < 64 {
                    for i in item.particles() {
                        used[i as usize] |= 1 << c;
                    }
                }
                colour_of.push(c as usize);
            }
            let colours = colour_of
                .iter()
                .filter(|&&c| c < 64)
                .max()
                .map_or(0, |c| c + 1);
            // Counting sort by colour: where each colour's run starts, then
            // each item into the next slot of its colour's run.
            let mut next = vec![0usize; colours + 1];
            for &c in colour_of.iter().filter(|&&c| c < 64) {
                next[c + 1] += 1;
            }
            for c in 0..colours {
                next[c + 1] += next[c];
            }
            let base = out.items.len();
            out.batches
                .extend((0..colours).map(|c| base + next[c]..base + next[c + 1]));
            let mut order = vec![0u32; next[colours]];
            for (i, &c) in colour_of.iter().enumerate().filter(|(_, c)| **c < 64) {
                order[next[c]] = i as u32;
                next[c] += 1;
            }
            out.items.extend(order.iter().map(|&i| left[i as usize]));
            left = left
                .into_iter()
                .zip(colour_of)
                .filter(|(_, k)| *k >= 64)
                .map(|(p, _)| p)
                .collect();
        }
        out
    }

    /// Number of constraints.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// All pair sets of a grid cloth.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    /// Weft and warp neighbours.
    pub structural: PairSet,
    /// Both diagonals of every cell.
    pub shear: PairSet,
    /// Pairs two apart along the weft and the warp, with their middles.
    pub bend: TripleSet,
    /// Every particle's patch, for facing: one colour, in particle order
    /// (patch `k` is particle `k`'s).
    pub patches: Batched<Patch>,
    /// Triangles of the cloth surface (two per cell), for meshes.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle, which of its edges lie on the cloth's border ([`rim`]).
    pub rims: Vec<u8>,
}

/// Which edges of `tri` lie on the border of a `weft × warp` grid: bit `k`
/// for the edge opposite corner `k`.
pub fn rim(tri: [u32; 3], spec: &ClothSpec) -> u8 {
    let (w, h) = (spec.weft, spec.warp);
    let on_border = |a: u32, b: u32| {
        let (ai, aj, bi, bj) = (a % w, a / w, b % w, b / w);
        (ai == bi && (ai == 0 || ai == w - 1)) || (aj == bj && (aj == 0 || aj == h - 1))
    };
    (0..3).fold(0, |m, k| {
        let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
        m | (u8::from(on_border(a, b)) << k)
    })
}

impl Topology {
    /// The topology of a `weft × warp` grid with rest lengths from `spec`'s layout.
    pub fn grid(spec: &ClothSpec) -> Self {
        let (nx, ny) = (spec.weft, spec.warp);
        let n = spec.len();
        let idx = |i: u32, j: u32| spec.index(i, j) as u32;
        let (dx, dy) = spec.spacing();
        // Across over along: a weft edge (along X) stands for a strip dy
        // wide, a warp edge for one dx wide; a diagonal for a square's worth.
        let aspect = |a: (u32, u32), b: (u32, u32)| match (a.0 == b.0, a.1 == b.1) {
            (false, true) => dy / dx,
            (true, false) => dx / dy,
            _ => 1.0,
        };
        let pair = |a: (u32, u32), b: (u32, u32)| Pair {
            a: idx(a.0, a.1),
            b: idx(b.0, b.1),
            rest: spec
                .rest_position(a.0, a.1)
                .distance(spec.rest_position(b.0, b.1)),
            aspect: aspect(a, b),
        };
        let mut structural = Vec::new();
        let mut shear = Vec::new();
        let mut bend = Vec::new();
        let mut triangles = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx {
                    structural.push(pair((i, j), (i + 1, j)));
                }
                if j + 1 < ny {
                    structural.push(pair((i, j), (i, j + 1)));
                }
                if i + 1 < nx && j + 1 < ny {
                    shear.push(pair((i, j), (i + 1, j + 1)));
                    shear.push(pair((i + 1, j), (i, j + 1)));
                    triangles.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                    triangles.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
                }
                if i + 2 < nx {
                    let p = pair((i, j), (i + 2, j));
                    bend.push(Triple {
                        a: p.a,
                        mid: idx(i + 1, j),
                        b: p.b,
                        rest: p.rest,
                        aspect: p.aspect,
                    });
                }
                if j + 2 < ny {
                    let p = pair((i, j), (i, j + 2));
                    bend.push(Triple {
                        a: p.a,
                        mid: idx(i, j + 1),
                        b: p.b,
                        rest: p.rest,
                        aspect: p.aspect,
                    });
                }
            }
        }
        Self {
            structural: PairSet::coloured(structural, n),
            shear: PairSet::coloured(shear, n),
            bend: TripleSet::coloured(bend, n),
            patches: Batched::coloured((0..n).map(|k| Patch::of(spec, k)).collect(), n),
            rims: triangles.iter().map(|&t| rim(t, spec)).collect(),
            triangles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether no two constraints of any colour share a particle.
    fn colours_are_independent<T: Touches>(set: &Batched<T>, particles: usize) -> bool {
        set.batches.iter().all(|range| {
            let mut seen = vec![false; particles];
            set.items[range.clone()]
                .iter()
                .flat_map(|c| c.particles())
                .all(|i| !std::mem::replace(&mut seen[i as usize], true))
        })
    }

    #[test]
    fn grid_sets_are_complete_and_their_colours_independent() {
        let sizes = [(1, 1), (2, 3), (3, 2), (5, 4), (7, 7), (24, 16), (64, 64)];
        for (nx, ny) in sizes {
            let spec = ClothSpec {
                weft: nx,
                warp: ny,
                ..ClothSpec::default()
            };
            let t = Topology::grid(&spec);
            let (nx, ny) = (nx as usize, ny as usize);
            let n = nx * ny;
            assert_eq!(t.structural.len(), (nx - 1) * ny + nx * (ny - 1));
            assert_eq!(t.shear.len(), 2 * (nx - 1) * (ny - 1));
            assert_eq!(
                t.bend.len(),
                nx.saturating_sub(2) * ny + nx * ny.saturating_sub(2)
            );
            for set in [&t.structural, &t.shear] {
                assert!(colours_are_independent(set, n), "{nx} × {ny}");
                assert_eq!(set.batches.last().map_or(0, |b| b.end), set.len());
            }
            assert!(colours_are_independent(&t.bend, n), "{nx} × {ny}");
            assert_eq!(t.patches.batches, vec![0..n], "{nx} × {ny}");
            assert!(
                t.patches
                    .items
                    .iter()
                    .enumerate()
                    .all(|(k, p)| p.at as usize == k)
            );
            assert!(t.structural.batches.len() <= 4 && t.bend.batches.len() <= 6);
        }
    }
}
