//! The IMU: gyro = true body rate + bias + white noise; accelerometer = specific force
//! (acceleration minus gravity, so +g on z at rest) at the IMU's lever arm, in the IMU
//! frame, + bias + noise. No orientation (REP 145: `orientation_covariance[0] = -1`).

use crate::messages::{diagonal3, SimImu};
use crate::path::Trajectory;
use crate::sensors::ImuConfig;
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::geometry_msgs::Quaternion;
use fusemap_io::log::ros2::msgs::sensor_msgs::Imu;
use fusemap_io::log::ros2::msgs::std_msgs::Header;

/// Standard gravity, m/s² (CGPM 1901).
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Simulates one message every `1 / rate_hz` seconds of the run.
pub fn simulate_imu(
    cfg: &ImuConfig,
    frame_id: &str,
    traj: &Trajectory,
    start: Stamp,
    rng: &mut SplitMix64,
) -> Vec<SimImu> {
    let r = cfg.mount.rotation();
    // base → imu rotation transposed: a base-frame vector in the IMU frame.
    let to_imu = |v: [f64; 3]| -> [f64; 3] { [0, 1, 2].map(|c| r[0][c] * v[0] + r[1][c] * v[1] + r[2][c] * v[2]) };
    let (rx, ry) = (cfg.mount.x, cfg.mount.y);
    let (sg, sa) = (cfg.gyro_noise_std_radps, cfg.accel_noise_std_mps2);
    let mut orientation_covariance = [0.0; 9];
    orientation_covariance[0] = -1.0;
    let mut out = Vec::new();
    let mut k = 0usize;
    while k as f64 / cfg.rate_hz <= traj.duration() {
        let t = k as f64 / cfg.rate_hz;
        k += 1;
        let s = traj.sample_at(t);
        let w = s.omega;
        // Base-origin acceleration of a unicycle in the body frame: (v̇, v·ω); at the lever
        // arm add α × r + ω × (ω × r).
        let accel_base = [s.accel - s.alpha * ry - w * w * rx, s.v * w + s.alpha * rx - w * w * ry, STANDARD_GRAVITY];
        let gyro = to_imu([0.0, 0.0, w]);
        let acc = to_imu(accel_base);
        let mut angular_velocity = [0.0; 3];
        let mut linear_acceleration = [0.0; 3];
        for i in 0..3 {
            angular_velocity[i] = gyro[i] + sg * rng.gaussian();
            linear_acceleration[i] = acc[i] + cfg.accel_bias_mps2[i] + sa * rng.gaussian();
        }
        angular_velocity[2] += cfg.gyro_bias_radps;
        let stamp = Stamp(start.0 + ((t + cfg.time_offset_s) * 1e9).round() as i64);
        out.push(SimImu::new(
            &cfg.topic,
            Imu {
                header: Header::new(stamp, frame_id),
                orientation: Quaternion::default(),
                orientation_covariance,
                angular_velocity: angular_velocity.into(),
                angular_velocity_covariance: diagonal3([sg * sg; 3]),
                linear_acceleration: linear_acceleration.into(),
                linear_acceleration_covariance: diagonal3([sa * sa; 3]),
            },
        ));
    }
    out
}
