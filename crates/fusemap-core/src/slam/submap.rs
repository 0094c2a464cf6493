//! Submaps: short-lived local maps that scans are matched against (Hess et al. 2016, §III).
//!
//! A submap is a probability grid built from consecutive scans in the local SLAM frame,
//! small enough that the drift inside it is negligible. Two are active at any time: every
//! inserted scan goes into both, scans are matched against the older (which holds more of
//! the surroundings), and when the newer is full the older one — now holding twice that —
//! is finished and kept for loop closure.
//!
//! "Full" is measured in what makes drift: metres driven and radians turned
//! ([`SubmapBounds`]), not in scans. Hess et al. 2016 count range data (90 a submap), which
//! suits a 40 Hz lidar at walking speed; a log with one scan per metre would then build
//! submaps 90 m long, whose far ends disagree by the drift of 90 m. Bounded in metres, a
//! slow keyframe log and a fast lidar get submaps of the same size.
//!
//! Each submap keeps two grids: its occupancy (a probability grid, updated in odds space)
//! and the likelihood field derived from it (`field.rs`), which is what every matcher reads.
//! A finished submap keeps only the field, packed (`packed_grid.rs`): loop closure unpacks
//! it when a search needs it.

use super::field::{self, Crossing, FieldKernel};
use super::grid::{ProbabilityGrid, UpdateTable};
use super::packed_grid::PackedGrid;
use crate::geometry::{Point2, Pose2};
use crate::parallel::join;

/// One submap.
#[derive(Clone, Debug)]
pub struct Submap {
    /// Its frame in the local SLAM frame: the position of its first scan, axes of the
    /// local frame (the grid is axis-aligned in the local frame).
    pub local_pose: Pose2,
    /// The likelihood field scans are matched against, cells in local-frame coordinates
    /// (emptied when the submap is finished: see `packed`).
    pub grid: ProbabilityGrid,
    /// The finished submap's field, packed.
    pub packed: Option<PackedGrid>,
    /// The occupancy the field is derived from (emptied when the submap is finished).
    pub occupancy: ProbabilityGrid,
    /// Scans inserted.
    pub scans: usize,
    /// No more scans go in.
    pub finished: bool,
}

/// When the newer active submap is full.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubmapBounds {
    /// Metres driven since it began.
    pub distance_m: f64,
    /// Radians turned since it began (the sum of the absolute turns).
    pub rotation_rad: f64,
    /// Scans inserted (a robot at rest still adds one every few seconds).
    pub max_scans: usize,
}

/// The two active submaps and the finished ones.
#[derive(Debug)]
pub struct Submaps {
    resolution: f64,
    bounds: SubmapBounds,
    /// Distance and rotation since the newest submap began, and the last scan's pose.
    travel: (f64, f64, Option<Pose2>),
    /// The newest submap is full: the next scan starts another.
    newest_full: bool,
    hit: UpdateTable,
    miss: UpdateTable,
    kernel: FieldKernel,
    /// Scratch for each active submap's field update.
    crossings: [Vec<Crossing>; 2],
    all: Vec<Submap>,
    /// Indices of the active submaps (oldest first).
    active: Vec<usize>,
    /// Farthest a scan may be from an active submap's start, metres (see
    /// [`insert`](Self::insert)).
    reach_m: f64,
    /// Bytes held by the finished submaps' packed fields.
    finished_bytes: usize,
}

/// Beyond twice a submap's length, how much farther a scan may lie from the submap's start
/// before the active submaps are closed rather than grown to reach it, metres: more than
/// any one step between scans of a real log (one scan a metre on the slowest CARMEN logs).
const REACH_MARGIN_M: f64 = 10.0;

impl Submaps {
    /// No submap yet; fields of σ `field_sigma_m`.
    pub fn new(
        resolution: f64,
        bounds: SubmapBounds,
        hit_probability: f32,
        miss_probability: f32,
        field_sigma_m: f64,
    ) -> Self {
        Self {
            resolution,
            bounds: SubmapBounds { max_scans: bounds.max_scans.max(1), ..bounds },
            travel: (0.0, 0.0, None),
            newest_full: false,
            hit: UpdateTable::new(hit_probability),
            miss: UpdateTable::new(miss_probability),
            kernel: FieldKernel::new(field_sigma_m, resolution),
            crossings: [Vec::new(), Vec::new()],
            all: Vec::new(),
            active: Vec::new(),
            reach_m: 2.0 * bounds.distance_m + REACH_MARGIN_M,
            finished_bytes: 0,
        }
    }

    /// Bytes held by every submap's grids: the finished ones' fields and the active ones'
    /// grids with their mirrors and scratch.
    pub fn bytes(&self) -> usize {
        let active: usize = self.active.iter().map(|&i| self.all[i].grid.bytes() + self.all[i].occupancy.bytes()).sum();
        self.finished_bytes + active
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
    /// submap when needed. Returns the indices of the submaps it went into, and those of
    /// the submaps finished by this insertion.
    ///
    /// A scan farther from an active submap's start than a submap's travel allows (after a
    /// long pause in the log, or a pose that came from nowhere) closes the active submaps
    /// and starts a new one: a grid grown to span the gap would need the square of its
    /// length in cells (10¹⁷ m apart, 10³⁷), and would hold nothing between.
    pub fn insert(
        &mut self,
        pose: Pose2,
        origin: Point2,
        hits: &[Point2],
        misses: &[Point2],
    ) -> (Vec<usize>, Vec<usize>) {
        let mut finished = Vec::new();
        let far = |s: &Submap| s.local_pose.translation().distance(pose.translation()) > self.reach_m;
        if self.active.iter().any(|&i| far(&self.all[i])) {
            for i in std::mem::take(&mut self.active) {
                self.finish(i);
                finished.push(i);
            }
        }
        if let Some(last) = self.travel.2 {
            let d = last.inverse().compose(pose);
            self.travel.0 += d.x.hypot(d.y);
            self.travel.1 += d.theta.abs();
        }
        self.travel.2 = Some(pose);
        if self.active.is_empty() || self.newest_full {
            self.newest_full = false;
            self.travel = (0.0, 0.0, Some(pose));
            self.all.push(Submap {
                local_pose: Pose2::new(pose.x, pose.y, 0.0),
                grid: ProbabilityGrid::new(self.resolution),
                occupancy: ProbabilityGrid::new(self.resolution),
                packed: None,
                scans: 0,
                finished: false,
            });
            self.active.push(self.all.len() - 1);
        }
        let (hit, miss, kernel) = (&self.hit, &self.miss, &self.kernel);
        let into_one = |s: &mut Submap, crossings: &mut Vec<Crossing>| {
            crossings.clear();
            s.occupancy.insert_tracking(origin, hits, misses, hit, miss, crossings);
            let occupancy = &s.occupancy;
            field::update(&mut s.grid, kernel, crossings, |x, y| occupancy.probability(x, y) > 0.5);
            s.scans += 1;
        };
        // The two active submaps share nothing: one on each thread.
        let [c0, c1] = &mut self.crossings;
        match self.active[..] {
            [a, b] if a < b => {
                let (older, newer) = self.all.split_at_mut(b);
                join(|| into_one(&mut older[a], c0), || into_one(&mut newer[0], c1));
            }
            _ => {
                for &i in &self.active {
                    into_one(&mut self.all[i], c0);
                }
            }
        }
        let into = self.active.clone();
        // The newest full: the next scan starts a submap, and the older one, which now
        // holds twice as much, is finished.
        let (b, (d, r, _)) = (self.bounds, self.travel);
        let newest = &self.all[*self.active.last().expect("one active at least")];
        self.newest_full = newest.scans >= b.max_scans || d >= b.distance_m || r >= b.rotation_rad;
        if self.newest_full && self.active.len() == 2 {
            let i = self.active.remove(0);
            self.finish(i);
            finished.push(i);
        }
        (into, finished)
    }

    /// Submap `i` takes no more scans: its field is frozen and packed, its occupancy
    /// dropped.
    fn finish(&mut self, i: usize) {
        let s = &mut self.all[i];
        s.finished = true;
        s.grid.freeze();
        let packed = PackedGrid::pack(&s.grid);
        self.finished_bytes += packed.bytes();
        s.packed = Some(packed);
        s.grid = ProbabilityGrid::new(self.resolution);
        s.occupancy = ProbabilityGrid::new(self.resolution);
    }

    /// The field of finished submap `i`, unpacked.
    pub fn finished_field(&self, i: usize) -> ProbabilityGrid {
        self.all[i].packed.as_ref().expect("only a finished submap's field is unpacked").unpack()
    }

    /// A copy of finished submap `i`, appended (tests of the loop search's cost over very
    /// many submaps).
    #[cfg(test)]
    pub(in crate::slam) fn push_copy_of_finished(&mut self, i: usize) -> usize {
        assert!(self.all[i].finished, "only a finished submap is copied");
        self.all.push(self.all[i].clone());
        self.all.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_submaps_overlap_and_the_older_finishes_at_twice_the_size() {
        let bounds = SubmapBounds { distance_m: 1e9, rotation_rad: 1e9, max_scans: 3 };
        let mut s = Submaps::new(0.05, bounds, 0.55, 0.49, 0.05);
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

    #[test]
    fn a_submap_is_full_after_so_many_metres_or_radians_whatever_the_scan_rate() {
        let bounds = SubmapBounds { distance_m: 2.0, rotation_rad: 1.0, max_scans: 1000 };
        let hit = [Point2::new(2.0, 0.3)];
        // 0.1 m a scan and 1 m a scan start their second submap after the same 2 m.
        for step in [0.1, 1.0] {
            let mut s = Submaps::new(0.05, bounds, 0.55, 0.49, 0.05);
            let mut k = 0;
            while s.all().len() < 2 {
                let x = step * k as f64;
                s.insert(Pose2::new(x, 0.0, 0.0), Point2::new(x, 0.0), &hit, &[]);
                k += 1;
            }
            // The first scan past 2 m (rounding may leave the sum a hair short of it).
            let x = s.all()[1].local_pose.x;
            assert!((2.0 - 1e-9..=2.0 + step + 1e-9).contains(&x), "{step}: {x}");
        }
        // Turning on the spot: a new submap every radian.
        let mut s = Submaps::new(0.05, bounds, 0.55, 0.49, 0.05);
        for k in 0..=40 {
            s.insert(Pose2::new(0.0, 0.0, 0.1 * k as f64), Point2::new(0.0, 0.0), &hit, &[]);
        }
        assert_eq!(s.all().len(), 4);
    }

    #[test]
    fn a_scan_far_beyond_the_active_submaps_closes_them_and_starts_anew() {
        let bounds = SubmapBounds { distance_m: 2.0, rotation_rad: 1.0, max_scans: 1000 };
        let hit = [Point2::new(0.5, 0.3)];
        let mut s = Submaps::new(0.05, bounds, 0.55, 0.49, 0.05);
        for k in 0..30 {
            s.insert(Pose2::new(0.1 * k as f64, 0.0, 0.0), Point2::new(0.1 * k as f64, 0.0), &hit, &[]);
        }
        let (before, bytes) = (s.all().len(), s.bytes());
        assert_eq!(before, 2);
        // 10¹⁷ m away: both active submaps are finished, the scan goes into a new one only.
        let far = Pose2::new(1e17, -1e17, 0.0);
        let (into, finished) = s.insert(far, far.translation(), &[Point2::new(1e17 + 0.5, -1e17)], &[]);
        assert_eq!((into, finished), (vec![2], vec![0, 1]));
        assert!(s.all()[..2].iter().all(|m| m.finished));
        // The grids hold what they held (finished: cropped), and the new one a scan's worth.
        assert!(s.bytes() < 2 * bytes, "{} bytes, {bytes} before", s.bytes());
    }
}
