//! Arbitrary sequences of pose-sensor readings into the estimator (EKF, smoother, gates,
//! slip checks, heading initialisation): odometry, gyro rates, headings, GNSS positions
//! and absolute poses, with any stamps and any values (NaN, ±inf, 10³⁰⁸, negative
//! variances, repeated and reversed stamps). `estimate` may refuse with an error, never
//! panic, and an estimate it returns has finite poses.

#![no_main]

use fusemap_core::estimator::{estimate, EstimatorConfig, EstimatorInput, FixQuality};
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::time::{PoseTrack, Stamp, SyncMode};
use libfuzzer_sys::fuzz_target;

#[path = "bytes.rs"]
mod bytes;
use bytes::Bytes;

/// The target's own values, on the shared reader.
trait Values {
    fn f64(&mut self) -> f64;
    fn var(&mut self) -> f64;
}

impl Values for Bytes<'_> {
    /// A value: mostly small and plausible (so that the filter runs far), sometimes any
    /// f64 bit pattern.
    fn f64(&mut self) -> f64 {
        match self.u8() % 8 {
            0 => self.any_f64(),
            1 => 0.0,
            _ => self.small(1000.0),
        }
    }
    fn var(&mut self) -> f64 {
        match self.u8() % 4 {
            0 => self.f64(),
            _ => f64::from(self.u16()) / 1e5,
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let mut inputs = Vec::new();
    let mut t = 1_000_000_000i64;
    while !b.0.is_empty() && inputs.len() < 4096 {
        // Mostly forward in time, sometimes anywhere.
        t = match b.u8() % 16 {
            0 => i64::from(b.u16() as i16) * 1_000_000_000,
            _ => t.saturating_add(i64::from(b.u8()) * 5_000_000),
        };
        let stamp = Stamp(t);
        let input = match b.u8() % 5 {
            0 => EstimatorInput::Odometry {
                stamp,
                pose: Pose2::new(b.f64(), b.f64(), b.f64()),
                covariance: (b.u8() % 2 == 0)
                    .then(|| [[b.var(), 0.0, 0.0], [0.0, b.var(), 0.0], [0.0, 0.0, b.var()]].into()),
            },
            1 => EstimatorInput::Gyro { stamp, yaw_rate: b.f64(), variance: (b.u8() % 2 == 0).then(|| b.var()) },
            2 => EstimatorInput::Heading { stamp, yaw: b.f64(), variance: b.var() },
            3 => EstimatorInput::Position {
                stamp,
                enu: [b.f64(), b.f64()],
                covariance: [[b.var(), 0.0], [0.0, b.var()]].into(),
                antenna: Point2::new(b.f64() / 100.0, b.f64() / 100.0),
                quality: [FixQuality::RtkFixed, FixQuality::Fix, FixQuality::Sbas, FixQuality::Unknown]
                    [usize::from(b.u8() % 4)],
            },
            _ => EstimatorInput::Pose {
                stamp,
                pose: Pose2::new(b.f64(), b.f64(), b.f64()),
                covariance: [[b.var(), 0.0, 0.0], [0.0, b.var(), 0.0], [0.0, 0.0, b.var()]].into(),
            },
        };
        inputs.push(input);
    }
    if let Ok(e) = estimate(&inputs, &EstimatorConfig::default()) {
        for (stamp, pose) in e.samples() {
            assert!(pose.is_finite(), "a non-finite pose at {stamp:?}");
            let _ = PoseTrack::pose_at(&e, stamp, SyncMode::Interpolate);
        }
    }
});
