//! Submaps: short-lived local maps that scans are matched against (Hess et al. 2016, §III).
//!
//! A submap is a probability grid built from a few dozen consecutive scans in the local
//! SLAM frame, small enough that the drift inside it is negligible. Two are active at any
//! time: every inserted scan goes into both, scans are matched against the older (which
//! holds more of the surroundings), and when the newer has taken `scans_per_submap` scans
//! the older one — now holding twice that — is finished and kept for loop closure.

use super::grid::{ProbabilityGrid, UpdateTable};
use crate::geometry::{Point2, Pose2};

/// One submap.
#[derive(Clone, Debug)]
pub struct Submap {
    /// Its frame in the local SLAM frame: the position of its first scan, axes of the
    /// local frame (the grid is axis-aligned in the local frame).
    pub local_pose: Pose2,
    /// The grid, cells in local-frame coordinates.
    pub grid: ProbabilityGrid,
    /// Scans inserted.
    pub scans: usize,
    /// No more scans go in.
    pub finished: bool,
}

/// The two active submaps and the finished ones.
#[derive(Debug)]
pub struct Submaps {
    resolution: f64,
    scans_per_submap: usize,
    hit: UpdateTable,
    miss: UpdateTable,
    all: Vec<Submap>,
    /// Indices of the active submaps (oldest first).
    active: Vec<usize>,
}

impl Submaps {
    /// No submap yet.
    pub fn new(resolution: f64, scans_per_submap: usize, hit_probability: f32, miss_probability: f32) -> Self {
        Self {
            resolution,
            scans_per_submap: scans_per_submap.max(1),
            hit: UpdateTable::new(hit_probability),
            miss: UpdateTable::new(miss_probability),
            all: Vec::new(),
            active: Vec::new(),
        }
    }

    /// Every submap, in creation order.
    pub fn all(&self) -> &[Submap] {
        &self.all
    }

    /// The submap a new scan is matched against (the oldest active one).
    pub fn matching(&self) -> Option<(usize, &Submap)> {
        self.active.first().map(|&i| (i, &self.all[i]))
    }

    /// Inserts a scan (points in the local frame) into the active submaps, starting a new
    /// submap when needed. Returns the indices of the submaps it went into, and the index
    /// of a submap finished by this insertion.
    pub fn insert(
        &mut self,
        pose: Pose2,
        origin: Point2,
        hits: &[Point2],
        misses: &[Point2],
    ) -> (Vec<usize>, Option<usize>) {
        if self.active.is_empty() || self.all[*self.active.last().unwrap()].scans >= self.scans_per_submap {
            self.all.push(Submap {
                local_pose: Pose2::new(pose.x, pose.y, 0.0),
                grid: ProbabilityGrid::new(self.resolution),
                scans: 0,
                finished: false,
            });
            self.active.push(self.all.len() - 1);
        }
        for &i in &self.active {
            let s = &mut self.all[i];
            s.grid.insert(origin, hits, misses, &self.hit, &self.miss);
            s.scans += 1;
        }
        let into = self.active.clone();
        let mut finished = None;
        if self.active.len() > 2
            || (self.active.len() == 2 && self.all[self.active[0]].scans >= 2 * self.scans_per_submap)
        {
            let i = self.active.remove(0);
            self.all[i].finished = true;
            self.all[i].grid.freeze();
            finished = Some(i);
        }
        (into, finished)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_submaps_overlap_and_the_older_finishes_at_twice_the_size() {
        let mut s = Submaps::new(0.05, 3, 0.55, 0.49);
        let hit = [Point2::new(2.0, 0.3)];
        let mut finished = Vec::new();
        let mut into_counts = Vec::new();
        for k in 0..10 {
            let (into, f) = s.insert(Pose2::new(0.1 * k as f64, 0.0, 0.0), Point2::new(0.1 * k as f64, 0.0), &hit, &[]);
            into_counts.push(into.len());
            finished.extend(f);
        }
        assert_eq!(into_counts, vec![1, 1, 1, 2, 2, 2, 2, 2, 2, 2]);
        // Submap 0 took scans 0–5, submap 1 scans 3–8, submap 2 from scan 6.
        assert_eq!(finished, vec![0, 1]);
        assert_eq!(s.all()[0].scans, 6);
        assert!(s.all()[0].finished && !s.all()[2].finished);
        assert_eq!(s.matching().map(|(i, _)| i), Some(2));
        assert!((s.all()[1].local_pose.x - 0.3).abs() < 1e-12);
    }
}
