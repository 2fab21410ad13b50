//! A family's violation, max and RMS over its constraints, and the
//! [`Tally`] it is counted in: tallies of consecutive blocks merge in block
//! order, so the figure does not depend on the threads that counted it.

/// Max and RMS of a family's violation over its pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Violation {
    /// Largest violation.
    pub max: f32,
    /// Root mean square of the violations.
    pub rms: f32,
}

impl Violation {
    /// Max and RMS of some violations (0 for none).
    pub fn of(values: impl Iterator<Item = f32>) -> Self {
        let mut t = Tally::default();
        values.for_each(|v| t.add(v));
        t.violation()
    }
}

/// A running max and sum of squares, from which a [`Violation`] is read.
/// Tallies of consecutive runs of values merge, so a long list can be
/// tallied in blocks on several threads: merged in block order, the result
/// does not depend on the threads.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Tally {
    max: f32,
    sum: f64,
    n: usize,
}

impl Tally {
    /// Counts one violation.
    #[inline]
    pub(crate) fn add(&mut self, v: f32) {
        self.max = self.max.max(v);
        self.sum += (v as f64) * (v as f64);
        self.n += 1;
    }

    /// Counts the values `other` counted, after this one's.
    pub(crate) fn merge(&mut self, other: Tally) {
        self.max = self.max.max(other.max);
        self.sum += other.sum;
        self.n += other.n;
    }

    /// Max and RMS of the values counted (0 for none).
    pub(crate) fn violation(&self) -> Violation {
        Violation {
            max: self.max,
            rms: if self.n == 0 {
                0.0
            } else {
                (self.sum / self.n as f64).sqrt() as f32
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tallies_merged_in_blocks_equal_one_tally() {
        let values: Vec<f32> = (0..1000).map(|k| (k as f32 * 0.37).sin().abs()).collect();
        let whole = Violation::of(values.iter().copied());
        let mut merged = Tally::default();
        for block in values.chunks(64) {
            let mut t = Tally::default();
            block.iter().for_each(|&v| t.add(v));
            merged.merge(t);
        }
        assert_eq!(merged.violation().max, whole.max);
        assert!((merged.violation().rms - whole.rms).abs() <= 1e-6 * whole.rms);
        assert_eq!(Violation::of(std::iter::empty()), Violation::default());
    }
}
