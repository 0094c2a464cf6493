//! Wheel odometry of a differential drive: each wheel's true travel × the scale error
//! × the groove slip (while that wheel is over a groove) + noise, dead-reckoned into
//! `odom_from_base` (Thrun et al., *Probabilistic Robotics*, §5.4, the odometry motion
//! model run forwards). `odom` starts at identity.

use crate::messages::{diagonal6, rpy_to_quaternion, SimOdometry};
use crate::path::{unicycle_step, Trajectory, TRUTH_RATE_HZ};
use crate::sensors::OdometryConfig;
use crate::world::Rect;
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::geometry_msgs::{Pose, PoseWithCovariance, Twist, TwistWithCovariance};
use fusemap_io::log::ros2::msgs::nav_msgs::Odometry;
use fusemap_io::log::ros2::msgs::std_msgs::Header;

/// Dead-reckons the run and emits a message every `1 / rate_hz` seconds (at the first
/// 200 Hz step at or after each due time). Returns the messages and the number of
/// 5 ms steps with a wheel in a groove.
pub fn simulate_odometry(
    cfg: &OdometryConfig,
    frames: (&str, &str),
    grooves: &[Rect],
    traj: &Trajectory,
    start: Stamp,
    rng: &mut SplitMix64,
) -> (Vec<SimOdometry>, u64) {
    let dt = 1.0 / TRUTH_RATE_HZ;
    let half = cfg.wheel_separation_m / 2.0;
    let in_groove = |p: Point2| grooves.iter().any(|g| g.contains(p));
    let (mut odom, mut v_m, mut w_m) = (Pose2::IDENTITY, 0.0, 0.0);
    let mut out = Vec::new();
    let mut slipping_steps = 0u64;
    let mut next = 0usize;
    for s in traj.samples() {
        while (next as f64) / cfg.rate_hz <= s.t + 1e-9 {
            next += 1;
            let stamp = Stamp(start.0 + ((s.t + cfg.time_offset_s) * 1e9).round() as i64);
            let pose = Pose {
                position: [odom.x, odom.y, 0.0].into(),
                orientation: rpy_to_quaternion(0.0, 0.0, odom.theta).into(),
            };
            let twist = Twist { linear: [v_m, 0.0, 0.0].into(), angular: [0.0, 0.0, w_m].into() };
            out.push(SimOdometry::new(
                &cfg.topic,
                Odometry {
                    header: Header::new(stamp, frames.0),
                    child_frame_id: frames.1.into(),
                    pose: PoseWithCovariance { pose, covariance: diagonal6(cfg.pose_covariance_diagonal) },
                    twist: TwistWithCovariance { twist, covariance: diagonal6(cfg.twist_covariance_diagonal) },
                },
            ));
        }
        // The wheels' true ground speeds over the step that starts here.
        let (vl, vr) = (s.v - s.omega * half, s.v + s.omega * half);
        let left_slips = in_groove(s.pose * Point2::new(0.0, half));
        let right_slips = in_groove(s.pose * Point2::new(0.0, -half));
        if left_slips || right_slips {
            slipping_steps += 1;
        }
        let sl = if left_slips { cfg.slip_factor_left } else { 1.0 };
        let sr = if right_slips { cfg.slip_factor_right } else { 1.0 };
        let ml = vl * cfg.scale_error * sl + cfg.wheel_noise_std_mps * rng.gaussian();
        let mr = vr * cfg.scale_error * sr + cfg.wheel_noise_std_mps * rng.gaussian();
        v_m = (ml + mr) / 2.0;
        w_m = (mr - ml) / cfg.wheel_separation_m;
        odom = unicycle_step(odom, v_m, w_m, dt);
    }
    (out, slipping_steps)
}
