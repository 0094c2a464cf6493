//! Repeated scans: the same message twice in a log (a bag recorded from two bridges, a
//! CARMEN line pasted twice, chunks written twice by a buggy recorder) is one observation,
//! and must be inserted once — twice would count its evidence as two independent looks.
//!
//! A scan repeats the one before it on its topic when both carry the same header stamp
//! and the same ranges, bit for bit. Scans reach the map in stamp order, so a repeat
//! follows its original.

use fusemap_core::time::Stamp;
use fusemap_io::log::ScanMessage;

/// Remembers the last scan of one topic.
#[derive(Debug, Default)]
pub struct RepeatFilter {
    last: Option<(Stamp, Vec<u32>)>,
}

impl RepeatFilter {
    /// True when `msg` repeats the scan seen before it; otherwise it becomes the one
    /// the next is compared with.
    pub fn is_repeat(&mut self, msg: &ScanMessage) -> bool {
        let stamp = msg.scan.stamp;
        let ranges = &msg.scan.ranges;
        if let Some((s, bits)) = &self.last {
            if *s == stamp && bits.len() == ranges.len() && bits.iter().zip(ranges).all(|(b, r)| *b == r.to_bits()) {
                return true;
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
}
