//! Whether two tracks of one robot agree on the direction it moved: the lidar's (SLAM's
//! track, which follows the lidar's mount) against the pose sensors' (odometry, IMU,
//! GNSS through the estimator).
//!
//! A lidar mount wrong by δ in yaw makes SLAM's base track the true one composed with a
//! constant body-frame rotation: every relative motion it reports is the wheels' relative
//! motion conjugated by it, its translation turned by −δ in the body frame. Odometry's
//! direction of travel does not depend on the lidar, so the median angle between the two
//! tracks' body-frame translations over straight steps measures δ (the observability
//! argument of Censi et al. 2013, who calibrate odometry and the lidar mount jointly;
//! wheel scale errors change the length of a step, not its direction). Steps that turn
//! are left out: there a wrong lever arm (the mount's x, y) bends the direction too.

use crate::geometry::{normalize_angle, Pose2};
use serde::Serialize;

/// The two tracks' disagreement on the direction of travel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MotionAgreement {
    /// Straight steps compared.
    pub steps: u64,
    /// Median angle from the reference track's body-frame step to the other's, degrees.
    pub median_deg: f64,
    /// Its standard error, degrees (1.4826 · MAD · 1.2533 / √n: the median's spread under
    /// Gaussian noise).
    pub standard_error_deg: f64,
}

/// Compares `(reference, other)` poses of the same instants, in time order, over steps of
/// at least `step_m` along the reference that turn less than `max_turn_rad`. `None` with
/// fewer than 10 such steps.
pub fn motion_agreement(pairs: &[(Pose2, Pose2)], step_m: f64, max_turn_rad: f64) -> Option<MotionAgreement> {
    let mut diffs = Vec::new();
    let mut a = 0;
    for j in 1..pairs.len() {
        let (r0, o0) = pairs[a];
        let (r1, o1) = pairs[j];
        let dr = r0.inverse() * r1;
        if dr.x.hypot(dr.y) < step_m {
            continue;
        }
        let d_o = o0.inverse() * o1;
        let straight = dr.theta.abs() < max_turn_rad && d_o.theta.abs() < max_turn_rad;
        if straight && d_o.x.hypot(d_o.y) >= 0.5 * step_m {
            diffs.push(normalize_angle(d_o.y.atan2(d_o.x) - dr.y.atan2(dr.x)));
        }
        a = j;
    }
    if diffs.len() < 10 {
        return None;
    }
    diffs.sort_by(f64::total_cmp);
    let median = median_of_sorted(&diffs);
    let mut dev: Vec<f64> = diffs.iter().map(|d| (d - median).abs()).collect();
    dev.sort_by(f64::total_cmp);
    let sigma = 1.4826 * median_of_sorted(&dev);
    let se = sigma * 1.2533 / (diffs.len() as f64).sqrt();
    Some(MotionAgreement {
        steps: diffs.len() as u64,
        median_deg: median.to_degrees(),
        standard_error_deg: se.to_degrees(),
    })
}

/// The median of a sorted, non-empty slice.
pub(crate) fn median_of_sorted(v: &[f64]) -> f64 {
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A drive along a zig-zag: straight legs joined by turns.
    fn drive() -> Vec<Pose2> {
        let mut p = Pose2::new(0.0, 0.0, 0.0);
        let mut out = vec![p];
        for k in 0..400 {
            let turn = if k % 40 < 30 { 0.0 } else { 0.15 * if (k / 40) % 2 == 0 { 1.0 } else { -1.0 } };
            p = p * Pose2::new(0.1, 0.0, turn);
            out.push(p);
        }
        out
    }

    proptest! {
        /// A track composed with a constant body-frame offset (a wrong mount's) turns every
        /// straight step by minus the offset's yaw; the same track agrees with itself.
        #[test]
        fn a_constant_mount_rotation_is_measured(yaw_deg in -5.0f64..5.0, x in -0.1f64..0.1) {
            let reference = drive();
            let mount = Pose2::new(x, 0.02, yaw_deg.to_radians());
            let pairs: Vec<(Pose2, Pose2)> = reference.iter().map(|&r| (r, r * mount)).collect();
            let m = motion_agreement(&pairs, 0.5, 3f64.to_radians()).unwrap();
            prop_assert!((m.median_deg + yaw_deg).abs() < 1e-6, "{m:?}");
            let same: Vec<(Pose2, Pose2)> = reference.iter().map(|&r| (r, r)).collect();
            prop_assert_eq!(motion_agreement(&same, 0.5, 3f64.to_radians()).unwrap().median_deg, 0.0);
        }
    }

    #[test]
    fn too_few_steps_say_nothing() {
        let short: Vec<(Pose2, Pose2)> = drive()[..20].iter().map(|&r| (r, r)).collect();
        assert_eq!(motion_agreement(&short, 0.5, 0.05), None);
    }
}
