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

/// Precision, recall and F1 of occupied cells against ground truth with a tolerance of
/// `tolerance` cells (Chebyshev distance): a predicted occupied cell counts as correct
/// when a true occupied cell lies within the tolerance, and a true one as found when a
/// predicted one does — the usual way occupancy maps are scored against a reference, since
/// a wall on a cell border lands in either neighbour.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TolerantScore {
    /// Predicted occupied cells near a true one / predicted occupied cells.
    pub precision: f64,
    /// True occupied cells near a predicted one / true occupied cells.
    pub recall: f64,
    /// Harmonic mean of the two (0 when both are 0).
    pub f1: f64,
    /// Predicted occupied cells.
    pub predicted: usize,
    /// True occupied cells.
    pub truth: usize,
}

impl TolerantScore {
    /// Scores `predicted` against `truth`, both sets of occupied cells.
    pub fn new(
        predicted: &std::collections::HashSet<crate::grid::CellIndex>,
        truth: &std::collections::HashSet<crate::grid::CellIndex>,
        tolerance: i64,
    ) -> Self {
        let near = |c: &crate::grid::CellIndex, set: &std::collections::HashSet<crate::grid::CellIndex>| {
            (-tolerance..=tolerance).any(|dy| {
                (-tolerance..=tolerance).any(|dx| set.contains(&crate::grid::CellIndex { x: c.x + dx, y: c.y + dy }))
            })
        };
        let tp_p = predicted.iter().filter(|c| near(c, truth)).count();
        let tp_t = truth.iter().filter(|c| near(c, predicted)).count();
        let precision = if predicted.is_empty() { 1.0 } else { tp_p as f64 / predicted.len() as f64 };
        let recall = if truth.is_empty() { 1.0 } else { tp_t as f64 / truth.len() as f64 };
        let f1 = if precision + recall > 0.0 { 2.0 * precision * recall / (precision + recall) } else { 0.0 };
        Self { precision, recall, f1, predicted: predicted.len(), truth: truth.len() }
    }
}

#[cfg(test)]
mod tolerant_tests {
    use super::*;
    use crate::grid::CellIndex;
    use std::collections::HashSet;

    fn cells(v: &[(i64, i64)]) -> HashSet<CellIndex> {
        v.iter().map(|&(x, y)| CellIndex { x, y }).collect()
    }

    #[test]
    fn a_wall_one_cell_off_is_found_within_the_tolerance_and_not_without() {
        let truth = cells(&[(0, 0), (1, 0), (2, 0), (3, 0)]);
        let shifted = cells(&[(0, 1), (1, 1), (2, 1), (3, 1)]);
        assert_eq!(TolerantScore::new(&shifted, &truth, 1).f1, 1.0);
        assert_eq!(TolerantScore::new(&shifted, &truth, 0).f1, 0.0);
        // Half the prediction is noise far away: precision 0.5, recall 1.
        let noisy = cells(&[(0, 0), (1, 0), (2, 0), (3, 0), (10, 10), (11, 10), (12, 10), (13, 10)]);
        let s = TolerantScore::new(&noisy, &truth, 1);
        assert_eq!((s.precision, s.recall), (0.5, 1.0));
        assert!((s.f1 - 2.0 / 3.0).abs() < 1e-12);
    }
}
