//! The estimator's configuration: every noise figure, gate and threshold, as the
//! `[estimator]` table of the TOML configuration.

use crate::field_error::FieldError;
use serde::{Deserialize, Serialize};

/// Noise figures, gates and thresholds of the planar estimator.
///
/// Defaults suit a wheeled ground robot at walking speed with a MEMS gyro and an RTK
/// receiver. Odometry noise is a random walk in distance (variance grows linearly with the
/// distance driven and the angle turned, so splitting one motion into many increments
/// gives the same total uncertainty; Thrun et al., *Probabilistic Robotics*, §5.4 model the
/// standard deviation as proportional to the motion instead, which depends on the message
/// rate).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorConfig {
    /// Probability of the χ² Mahalanobis gate applied to every correction (fixes, poses,
    /// headings, zero-rate updates).
    pub gate_probability: f64,
    /// Distance between the first and last fix used to initialise the heading from the
    /// course over ground, metres.
    pub heading_init_distance_m: f64,
    /// Only fixes whose largest standard deviation is at most this are used to initialise
    /// the heading, metres. Imprecise fixes need a longer baseline: the distance used is at
    /// least ten times the largest standard deviation of the fixes in the fit.
    pub heading_init_max_fix_sigma_m: f64,
    /// Largest RMS residual of the course-over-ground fit, metres (at least three times the
    /// fixes' own standard deviation is always allowed).
    pub heading_init_max_residual_m: f64,
    /// Odometry translation noise: standard deviation after one metre, per axis of the
    /// base frame, m/√m.
    pub odometry_translation_noise: f64,
    /// Odometry translation noise growing with time (covers creep and timing jitter), m/√s.
    pub odometry_translation_noise_per_sqrt_s: f64,
    /// Odometry heading noise per radian turned, rad/√rad.
    pub odometry_rotation_noise_per_rad: f64,
    /// Odometry heading noise per metre driven, rad/√m.
    pub odometry_rotation_noise_per_m: f64,
    /// Use the covariance carried by odometry messages (read as the covariance of the
    /// increment since the previous message) instead of the figures above when it is
    /// positive definite.
    pub use_odometry_covariance: bool,
    /// Odometry increments longer than this add translation noise for the unknown path
    /// inside them (`gap_speed_sigma_mps` × duration, at most the distance across the gap),
    /// seconds.
    pub max_odometry_gap_s: f64,
    /// Speed uncertainty across an odometry gap, m/s.
    pub gap_speed_sigma_mps: f64,
    /// Gyro rate noise per sample when the message carries no variance, rad/s.
    pub gyro_rate_sigma: f64,
    /// Yaw rates beyond this are a sensor or driver fault and are dropped (counted), rad/s.
    /// The default, 35 rad/s (2000 °/s), is the full scale of common MEMS gyros and far
    /// above any ground robot's turn rate.
    pub max_gyro_rate_rad_s: f64,
    /// Gyro samples further apart than this leave a gap in which the odometry heading is
    /// used instead, seconds.
    pub max_gyro_gap_s: f64,
    /// Heading noise added over time for what the gyro model leaves out (scale error,
    /// vibration), rad/√s.
    pub heading_noise_per_sqrt_s: f64,
    /// Gyro bias random walk, (rad/s)/√s.
    pub gyro_bias_random_walk: f64,
    /// Odometry scale random walk per metre driven, 1/√m.
    pub odometry_scale_random_walk: f64,
    /// Prior standard deviation of the start position when an absolute source exists, metres.
    pub initial_position_sigma_m: f64,
    /// Prior standard deviation of the gyro bias, rad/s.
    pub initial_gyro_bias_sigma: f64,
    /// Prior standard deviation of the odometry scale (true distance = scale × odometry distance).
    pub initial_scale_sigma: f64,
    /// Fix standard deviation used when a fix's covariance is not positive definite, metres.
    pub fallback_fix_sigma_m: f64,
    /// Heading standard deviation used when a heading's variance is not positive, radians.
    pub fallback_heading_sigma_rad: f64,
    /// The least heading standard deviation an IMU's orientation may claim, radians: a
    /// smaller covariance is raised to it (and counted). An attitude filter's absolute
    /// yaw is good to a degree or so indoors, a navigation-grade INS to about 0.1°; a
    /// covariance of 10⁻¹² rad² would pin the track to every error of the reading.
    pub imu_heading_floor_sigma_rad: f64,
    /// Position standard deviation used when a pose's covariance is not positive definite, metres.
    pub fallback_pose_sigma_m: f64,
    /// Heading standard deviation used when a pose's covariance is not positive definite, radians.
    pub fallback_pose_sigma_rad: f64,
    /// Length of the window over which odometry and gyro heading increments are compared
    /// to detect wheel slip, seconds.
    pub slip_window_s: f64,
    /// The disagreement, in standard deviations, beyond which odometry is taken to slip.
    pub slip_sigma: f64,
    /// Factor on the odometry noise variance while it slips.
    pub slip_noise_inflation: f64,
    /// While the odometry slips, predict with the odometry speed from before the slip
    /// (only ever slower than the slipping odometry: spinning wheels over-count).
    pub slip_hold_speed: bool,
    /// Length of the window over which the odometry distance is compared with precise
    /// fixes to detect wheel slip, seconds.
    pub slip_fix_window_s: f64,
    /// Only fixes with a largest standard deviation up to this judge slip, metres.
    pub slip_fix_max_sigma_m: f64,
    /// Slip intervals closer than this are reported as one stretch, seconds.
    pub slip_merge_gap_s: f64,
    /// Odometry slower than this (translation) counts as standing still, m/s.
    pub stationary_max_speed_mps: f64,
    /// Odometry turning slower than this counts as standing still, rad/s.
    pub stationary_max_rate: f64,
    /// Standing still for at least this long lets the gyro measure its own bias, seconds.
    pub stationary_min_s: f64,
    /// Gate-rejected position fixes in a row that agree with each other (the filter, not
    /// the fixes, is off) before the filter's position uncertainty is reopened; 0 disables.
    pub gate_reset_consistent_fixes: usize,
    /// … and only when the odometry could have drifted that far: the common offset of the
    /// rejected fixes is at most this share of the distance driven since the last fix the
    /// filter took (plus ten times the fixes' σ). A GNSS jump of 100 m seconds after a good
    /// fix is the receiver's, not the filter's, however well the fixes after it agree.
    pub gate_reset_max_drift: f64,
    /// `pose_at` refuses to interpolate across samples further apart than this, seconds.
    pub max_sample_gap_s: f64,
    /// Correlation time of the position error of non-RTK fixes (multipath, atmosphere),
    /// seconds. Fixes arriving faster than this are not independent: counting each at its
    /// own σ would let a few seconds of a 0.5 m bias outweigh the odometry (the design
    /// document's §2.4: correlated observations must not be counted as independent). Each
    /// fix's update covariance is therefore scaled by `correlation_time / interval` (at
    /// least 1), so one correlation time of fixes carries the weight of one fix; the
    /// outlier gate still uses the fix's own σ. 0 treats every fix as independent.
    pub fix_correlation_time_s: f64,
    /// The same for RTK fixed solutions (`STATUS_GBAS_FIX`), whose centimetre errors are
    /// close to white, seconds.
    pub rtk_fix_correlation_time_s: f64,
    /// A fix reported as RTK (`STATUS_GBAS_FIX`) counts as an RTK fixed solution only when
    /// its σ is at most this, metres: drivers report RTK float and WAAS with the same
    /// status, and their decimetre errors are correlated like a plain fix's.
    pub rtk_fix_max_sigma_m: f64,
    /// Test every accepted fix again against the smoothed track and, if any fails the
    /// gate, run the estimate once more without them.
    pub smoothed_fix_gate: bool,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            gate_probability: 0.99,
            heading_init_distance_m: 5.0,
            heading_init_max_fix_sigma_m: 2.0,
            heading_init_max_residual_m: 0.3,
            odometry_translation_noise: 0.02,
            odometry_translation_noise_per_sqrt_s: 0.002,
            odometry_rotation_noise_per_rad: 0.05,
            odometry_rotation_noise_per_m: 0.02,
            use_odometry_covariance: true,
            max_odometry_gap_s: 0.25,
            gap_speed_sigma_mps: 1.0,
            gyro_rate_sigma: 0.01,
            max_gyro_rate_rad_s: 35.0,
            max_gyro_gap_s: 0.1,
            heading_noise_per_sqrt_s: 0.002,
            gyro_bias_random_walk: 1e-4,
            odometry_scale_random_walk: 1e-4,
            initial_position_sigma_m: 1.0,
            initial_gyro_bias_sigma: 0.02,
            initial_scale_sigma: 0.05,
            fallback_fix_sigma_m: 1.0,
            fallback_heading_sigma_rad: 0.1,
            imu_heading_floor_sigma_rad: 0.002,
            fallback_pose_sigma_m: 0.5,
            fallback_pose_sigma_rad: 0.1,
            slip_window_s: 0.5,
            slip_sigma: 4.0,
            slip_noise_inflation: 100.0,
            slip_hold_speed: true,
            slip_fix_window_s: 1.0,
            slip_fix_max_sigma_m: 0.1,
            slip_merge_gap_s: 0.5,
            stationary_max_speed_mps: 0.005,
            stationary_max_rate: 0.005,
            stationary_min_s: 0.5,
            gate_reset_consistent_fixes: 3,
            gate_reset_max_drift: 0.2,
            max_sample_gap_s: 1.0,
            fix_correlation_time_s: 10.0,
            rtk_fix_correlation_time_s: 0.0,
            rtk_fix_max_sigma_m: 0.05,
            smoothed_fix_gate: true,
        }
    }
}

/// The largest standard deviation (or noise density) a key may give, in its own unit:
/// the filter carries its square and multiplies that by elapsed times, distances and
/// other variances, and 10¹² keeps every such product far inside an `f64`, where
/// 10³⁰⁰ overflowed at the first prediction. A million metres, radians or a scale of
/// a million is already no information at all.
pub const MAX_SIGMA: f64 = 1e6;

impl EstimatorConfig {
    /// Checks every field; the error names the first bad one in its TOML path
    /// (`estimator.gate_probability`).
    pub fn validate(&self) -> Result<(), FieldError> {
        for (name, v) in self.positive_fields() {
            if !(v.is_finite() && v > 0.0) {
                return Err(FieldError::new(
                    format!("estimator.{name}"),
                    format!("must be a positive number (got {v})"),
                ));
            }
        }
        for (name, v) in self.non_negative_fields() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(FieldError::new(
                    format!("estimator.{name}"),
                    format!("must be a non-negative number (got {v})"),
                ));
            }
        }
        for (name, v) in self.sigma_fields() {
            if v > MAX_SIGMA {
                return Err(FieldError::new(
                    format!("estimator.{name}"),
                    format!(
                        "is a standard deviation of at most {MAX_SIGMA:e} (got {v}): the filter squares it, and \
                         a larger one is no information at all, not a noise level"
                    ),
                ));
            }
        }
        if !(self.gate_probability > 0.0 && self.gate_probability < 1.0) {
            return Err(FieldError::new(
                "estimator.gate_probability",
                format!("must be in (0, 1) (got {})", self.gate_probability),
            ));
        }
        if !(self.slip_noise_inflation.is_finite() && self.slip_noise_inflation >= 1.0) {
            return Err(FieldError::new(
                "estimator.slip_noise_inflation",
                format!("must be at least 1 (got {})", self.slip_noise_inflation),
            ));
        }
        Ok(())
    }

    /// The fields that must be positive and finite.
    fn positive_fields(&self) -> [(&'static str, f64); 22] {
        [
            ("heading_init_distance_m", self.heading_init_distance_m),
            ("heading_init_max_fix_sigma_m", self.heading_init_max_fix_sigma_m),
            ("heading_init_max_residual_m", self.heading_init_max_residual_m),
            ("max_odometry_gap_s", self.max_odometry_gap_s),
            ("gyro_rate_sigma", self.gyro_rate_sigma),
            ("max_gyro_rate_rad_s", self.max_gyro_rate_rad_s),
            ("max_gyro_gap_s", self.max_gyro_gap_s),
            ("initial_position_sigma_m", self.initial_position_sigma_m),
            ("initial_gyro_bias_sigma", self.initial_gyro_bias_sigma),
            ("initial_scale_sigma", self.initial_scale_sigma),
            ("fallback_fix_sigma_m", self.fallback_fix_sigma_m),
            ("fallback_heading_sigma_rad", self.fallback_heading_sigma_rad),
            ("imu_heading_floor_sigma_rad", self.imu_heading_floor_sigma_rad),
            ("fallback_pose_sigma_m", self.fallback_pose_sigma_m),
            ("fallback_pose_sigma_rad", self.fallback_pose_sigma_rad),
            ("slip_window_s", self.slip_window_s),
            ("slip_sigma", self.slip_sigma),
            ("slip_fix_window_s", self.slip_fix_window_s),
            ("slip_fix_max_sigma_m", self.slip_fix_max_sigma_m),
            ("stationary_min_s", self.stationary_min_s),
            ("max_sample_gap_s", self.max_sample_gap_s),
            ("rtk_fix_max_sigma_m", self.rtk_fix_max_sigma_m),
        ]
    }

    /// The fields that must be non-negative and finite.
    fn non_negative_fields(&self) -> [(&'static str, f64); 14] {
        [
            ("odometry_translation_noise", self.odometry_translation_noise),
            ("gate_reset_max_drift", self.gate_reset_max_drift),
            ("odometry_translation_noise_per_sqrt_s", self.odometry_translation_noise_per_sqrt_s),
            ("odometry_rotation_noise_per_rad", self.odometry_rotation_noise_per_rad),
            ("odometry_rotation_noise_per_m", self.odometry_rotation_noise_per_m),
            ("gap_speed_sigma_mps", self.gap_speed_sigma_mps),
            ("heading_noise_per_sqrt_s", self.heading_noise_per_sqrt_s),
            ("gyro_bias_random_walk", self.gyro_bias_random_walk),
            ("odometry_scale_random_walk", self.odometry_scale_random_walk),
            ("slip_merge_gap_s", self.slip_merge_gap_s),
            ("stationary_max_speed_mps", self.stationary_max_speed_mps),
            ("stationary_max_rate", self.stationary_max_rate),
            ("fix_correlation_time_s", self.fix_correlation_time_s),
            ("rtk_fix_correlation_time_s", self.rtk_fix_correlation_time_s),
        ]
    }

    /// The standard deviations and noise densities, at most [`MAX_SIGMA`].
    fn sigma_fields(&self) -> impl Iterator<Item = (&'static str, f64)> {
        const SIGMAS: [&str; 18] = [
            "gyro_rate_sigma",
            "initial_position_sigma_m",
            "initial_gyro_bias_sigma",
            "initial_scale_sigma",
            "fallback_fix_sigma_m",
            "fallback_heading_sigma_rad",
            "imu_heading_floor_sigma_rad",
            "fallback_pose_sigma_m",
            "fallback_pose_sigma_rad",
            "slip_sigma",
            "odometry_translation_noise",
            "odometry_translation_noise_per_sqrt_s",
            "odometry_rotation_noise_per_rad",
            "odometry_rotation_noise_per_m",
            "gap_speed_sigma_mps",
            "heading_noise_per_sqrt_s",
            "gyro_bias_random_walk",
            "odometry_scale_random_walk",
        ];
        self.positive_fields().into_iter().chain(self.non_negative_fields()).filter(|(n, _)| SIGMAS.contains(n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_bad_fields_are_named() {
        assert_eq!(EstimatorConfig::default().validate(), Ok(()));
        // Every σ key names a field of the two lists.
        assert_eq!(EstimatorConfig::default().sigma_fields().count(), 18);
        let cfg = EstimatorConfig { gate_probability: 1.0, ..Default::default() };
        assert_eq!(cfg.validate().unwrap_err().field, "estimator.gate_probability");
        let cfg = EstimatorConfig { gyro_rate_sigma: f64::NAN, ..Default::default() };
        assert_eq!(cfg.validate().unwrap_err().field, "estimator.gyro_rate_sigma");
        let cfg = EstimatorConfig { odometry_translation_noise: -1.0, ..Default::default() };
        assert_eq!(cfg.validate().unwrap_err().field, "estimator.odometry_translation_noise");
        let cfg = EstimatorConfig { initial_scale_sigma: 1e300, ..Default::default() };
        assert_eq!(cfg.validate().unwrap_err().field, "estimator.initial_scale_sigma");
        let cfg = EstimatorConfig { gyro_bias_random_walk: MAX_SIGMA, ..Default::default() };
        assert_eq!(cfg.validate(), Ok(()));
        let cfg = EstimatorConfig { slip_noise_inflation: 0.5, ..Default::default() };
        assert_eq!(cfg.validate().unwrap_err().field, "estimator.slip_noise_inflation");
    }
}
