//! Time stamps.

use serde::{Deserialize, Serialize};

/// A time stamp in integer nanoseconds since an arbitrary epoch (Unix time for ROS logs,
/// log start for relative CARMEN logs). Integer so that equal stamps compare equal and
/// ordering is exact; `i64` nanoseconds span ±292 years.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Stamp(pub i64);

impl Stamp {
    /// The epoch.
    pub const ZERO: Stamp = Stamp(0);

    /// From seconds (rounded to the nearest nanosecond). `None` when not finite or out of range.
    pub fn from_secs_f64(s: f64) -> Option<Stamp> {
        let ns = (s * 1e9).round();
        (ns.is_finite() && ns.abs() < 9.2e18).then_some(Stamp(ns as i64))
    }

    /// Parses a decimal number of seconds (`"1134864629.895182"`, `"-0.042"`, `"12"`)
    /// exactly, digit by digit: going through `f64` would lose the microseconds of a Unix
    /// stamp (an `f64` near 1.1e9 s resolves only ~0.24 µs and rounds the product).
    /// Digits beyond nanoseconds are truncated. `None` when it is not such a number.
    pub fn parse_decimal(s: &str) -> Option<Stamp> {
        let (neg, body) = match s.as_bytes().first()? {
            b'-' => (true, &s[1..]),
            b'+' => (false, &s[1..]),
            _ => (false, s),
        };
        let (int, frac) = body.split_once('.').unwrap_or((body, ""));
        if int.is_empty() && frac.is_empty() {
            return None;
        }
        if !int.bytes().all(|b| b.is_ascii_digit()) || !frac.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let secs: i64 = if int.is_empty() { 0 } else { int.parse().ok()? };
        let mut nanos: i64 = 0;
        for (i, b) in frac.bytes().take(9).enumerate() {
            nanos += (b - b'0') as i64 * 10i64.pow(8 - i as u32);
        }
        let v = secs.checked_mul(1_000_000_000)?.checked_add(nanos)?;
        Some(Stamp(if neg { -v } else { v }))
    }

    /// From ROS `sec` + `nanosec` fields.
    pub fn from_sec_nsec(sec: i64, nsec: u32) -> Stamp {
        Stamp(sec.saturating_mul(1_000_000_000).saturating_add(nsec as i64))
    }

    /// Seconds as `f64`.
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 * 1e-9
    }

    /// `self - earlier` in seconds, exact in the integer difference for any two stamps (a
    /// 584-year gap between extreme stamps does not wrap round to a short one).
    pub fn secs_since(self, earlier: Stamp) -> f64 {
        (i128::from(self.0) - i128::from(earlier.0)) as f64 * 1e-9
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_of_extreme_stamps_do_not_wrap() {
        assert_eq!(Stamp(i64::MAX).secs_since(Stamp(i64::MIN)), (u64::MAX as f64) * 1e-9);
        assert!(Stamp(i64::MIN).secs_since(Stamp(i64::MAX)) < -1.8e10);
        assert_eq!(Stamp(3_000_000_000).secs_since(Stamp(1_000_000_000)), 2.0);
    }

    #[test]
    fn conversions() {
        assert_eq!(Stamp::from_secs_f64(1.5), Some(Stamp(1_500_000_000)));
        assert_eq!(Stamp::from_secs_f64(f64::NAN), None);
        assert_eq!(Stamp::from_sec_nsec(2, 5), Stamp(2_000_000_005));
        assert!((Stamp(2_500_000_000).secs_since(Stamp(1_000_000_000)) - 1.5).abs() < 1e-12);
        // Unix stamps of the SLAM-benchmark logs keep their microseconds exactly.
        assert_eq!(Stamp::parse_decimal("1134864629.895182"), Some(Stamp(1_134_864_629_895_182_000)));
        assert_eq!(Stamp::parse_decimal("-0.042"), Some(Stamp(-42_000_000)));
        assert_eq!(Stamp::parse_decimal("12"), Some(Stamp(12_000_000_000)));
        assert_eq!(Stamp::parse_decimal(".5"), Some(Stamp(500_000_000)));
        assert_eq!(Stamp::parse_decimal("0.1234567891"), Some(Stamp(123_456_789)));
        for bad in ["", "-", ".", "1e5", "nan", "1.2.3", "0x10", " 1"] {
            assert_eq!(Stamp::parse_decimal(bad), None, "{bad}");
        }
    }
}
