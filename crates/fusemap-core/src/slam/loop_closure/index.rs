//! Where things are: submap footprints and a spatial hash of points, for "what lies
//! near here" in time independent of the map's size.

use crate::geometry::Point2;
use std::collections::HashMap;

/// Where a submap's nodes lie, in its own frame: for "near" and for the global window.
#[derive(Clone, Copy, Debug, Default)]
pub(in crate::slam) struct Footprint {
    pub(super) sum: (f64, f64),
    pub(super) count: usize,
    pub(super) min: (f64, f64),
    pub(super) max: (f64, f64),
    /// The travel at its first and last node.
    pub(super) first_path_m: f64,
    pub(super) last_path_m: f64,
}

impl Footprint {
    /// Adds a node at `p` (the submap's frame), reached after `path_m` of travel.
    pub(in crate::slam) fn add(&mut self, p: Point2, path_m: f64) {
        self.last_path_m = path_m;
        if self.count == 0 {
            self.first_path_m = path_m;
            (self.min, self.max) = ((p.x, p.y), (p.x, p.y));
        }
        self.sum = (self.sum.0 + p.x, self.sum.1 + p.y);
        self.count += 1;
        self.min = (self.min.0.min(p.x), self.min.1.min(p.y));
        self.max = (self.max.0.max(p.x), self.max.1.max(p.y));
    }

    pub(super) fn centre(&self) -> Point2 {
        let n = self.count.max(1) as f64;
        Point2::new(self.sum.0 / n, self.sum.1 / n)
    }

    /// Half the larger side of the box holding the nodes.
    pub(super) fn half_extent(&self) -> f64 {
        0.5 * (self.max.0 - self.min.0).max(self.max.1 - self.min.1).max(0.0)
    }
}

/// An `f64` ordered by `total_cmp`, for the priority queue.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Ordered(pub(super) f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Ordered {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Points bucketed by a square cell, for "what lies within r of here" in time independent
/// of the number of points. Buckets hold indices in insertion order.
#[derive(Debug, Default)]
pub(super) struct SpatialHash {
    cell: f64,
    buckets: HashMap<(i64, i64), Vec<usize>>,
}

impl SpatialHash {
    pub(super) fn new(cell: f64) -> Self {
        Self { cell, buckets: HashMap::new() }
    }

    pub(super) fn key(&self, p: Point2) -> (i64, i64) {
        ((p.x / self.cell).floor() as i64, (p.y / self.cell).floor() as i64)
    }

    pub(super) fn insert(&mut self, i: usize, p: Point2) {
        if p.is_finite() {
            let k = self.key(p);
            self.buckets.entry(k).or_default().push(i);
        }
    }

    /// Indices whose cell lies within `r` of `p` (a superset of the points within `r`),
    /// sorted.
    pub(super) fn near(&self, p: Point2, r: f64) -> Vec<usize> {
        if !p.is_finite() || !r.is_finite() {
            return Vec::new();
        }
        let k = self.key(p);
        let span = (r / self.cell).ceil().min(1e4) as i64 + 1;
        let mut out = Vec::new();
        // Few buckets when the span is large but the map small: walk the buckets instead.
        if ((2 * span + 1) * (2 * span + 1)) as usize > self.buckets.len() {
            for (key, v) in &self.buckets {
                // `abs_diff`: keys of poses 10¹⁹ m out saturate at i64's ends.
                if key.0.abs_diff(k.0) <= span as u64 && key.1.abs_diff(k.1) <= span as u64 {
                    out.extend(v);
                }
            }
        } else {
            for dy in -span..=span {
                for dx in -span..=span {
                    let Some(key) = k.0.checked_add(dx).zip(k.1.checked_add(dy)) else { continue };
                    if let Some(v) = self.buckets.get(&key) {
                        out.extend(v);
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_at_the_ends_of_the_key_range_are_found_without_overflow() {
        let mut h = SpatialHash::new(10.0);
        h.insert(0, Point2::new(0.0, 0.0));
        h.insert(1, Point2::new(1e300, -1e300));
        h.insert(2, Point2::new(-1e300, 1e300));
        // Few buckets: the walk over the buckets.
        assert_eq!(h.near(Point2::new(1e300, -1e300), 50.0), vec![1]);
        assert_eq!(h.near(Point2::new(-1e300, 1e300), 50.0), vec![2]);
        // Many buckets: the walk over the cells around the key.
        for i in 3..200 {
            h.insert(i, Point2::new(1000.0 * i as f64, 0.0));
        }
        assert_eq!(h.near(Point2::new(1e300, -1e300), 15.0), vec![1]);
        assert_eq!(h.near(Point2::new(5.0, 5.0), 15.0), vec![0]);
    }
}
