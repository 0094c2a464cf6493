//! The estimated track and pose look-ups on it.

use super::report::EstimatorReport;
use crate::geometry::Pose2;
use crate::time::{NoPose, Stamp};
use serde::Serialize;

/// One sample of the track.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StateSample {
    /// Time.
    pub stamp: Stamp,
    /// `map_from_base`.
    pub pose: Pose2,
    /// Covariance of (x, y, θ).
    pub covariance: [[f64; 3]; 3],
    /// Gyro bias, rad/s (true rate = measured − bias).
    pub gyro_bias: f64,
    /// Odometry scale (true distance = scale × odometry distance).
    pub odometry_scale: f64,
}

/// The estimator's result: the forward filter's track, the smoothed track, and the report.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// The filter's states (each given the inputs up to its stamp, except the start
    /// heading, which comes from the heading initialisation). The pipeline's estimator
    /// track empties it before mapping (it maps with `smoothed`): there
    /// [`Estimate::filtered_pose_at`] gives [`NoPose::Empty`].
    pub filtered: Vec<StateSample>,
    /// The smoother's states (each given the whole log): the track a mapper should use.
    pub smoothed: Vec<StateSample>,
    /// What was used, rejected and learnt.
    pub report: EstimatorReport,
    /// Longest gap between samples [`Estimate::pose_at`] interpolates across, seconds.
    pub max_gap_s: f64,
}

impl Estimate {
    /// The smoothed pose and covariance at `t`, interpolated between the samples around it
    /// (linear in x, y and the covariance, shortest arc in θ). Outside the track, or
    /// across a gap longer than `max_gap_s`, an explicit [`NoPose`]: never extrapolated.
    pub fn pose_at(&self, t: Stamp) -> Result<(Pose2, [[f64; 3]; 3]), NoPose> {
        lookup(&self.smoothed, t, self.max_gap_s)
    }

    /// The same look-up on the filtered track.
    pub fn filtered_pose_at(&self, t: Stamp) -> Result<(Pose2, [[f64; 3]; 3]), NoPose> {
        lookup(&self.filtered, t, self.max_gap_s)
    }
}

fn lookup(samples: &[StateSample], t: Stamp, max_gap_s: f64) -> Result<(Pose2, [[f64; 3]; 3]), NoPose> {
    let (first, last) = match (samples.first(), samples.last()) {
        (Some(a), Some(b)) => (a, b),
        _ => return Err(NoPose::Empty),
    };
    if t < first.stamp {
        return Err(NoPose::BeforeStart(first.stamp.secs_since(t)));
    }
    if t > last.stamp {
        return Err(NoPose::AfterEnd(t.secs_since(last.stamp)));
    }
    let i = samples.partition_point(|s| s.stamp < t);
    let b = &samples[i];
    if b.stamp == t {
        return Ok((b.pose, b.covariance));
    }
    let a = &samples[i - 1];
    let gap_s = b.stamp.secs_since(a.stamp);
    if gap_s > max_gap_s {
        return Err(NoPose::Gap { gap_s, limit_s: max_gap_s });
    }
    let f = t.secs_since(a.stamp) / gap_s;
    let mut cov = a.covariance;
    for (r, row) in cov.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v += f * (b.covariance[r][c] - *v);
        }
    }
    Ok((a.pose.interpolate(b.pose, f), cov))
}

impl crate::time::PoseTrack for Estimate {
    /// The smoothed track, always interpolated (it is dense: one sample per filter step).
    fn pose_at(&self, t: Stamp, _mode: crate::time::SyncMode) -> Result<Pose2, NoPose> {
        Estimate::pose_at(self, t).map(|p| p.0)
    }

    fn covariance_at(&self, t: Stamp) -> Option<[[f64; 3]; 3]> {
        Estimate::pose_at(self, t).ok().map(|p| p.1)
    }

    fn span(&self) -> Option<(Stamp, Stamp)> {
        Some((self.smoothed.first()?.stamp, self.smoothed.last()?.stamp))
    }

    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        self.smoothed.iter().map(|s| (s.stamp, s.pose)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample(t: f64, x: f64) -> StateSample {
        StateSample {
            stamp: Stamp::from_secs_f64(t).unwrap(),
            pose: Pose2::new(x, 0.0, 0.0),
            covariance: [[x.abs() + 1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            gyro_bias: 0.0,
            odometry_scale: 1.0,
        }
    }

    fn track() -> Vec<StateSample> {
        vec![sample(0.0, 0.0), sample(0.5, 1.0), sample(1.0, 2.0), sample(3.0, 3.0)]
    }

    #[test]
    fn outside_or_across_a_gap_is_refused() {
        let s = track();
        assert!(matches!(lookup(&s, Stamp(-1), 1.0), Err(NoPose::BeforeStart(_))));
        assert!(matches!(lookup(&s, Stamp(3_000_000_001), 1.0), Err(NoPose::AfterEnd(_))));
        assert!(matches!(lookup(&s, Stamp(2_000_000_000), 1.0), Err(NoPose::Gap { .. })));
        assert_eq!(lookup(&[], Stamp(0), 1.0), Err(NoPose::Empty));
        let (p, c) = lookup(&s, Stamp(750_000_000), 1.0).unwrap();
        assert!((p.x - 1.5).abs() < 1e-12 && (c[0][0] - 2.5).abs() < 1e-12);
    }

    proptest! {
        /// Inside the track every answer lies between its two neighbours: no extrapolation.
        #[test]
        fn never_extrapolates(t in -1.0..4.0f64) {
            let s = track();
            let stamp = Stamp::from_secs_f64(t).unwrap();
            match lookup(&s, stamp, 5.0) {
                Ok((p, _)) => {
                    prop_assert!((0.0..=3.0).contains(&t));
                    let i = s.partition_point(|x| x.stamp < stamp).max(1);
                    prop_assert!(p.x >= s[i - 1].pose.x - 1e-9 && p.x <= s[i].pose.x + 1e-9);
                }
                Err(_) => prop_assert!(!(0.0..=3.0).contains(&t)),
            }
        }
    }
}
