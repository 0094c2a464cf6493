//! Arbitrary scans into SLAM: any stamps (repeated, reversed), track poses (missing,
//! NaN, 10¹⁷ m, jumping), sensor origins and points (NaN, far, all in one place), and GNSS
//! position fixes. Adding scans and finishing may not panic, whatever the input, and must
//! keep its grids small: every scan's final pose is finite.

#![no_main]

use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::slam::{PositionFix, ScanInput, Slam, SlamParams};
use fusemap_core::time::Stamp;
use libfuzzer_sys::fuzz_target;

#[path = "bytes.rs"]
mod bytes;
use bytes::Bytes;

/// The target's own values, on the shared reader.
trait Values {
    fn f64(&mut self) -> f64;
}

impl Values for Bytes<'_> {
    fn f64(&mut self) -> f64 {
        match self.u8() % 16 {
            0 => self.any_f64(),
            1 => 1e17,
            2 => -1e17,
            _ => self.small(2000.0),
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let mut slam = Slam::new(SlamParams::default());
    let mut fixes = Vec::new();
    let (mut t, mut scans) = (1_000_000_000i64, 0usize);
    let mut pose = Pose2::IDENTITY;
    while !b.0.is_empty() && scans < 300 {
        t = match b.u8() % 16 {
            0 => t,
            1 => i64::from(b.u16()) * 1_000_000_000,
            _ => t.saturating_add(100_000_000),
        };
        // A track that mostly moves a little, sometimes jumps anywhere or is missing.
        pose = match b.u8() % 8 {
            0 => Pose2::new(b.f64(), b.f64(), b.f64()),
            1 => pose,
            _ => pose.compose(Pose2::new(f64::from(b.u8()) / 500.0, 0.0, (f64::from(b.u8()) - 128.0) / 1000.0)),
        };
        let track = (b.u8() % 8 != 0).then_some(pose);
        // A room of points around the sensor, some of them anything.
        let n = usize::from(b.u8() % 64) * 4;
        let room: Vec<Point2> = (0..n)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / n.max(1) as f64;
                let r = 2.0 + (k % 7) as f64 * 0.3;
                Point2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let mut hits = room;
        for _ in 0..b.u8() % 4 {
            hits.push(Point2::new(b.f64(), b.f64()));
        }
        let origin = if b.u8() % 32 == 0 { Point2::new(b.f64(), b.f64()) } else { Point2::new(0.0, 0.0) };
        slam.add_scan(ScanInput { stamp: Stamp(t), track, origin, hits: &hits, misses: &[] });
        scans += 1;
        if b.u8() % 16 == 0 {
            fixes.push(PositionFix {
                stamp: Stamp(t),
                position: Point2::new(b.f64(), b.f64()),
                covariance: [[f64::from(b.u8()) / 10.0, 0.0], [0.0, f64::from(b.u8()) / 10.0]],
                antenna: Point2::new(0.0, 0.0),
                track: track.map(|p| (p, [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.001]])),
                correlation_time_s: 1.0,
            });
        }
    }
    slam.add_fixes(&fixes);
    let result = slam.finish();
    for (stamp, p) in &result.trajectory {
        assert!(p.is_finite(), "a non-finite pose at {stamp:?}");
    }
    assert!(result.report.submap_peak_bytes < 1 << 30, "{} bytes of submaps", result.report.submap_peak_bytes);
});
