//! Agreement of a map's occupied cells with ground truth.

use serde::{Deserialize, Serialize};

/// Counts of a binary classification against ground truth (occupied = positive).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Confusion {
    /// Predicted occupied, truly occupied.
    pub true_positive: u64,
    /// Predicted occupied, truly free.
    pub false_positive: u64,
    /// Predicted not occupied, truly occupied.
    pub false_negative: u64,
    /// Predicted not occupied, truly not occupied.
    pub true_negative: u64,
}

impl Confusion {
    /// Counts over paired predictions and truths.
    pub fn from_pairs(pairs: impl IntoIterator<Item = (bool, bool)>) -> Self {
        let mut c = Confusion::default();
        for (pred, truth) in pairs {
            match (pred, truth) {
                (true, true) => c.true_positive += 1,
                (true, false) => c.false_positive += 1,
                (false, true) => c.false_negative += 1,
                (false, false) => c.true_negative += 1,
            }
        }
        c
    }

    /// TP / (TP + FP); 1 when nothing was predicted occupied.
    pub fn precision(&self) -> f64 {
        let d = self.true_positive + self.false_positive;
        if d == 0 {
            1.0
        } else {
            self.true_positive as f64 / d as f64
        }
    }

    /// TP / (TP + FN); 1 when nothing is truly occupied.
    pub fn recall(&self) -> f64 {
        let d = self.true_positive + self.false_negative;
        if d == 0 {
            1.0
        } else {
            self.true_positive as f64 / d as f64
        }
    }

    /// Harmonic mean of precision and recall.
    pub fn f1(&self) -> f64 {
        let (p, r) = (self.precision(), self.recall());
        if p + r == 0.0 {
            0.0
        } else {
            2.0 * p * r / (p + r)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scores() {
        let c = Confusion::from_pairs([(true, true), (true, false), (false, true), (false, false), (true, true)]);
        assert_eq!(c, Confusion { true_positive: 2, false_positive: 1, false_negative: 1, true_negative: 1 });
        assert!((c.precision() - 2.0 / 3.0).abs() < 1e-12);
        assert!((c.recall() - 2.0 / 3.0).abs() < 1e-12);
        assert!((c.f1() - 2.0 / 3.0).abs() < 1e-12);
    }
}
