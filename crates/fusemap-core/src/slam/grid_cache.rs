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
//!
//! A finished submap's field is kept packed (`packed_grid.rs`); the cache holds it
//! unpacked beside its grids, for the refinement that follows a search.

use super::global_match::PrecomputedGrids;
use super::grid::ProbabilityGrid;
use std::collections::VecDeque;

/// A submap's field, unpacked, and its precomputed grids.
struct Held {
    field: ProbabilityGrid,
    grids: PrecomputedGrids,
}

impl Held {
    fn bytes(&self) -> usize {
        self.field.bytes() + self.grids.memory_bytes()
    }
}

/// Unpacked fields and their precomputed grids by submap index, least recently used
/// dropped past a byte budget.
pub struct GridCache {
    grids: Vec<Option<Held>>,
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

    /// Bytes of the fields and grids held now.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Makes room for one more submap (its grids are built on first use).
    pub fn add_submap(&mut self) {
        self.grids.push(None);
    }

    /// Unpacks the field (`field_of`) and builds the grids of every submap of `needed` not
    /// held (in parallel), makes them the most recently used, and drops the least recently
    /// used others past the budget: every one of `needed` can then be
    /// [`peek`](Self::peek)ed, however small the budget.
    pub fn prepare(&mut self, needed: &[usize], field_of: impl Fn(usize) -> ProbabilityGrid + Sync) {
        let missing: Vec<usize> = needed.iter().copied().filter(|&s| self.grids[s].is_none()).collect();
        let depth = self.depth;
        let built = crate::parallel::map_all(&missing, |&s| {
            let field = field_of(s);
            let grids = PrecomputedGrids::new(&field, depth);
            Held { field, grids }
        });
        for (s, g) in missing.into_iter().zip(built) {
            self.bytes += g.bytes();
            self.grids[s] = Some(g);
            self.built += 1;
        }
        self.peak_bytes = self.peak_bytes.max(self.bytes);
        for &s in needed {
            if let Some(i) = self.recent.iter().position(|&x| x == s) {
                self.recent.remove(i);
            }
            self.recent.push_back(s);
        }
        let mut k = 0;
        while self.bytes > self.budget && k < self.recent.len() {
            let old = self.recent[k];
            if needed.contains(&old) {
                k += 1;
                continue;
            }
            self.recent.remove(k);
            if let Some(g) = self.grids[old].take() {
                self.bytes -= g.bytes();
            }
        }
    }

    /// The field of submap `s` and its grids, if held.
    pub fn peek(&self, s: usize) -> Option<(&ProbabilityGrid, &PrecomputedGrids)> {
        self.grids.get(s)?.as_ref().map(|h| (&h.field, &h.grids))
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
        g.freeze();
        g
    }

    #[test]
    fn the_budget_drops_the_least_recently_used_and_rebuilds_the_same_grids() {
        let grids: Vec<ProbabilityGrid> = (0..4).map(grid).collect();
        // A field and its grids (the fields here are all the same size).
        let one = PrecomputedGrids::new(&grids[0], 4).memory_bytes() + grids[0].bytes();
        let mut c = GridCache::new(2 * one + one / 2, 4);
        (0..4).for_each(|_| c.add_submap());
        let of = |s: usize| grids[s].clone();
        c.prepare(&[0], of);
        let first = c.peek(0).unwrap().1.memory_bytes();
        assert_eq!(c.peek(0).unwrap().0.values(), grids[0].values());
        c.prepare(&[1], of);
        c.prepare(&[0], of); // 0 is now more recent than 1
        c.prepare(&[2], of); // over budget: 1 goes
        assert_eq!(c.built, 3);
        assert!(c.peek(1).is_none() && c.peek(0).is_some() && c.peek(2).is_some());
        // At most the budget plus the grid just built, before the oldest is dropped.
        assert!(c.peak_bytes <= 3 * one && c.bytes <= 2 * one + one / 2, "{} {}", c.peak_bytes, c.bytes);
        c.prepare(&[0], of);
        assert_eq!(c.built, 3, "0 was kept");
        c.prepare(&[1], of);
        assert_eq!(c.built, 4, "1 was dropped and is rebuilt");
        assert_eq!(c.peek(0).unwrap().1.memory_bytes(), first);
        // A batch keeps every grid it needs, whatever the budget.
        let mut tiny = GridCache::new(0, 4);
        (0..3).for_each(|_| tiny.add_submap());
        tiny.prepare(&[0, 1, 2], of);
        assert!((0..3).all(|s| tiny.peek(s).is_some()));
        tiny.prepare(&[2], of);
        assert!(tiny.peek(0).is_none() && tiny.peek(2).is_some());
    }
}
