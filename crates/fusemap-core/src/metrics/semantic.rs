//! Semantic accuracy of a map against ground truth.
//!
//! Of the truly occupied cells that the map holds as occupied, the share whose most likely
//! class is the true class, per class. The same cell tolerance as [`TolerantScore`]
//! applies (a wall on a cell border lands in either neighbour): a true cell is *held* when
//! an occupied map cell with semantic evidence lies within `tolerance` cells (Chebyshev),
//! and *matched* when one of those has the true class as its most likely class.
//!
//! [`TolerantScore`]: super::TolerantScore

use crate::grid::CellIndex;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};

/// One class's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ClassAccuracy {
    /// True cells of the class.
    pub truth: usize,
    /// Of those, cells the map holds as occupied with a class.
    pub held: usize,
    /// Of those, cells whose class matches.
    pub matched: usize,
}

impl ClassAccuracy {
    /// `matched / held`, `None` when the map holds none of the class's cells.
    pub fn accuracy(&self) -> Option<f64> {
        (self.held > 0).then(|| self.matched as f64 / self.held as f64)
    }
}

/// Accuracy per class (keyed by the caller's class key) and over all cells.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SemanticAccuracy {
    /// Per class.
    pub classes: BTreeMap<u16, ClassAccuracy>,
    /// Summed over the classes.
    pub total: ClassAccuracy,
}

impl SemanticAccuracy {
    /// Scores `predicted` (the most likely class of each occupied map cell that has
    /// semantic evidence) against `truth` (the class of each truly occupied cell).
    pub fn new(predicted: &HashMap<CellIndex, u16>, truth: &HashMap<CellIndex, u16>, tolerance: i64) -> Self {
        let mut out = SemanticAccuracy::default();
        for (&c, &k) in truth {
            let e = out.classes.entry(k).or_default();
            e.truth += 1;
            let mut held = false;
            let mut matched = false;
            for dy in -tolerance..=tolerance {
                for dx in -tolerance..=tolerance {
                    if let Some(&p) = predicted.get(&CellIndex::new(c.x + dx, c.y + dy)) {
                        held = true;
                        matched |= p == k;
                    }
                }
            }
            e.held += held as usize;
            e.matched += matched as usize;
        }
        for e in out.classes.values() {
            out.total.truth += e.truth;
            out.total.held += e.held;
            out.total.matched += e.matched;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_and_matched_within_the_tolerance() {
        let c = CellIndex::new;
        let truth: HashMap<_, _> = [(c(0, 0), 2), (c(5, 0), 2), (c(10, 0), 4), (c(20, 0), 4)].into();
        // (0,0): predicted one cell off with the right class; (5,0): wrong class;
        // (10,0): right; (20,0): not held.
        let predicted: HashMap<_, _> = [(c(1, 1), 2), (c(5, 0), 3), (c(10, 0), 4)].into();
        let a = SemanticAccuracy::new(&predicted, &truth, 1);
        assert_eq!(a.classes[&2], ClassAccuracy { truth: 2, held: 2, matched: 1 });
        assert_eq!(a.classes[&4], ClassAccuracy { truth: 2, held: 1, matched: 1 });
        assert_eq!(a.classes[&4].accuracy(), Some(1.0));
        assert_eq!(a.total, ClassAccuracy { truth: 4, held: 3, matched: 2 });
        let strict = SemanticAccuracy::new(&predicted, &truth, 0);
        assert_eq!(strict.classes[&2].held, 1);
    }
}
