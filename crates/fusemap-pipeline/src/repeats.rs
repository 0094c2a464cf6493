//! Repeated scans: the same message twice in a log (a bag recorded from two bridges, a
//! CARMEN line pasted twice, chunks written twice by a buggy recorder) is one observation,
//! and must be inserted once — twice would count its evidence as two independent looks.
//!
//! A scan repeats the one before it on its topic when both carry the same header stamp
//! and the same ranges, bit for bit. Scans reach the map in stamp order, so a repeat
//! follows its original.
//!
//! A scan with a new stamp but the ranges of the one before, bit for bit, while the pose
//! track has moved since those ranges were first seen is **frozen**: a driver that keeps
//! publishing its last reading (a stalled USB link, a lidar that lost its motor). No real
//! lidar repeats a few hundred ranges to the bit from two places; drawn at the moving
//! poses it smears one view along the path, and SLAM matching it holds the robot still
//! against every other sensor. At rest the same ranges are a plausible reading of a still
//! scene (a quantised driver), and are kept; so is a scan whose ranges are all one value
//! (every beam without a return in open space reads the same from anywhere).

use fusemap_core::geometry::{normalize_angle, Pose2};
use fusemap_core::time::Stamp;
use fusemap_io::log::ScanMessage;

/// Motion since a reading was first seen past which the same reading is frozen: metres …
const FROZEN_MOTION_M: f64 = 0.1;
/// … or radians.
const FROZEN_TURN_RAD: f64 = 0.035;

/// Remembers the last scan of one topic.
#[derive(Debug, Default)]
pub struct RepeatFilter {
    last: Option<(Stamp, Vec<u32>)>,
    /// The last scan (with a new stamp) had the ranges of the one before it, and they
    /// were not all one value.
    same_ranges: bool,
    /// The pose where the current ranges were first seen.
    anchor: Option<Pose2>,
}

impl RepeatFilter {
    /// True when `msg` repeats the scan seen before it; otherwise it becomes the one
    /// the next is compared with.
    pub fn is_repeat(&mut self, msg: &ScanMessage) -> bool {
        let stamp = msg.scan.stamp;
        let ranges = &msg.scan.ranges;
        if let Some((s, bits)) = &self.last {
            let same = bits.len() == ranges.len() && bits.iter().zip(ranges).all(|(b, r)| *b == r.to_bits());
            if *s == stamp && same {
                return true;
            }
            let first = ranges.iter().find(|r| r.is_finite());
            let varied = first.is_some_and(|f| ranges.iter().any(|r| r.is_finite() && r != f));
            self.same_ranges = same && varied;
            // A new reading: the next pose it is seen at anchors it (if this scan gets no
            // pose, the scan after it that repeats the reading does).
            if !self.same_ranges {
                self.anchor = None;
            }
        }
        let bits = match self.last.take() {
            Some((_, mut v)) => {
                v.clear();
                v.extend(ranges.iter().map(|r| r.to_bits()));
                v
            }
            None => ranges.iter().map(|r| r.to_bits()).collect(),
        };
        self.last = Some((stamp, bits));
        false
    }

    /// For the scan [`is_repeat`](Self::is_repeat) has just passed, placed at `pose`:
    /// true when it is frozen (see the module docs).
    pub fn is_frozen(&mut self, pose: Pose2) -> bool {
        match self.anchor {
            Some(a) => {
                let d = a.inverse().compose(pose);
                d.x.hypot(d.y) > FROZEN_MOTION_M || normalize_angle(d.theta).abs() > FROZEN_TURN_RAD
            }
            None => {
                self.anchor = Some(pose);
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(t: i64, ranges: &[f32]) -> ScanMessage {
        fusemap_io::testdata::scan_message(Stamp(t), 0.0, 0.1, f32::NAN, ranges.to_vec())
    }

    #[test]
    fn only_the_same_stamp_and_the_same_ranges_repeat() {
        let mut f = RepeatFilter::default();
        assert!(!f.is_repeat(&scan(1, &[1.0, f32::NAN])));
        // NaN ranges compare by their bits: the same message is a repeat.
        assert!(f.is_repeat(&scan(1, &[1.0, f32::NAN])));
        assert!(f.is_repeat(&scan(1, &[1.0, f32::NAN])));
        // Another reading at the same stamp (two sensors' clocks agreeing) is not.
        assert!(!f.is_repeat(&scan(1, &[1.0, 2.0])));
        assert!(!f.is_repeat(&scan(2, &[1.0, 2.0])));
        assert!(!f.is_repeat(&scan(2, &[1.0])));
    }

    #[test]
    fn the_same_ranges_from_a_moving_robot_are_frozen_and_at_rest_are_not() {
        let mut f = RepeatFilter::default();
        let at = |x: f64| Some(Pose2::new(x, 0.0, 0.0));
        // A scan seen at `pose` (`None`: no pose, as in a gap of the track): frozen?
        let mut see = |t: i64, ranges: &[f32], pose: Option<Pose2>| {
            !f.is_repeat(&scan(t, ranges)) && pose.is_some_and(|p| f.is_frozen(p))
        };
        assert!(!see(1, &[1.0, 2.0], at(0.0)));
        // At rest, and creeping within 10 cm of where the reading was first seen: kept.
        assert!(!see(2, &[1.0, 2.0], at(0.0)));
        assert!(!see(3, &[1.0, 2.0], at(0.05)));
        // The track has moved 30 cm (or turned 5°) and the lidar says the same: frozen.
        assert!(see(4, &[1.0, 2.0], at(0.3)));
        assert!(see(5, &[1.0, 2.0], Some(Pose2::new(0.0, 0.0, 0.09))));
        // A new reading is fresh wherever the robot is, and anchors the next comparison.
        assert!(!see(6, &[1.0, 2.1], at(5.0)));
        assert!(!see(7, &[1.0, 2.1], at(5.05)));
        // Every beam the same (no return anywhere in open space): never frozen.
        assert!(!see(8, &[f32::INFINITY, f32::INFINITY], at(6.0)));
        assert!(!see(9, &[f32::INFINITY, f32::INFINITY], at(9.0)));
        assert!(!see(10, &[2.0, 2.0, f32::NAN], at(10.0)));
        assert!(!see(11, &[2.0, 2.0, f32::NAN], at(12.0)));
        // A new reading whose scan got no pose is anchored where it is next seen, not at
        // the pose of the reading before it.
        assert!(!see(12, &[3.0, 4.0], None));
        assert!(!see(13, &[3.0, 4.0], at(20.0)));
        assert!(see(14, &[3.0, 4.0], at(21.0)));
    }
}
