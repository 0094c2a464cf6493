//! The branch-and-bound grids of finished submaps, held within a memory budget.
//!
//! Each finished submap's max-filtered levels (`PrecomputedGrids`) cost about seven times
//! its grid in bytes, and a submap's grid grows with the range of its returns: held for
//! every submap of a long log they were most of a run's memory (1.2 MiB a submap on the
//! Intel log, over a gigabyte on MIT Killian Court). Loop closures are searched near the
//! robot, so the grids of the submaps searched last are kept and the least recently used
//! dropped past the budget; a dropped one is rebuilt from its submap when a search needs
//! it again. The rebuilt grids are the same bytes, so the search's results do not depend
//! on the budget; only the time does.

use super::global_match::PrecomputedGrids;
use super::grid::ProbabilityGrid;
use std::collections::VecDeque;

/// Precomputed grids by submap index, least recently used dropped past a byte budget.
pub struct GridCache {
    grids: Vec<Option<PrecomputedGrids>>,
    /// Submaps holding grids, least recently used first.
    recent: VecDeque<usize>,
    bytes: usize,
    budget: usize,
    depth: usize,
    /// Grids built (first builds and rebuilds).
    pub built: u64,
    /// The most bytes held at once.
    pub peak_bytes: usize,
}

impl GridCache {
    /// An empty cache of `depth`-level grids holding at most `budget` bytes (always at
    /// least the grid in use).
    pub fn new(budget: usize, depth: usize) -> Self {
        Self { grids: Vec::new(), recent: VecDeque::new(), bytes: 0, budget, depth, built: 0, peak_bytes: 0 }
    }

    /// Makes room for one more submap (its grids are built on first use).
    pub fn add_submap(&mut self) {
        self.grids.push(None);
    }

    /// The grids of submap `s` (built from `grid` if not held), now the most recently used.
    pub fn get(&mut self, s: usize, grid: &ProbabilityGrid) -> &PrecomputedGrids {
        if self.grids[s].is_none() {
            let g = PrecomputedGrids::new(grid, self.depth);
            self.bytes += g.memory_bytes();
            self.grids[s] = Some(g);
            self.built += 1;
            self.peak_bytes = self.peak_bytes.max(self.bytes);
        }
        if let Some(i) = self.recent.iter().position(|&x| x == s) {
            self.recent.remove(i);
        }
        self.recent.push_back(s);
        while self.bytes > self.budget && self.recent.len() > 1 {
            let old = self.recent.pop_front().expect("more than one held");
            if let Some(g) = self.grids[old].take() {
                self.bytes -= g.memory_bytes();
            }
        }
        self.grids[s].as_ref().expect("built above and never dropped: it is the most recent")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::slam::grid::UpdateTable;

    fn grid(k: usize) -> ProbabilityGrid {
        let mut g = ProbabilityGrid::new(0.05);
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let pts: Vec<Point2> = (0..50).map(|i| Point2::new(k as f64 + 0.1 * i as f64, 3.0)).collect();
        g.insert(Point2::new(k as f64, 0.0), &pts, &[], &hit, &miss);
        g
    }

    #[test]
    fn the_budget_drops_the_least_recently_used_and_rebuilds_the_same_grids() {
        let grids: Vec<ProbabilityGrid> = (0..4).map(grid).collect();
        let one = PrecomputedGrids::new(&grids[0], 4).memory_bytes();
        let mut c = GridCache::new(2 * one + one / 2, 4);
        (0..4).for_each(|_| c.add_submap());
        let first = format!("{:?}", c.get(0, &grids[0]).memory_bytes());
        c.get(1, &grids[1]);
        c.get(0, &grids[0]); // 0 is now more recent than 1
        c.get(2, &grids[2]); // over budget: 1 goes
        assert_eq!(c.built, 3);
        // At most the budget plus the grid just built, before the oldest is dropped.
        assert!(c.peak_bytes <= 3 * one && c.bytes <= 2 * one + one / 2, "{} {}", c.peak_bytes, c.bytes);
        c.get(0, &grids[0]);
        assert_eq!(c.built, 3, "0 was kept");
        c.get(1, &grids[1]);
        assert_eq!(c.built, 4, "1 was dropped and is rebuilt");
        assert_eq!(format!("{:?}", c.get(0, &grids[0]).memory_bytes()), first);
        // A budget of nothing still holds the grids in use.
        let mut tiny = GridCache::new(0, 4);
        tiny.add_submap();
        assert!(tiny.get(0, &grids[0]).memory_bytes() > 0);
    }
}
