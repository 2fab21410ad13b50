//! Sort and prune: which axis-aligned boxes overlap, found by sorting them
//! along one axis.
//!
//! The boxes are sorted by their lower end along the axis the particles
//! spread farthest along; two boxes can only overlap if, along it, the
//! later one starts before the earlier one ends. So each box is compared
//! with the boxes after it in that order until one starts beyond its end,
//! and those are tested along the two other axes. The numbers are kept in
//! arrays per axis, in sorted order, so the scan reads memory straight
//! through.
//!
//! For a cloth this beats a spatial hash at the near pairs' reach (a rest
//! spacing and a half): most boxes a hash cell hands out are then near
//! anyway, and a sorted scan visits each at the cost of two comparisons.
//! The pairs reported depend on the boxes alone, not on the order of the
//! scan (which follows the positions), so what is built from them, in an
//! order of its own, is deterministic.

use glam::Vec3;

/// Boxes compared at a time.
const LANES: usize = 8;
type Lanes = wide::f32x8;

/// Boxes sorted by their lower end along one axis.
#[derive(Clone, Debug, Default)]
pub(crate) struct SortedBoxes {
    /// The axis sorted along (0, 1, 2: x, y, z).
    axis: usize,
    /// Each sorted box's index among the boxes given.
    id: Vec<u32>,
    /// The boxes' ends along the sorted axis, then along the two others.
    lo: Vec<f32>,
    hi: Vec<f32>,
    lo_b: Vec<f32>,
    hi_b: Vec<f32>,
    lo_c: Vec<f32>,
    hi_c: Vec<f32>,
    /// The longest box along the sorted axis.
    longest: f32,
    /// Scratch for the sort.
    order: Vec<(f32, u32)>,
}

impl SortedBoxes {
    /// Sorts `boxes` (`(lo, hi)`, finite) along `axis`; ties in their
    /// given order.
    pub(crate) fn build(
        &mut self,
        axis: usize,
        boxes: impl ExactSizeIterator<Item = (Vec3, Vec3)>,
    ) {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        self.axis = axis;
        self.order.clear();
        let n = boxes.len();
        let (mut lo, mut hi) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (i, (l, h)) in boxes.enumerate() {
            self.order.push((l[axis], i as u32));
            lo.push(l);
            hi.push(h);
        }
        self.order
            .sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
        self.id.clear();
        self.id.extend(self.order.iter().map(|&(_, i)| i));
        let ends = |v: &Vec<Vec3>, k: usize, out: &mut Vec<f32>| {
            out.clear();
            out.extend(self.id.iter().map(|&i| v[i as usize][k]));
        };
        ends(&lo, axis, &mut self.lo);
        ends(&hi, axis, &mut self.hi);
        ends(&lo, b, &mut self.lo_b);
        ends(&hi, b, &mut self.hi_b);
        ends(&lo, c, &mut self.lo_c);
        ends(&hi, c, &mut self.hi_c);
        self.longest = self
            .lo
            .iter()
            .zip(&self.hi)
            .fold(0.0f32, |m, (l, h)| m.max(h - l));
        // Boxes beyond every end close the last eight's scan.
        for v in [&mut self.lo, &mut self.lo_b, &mut self.lo_c] {
            v.extend([f32::INFINITY; LANES]);
        }
        for v in [&mut self.hi, &mut self.hi_b, &mut self.hi_c] {
            v.extend([f32::NEG_INFINITY; LANES]);
        }
    }

    /// Which of the eight sorted boxes from `j` overlap `[lo, hi]` along
    /// the two other axes and start along the sorted one no later than
    /// `end` (a bit per box, lowest first), and whether the scan goes on
    /// past them (the last starts no later than `end`).
    #[inline(always)]
    fn eight(&self, j: usize, end: f32, lo: [f32; 2], hi: [f32; 2]) -> (u32, bool) {
        let at = |v: &[f32]| Lanes::new(v[j..j + LANES].try_into().expect("eight"));
        let first = at(&self.lo);
        let hit = first.simd_le(Lanes::splat(end))
            & at(&self.lo_b).simd_le(Lanes::splat(hi[0]))
            & at(&self.hi_b).simd_ge(Lanes::splat(lo[0]))
            & at(&self.lo_c).simd_le(Lanes::splat(hi[1]))
            & at(&self.hi_c).simd_ge(Lanes::splat(lo[1]));
        (hit.to_bitmask(), self.lo[j + LANES - 1] <= end)
    }

    /// How many boxes there are.
    pub(crate) fn len(&self) -> usize {
        self.id.len()
    }

    /// Calls `f(k)` for every sorted position `k` from `from` on whose box
    /// overlaps `[lo, hi]` along the two other axes, and starts no later
    /// than `end` along the sorted one, until the boxes start beyond it.
    #[inline(always)]
    fn scan(&self, from: usize, end: f32, lo: [f32; 2], hi: [f32; 2], mut f: impl FnMut(usize)) {
        let mut j = from;
        while j < self.id.len() {
            let (mut hit, more) = self.eight(j, end, lo, hi);
            while hit != 0 {
                let k = j + hit.trailing_zeros() as usize;
                if k < self.id.len() {
                    f(k);
                }
                hit &= hit - 1;
            }
            if !more {
                break;
            }
            j += LANES;
        }
    }

    /// Calls `f(a, b)` for every pair of overlapping boxes (by their
    /// indices as given) whose first, in sorted order, is among the sorted
    /// positions `range`: over `0..len()`, every overlapping pair once.
    pub(crate) fn overlapping(&self, range: std::ops::Range<usize>, mut f: impl FnMut(u32, u32)) {
        for i in range {
            let (lo, hi) = ([self.lo_b[i], self.lo_c[i]], [self.hi_b[i], self.hi_c[i]]);
            self.scan(i + 1, self.hi[i], lo, hi, |j| f(self.id[i], self.id[j]));
        }
    }

    /// Calls `f` with every box (its index as given) that overlaps the box
    /// `[lo, hi]`, in sorted order.
    pub(crate) fn within(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(u32)) {
        let (a, b, c) = (self.axis, (self.axis + 1) % 3, (self.axis + 2) % 3);
        let n = self.id.len();
        let first = self.lo[..n].partition_point(|&l| l < lo[a] - self.longest);
        self.scan(first, hi[a], [lo[b], lo[c]], [hi[b], hi[c]], |j| {
            if self.hi[j] >= lo[a] {
                f(self.id[j]);
            }
        });
    }
}

/// The axis along which `x` spreads farthest (0, 1, 2: x, y, z; the first
/// of equals).
pub(crate) fn widest_axis(x: &[Vec3]) -> usize {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &p in x {
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    let d = hi - lo;
    if d.x >= d.y && d.x >= d.z {
        0
    } else if d.y >= d.z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A few hundred boxes of mixed sizes, deterministic.
    fn boxes() -> Vec<(Vec3, Vec3)> {
        let mut s = 12345u32;
        let mut r = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s % 10_000) as f32 / 1000.0
        };
        (0..300)
            .map(|_| {
                let lo = Vec3::new(r(), r(), r());
                (lo, lo + Vec3::new(r(), r(), r()) * 0.15)
            })
            .collect()
    }

    fn overlap(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> bool {
        a.0.cmple(b.1).all() && b.0.cmple(a.1).all()
    }

    #[test]
    fn finds_every_overlapping_pair_once_along_any_axis() {
        let boxes = boxes();
        let mut expected = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if overlap(boxes[i], boxes[j]) {
                    expected.push((i as u32, j as u32));
                }
            }
        }
        assert!(expected.len() > 50, "{}", expected.len());
        for axis in 0..3 {
            let mut sorted = SortedBoxes::default();
            sorted.build(axis, boxes.iter().copied());
            let mut found = Vec::new();
            // In two ranges, as two threads would.
            let half = sorted.len() / 2;
            for range in [0..half, half..sorted.len()] {
                sorted.overlapping(range, |a, b| found.push((a.min(b), a.max(b))));
            }
            found.sort_unstable();
            assert_eq!(found, expected, "axis {axis}");
        }
    }

    #[test]
    fn finds_every_box_a_query_overlaps() {
        let boxes = boxes();
        let mut sorted = SortedBoxes::default();
        sorted.build(
            widest_axis(&[Vec3::ZERO, Vec3::new(1.0, 3.0, 2.0)]),
            boxes.iter().copied(),
        );
        for q in boxes.iter().step_by(7) {
            let q = (q.0 - Vec3::splat(0.3), q.1 + Vec3::splat(0.2));
            let mut found = Vec::new();
            sorted.within(q.0, q.1, |b| found.push(b));
            found.sort_unstable();
            let expected: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&b| overlap(boxes[b as usize], q))
                .collect();
            assert_eq!(found, expected);
        }
    }
}
