//! `[log]`: how robot logs are read (pose source, time synchronisation, extrinsics,
//! pose glitches, the reorder window) and its validation.

use super::{err, finite, FieldError};
use serde::{Deserialize, Serialize};

/// Where a log's scans get their poses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseSource {
    /// The pose written on the scan line if the log has one (CARMEN), else the estimator
    /// when the log has an IMU, GNSS or poses, else the odometry topic, else TF to the base
    /// frame.
    #[default]
    Auto,
    /// The pose on each scan line (CARMEN corrected logs).
    ScanLine,
    /// The odometry topic, interpolated at each scan's stamp.
    Odometry,
    /// Dynamic TF transforms to the base frame, interpolated at each scan's stamp.
    Tf,
    /// The pose estimator: wheel odometry, IMU, GNSS and absolute poses fused by an
    /// extended Kalman filter and smoothed over the whole log (`auto` picks it when the log
    /// carries an IMU, GNSS or poses).
    Estimator,
}

/// How the pose at a scan's stamp is found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SyncConfig {
    /// Interpolate between the poses around the stamp.
    #[default]
    Interpolate,
    /// The nearest pose within `nearest_tolerance_s` (the design document's prototype).
    Nearest,
}

/// Where the laser's mount comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtrinsicsSource {
    /// `/tf_static` base → laser when the log has it, else the config's mount.
    #[default]
    Auto,
    /// Always the log's TF; a log without it is an error.
    Tf,
    /// Always the config's mount (TF, if present, is still compared and reported).
    Config,
}

/// How robot logs are read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogConfig {
    /// The robot's base frame.
    pub base_frame: String,
    /// Where scan poses come from.
    pub pose_source: PoseSource,
    /// Interpolation or nearest neighbour.
    pub sync: SyncConfig,
    /// Nearest-neighbour tolerance, seconds; 0 means half the median scan period.
    pub nearest_tolerance_s: f64,
    /// Longest gap in the pose track to interpolate across, seconds.
    pub max_pose_gap_s: f64,
    /// Interpolate across a longer gap when the robot moved at most this far over it,
    /// metres (0 disables).
    pub gap_bridge_motion_m: f64,
    /// … and turned at most this much, degrees.
    pub gap_bridge_motion_deg: f64,
    /// A pose sample implying a faster motion than this (from its neighbours in stamp
    /// order) is a glitch: rejected and counted, on every pose source. Metres per second.
    pub max_speed_m_s: f64,
    /// … or a faster turn than this, degrees per second.
    pub max_turn_rate_deg_s: f64,
    /// Place each beam with the pose at its own time (needs `time_increment`).
    pub deskew: bool,
    /// Where the laser mount comes from.
    pub extrinsics: ExtrinsicsSource,
    /// Largest accepted difference between TF and config mount translation, metres.
    pub extrinsics_tolerance_m: f64,
    /// Largest accepted difference between TF and config mount yaw, degrees.
    pub extrinsics_tolerance_deg: f64,
    /// A header stamp further than this from its receive time is reported, seconds.
    pub far_delay_s: f64,
    /// How far (seconds of header stamp) the time-ordered merge of the log's streams waits
    /// for a late message before releasing a later one: messages that arrive later than
    /// this behind their stream are counted and dropped. Bounds the memory of a run.
    pub reorder_window_s: f64,
}

impl LogConfig {
    /// The pose-glitch limits (`max_speed_m_s`, `max_turn_rate_deg_s`).
    pub fn motion_limits(&self) -> crate::time::MotionLimits {
        crate::time::MotionLimits {
            max_speed_m_s: self.max_speed_m_s,
            max_turn_rate_rad_s: self.max_turn_rate_deg_s.to_radians(),
        }
    }
}

impl Default for LogConfig {
    fn default() -> Self {
        Self {
            base_frame: "base_link".into(),
            pose_source: PoseSource::Auto,
            sync: SyncConfig::Interpolate,
            nearest_tolerance_s: 0.0,
            max_pose_gap_s: 0.5,
            gap_bridge_motion_m: 0.05,
            gap_bridge_motion_deg: 2.0,
            max_speed_m_s: 20.0,
            max_turn_rate_deg_s: 720.0,
            deskew: true,
            extrinsics: ExtrinsicsSource::Auto,
            extrinsics_tolerance_m: 0.02,
            extrinsics_tolerance_deg: 1.0,
            far_delay_s: 1.0,
            reorder_window_s: 2.0,
        }
    }
}

impl LogConfig {
    /// Checks every field; the error names the first bad one (`log.max_speed_m_s`).
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        finite("log.nearest_tolerance_s", self.nearest_tolerance_s)?;
        if self.nearest_tolerance_s < 0.0 {
            return Err(err("log.nearest_tolerance_s", "must be >= 0 (0 = half the scan period)"));
        }
        for (name, v) in [
            ("log.gap_bridge_motion_m", self.gap_bridge_motion_m),
            ("log.gap_bridge_motion_deg", self.gap_bridge_motion_deg),
        ] {
            if finite(name, v)? < 0.0 {
                return Err(err(name, format!("must be >= 0, got {v}")));
            }
        }
        for (name, v) in [
            ("log.max_pose_gap_s", self.max_pose_gap_s),
            ("log.max_speed_m_s", self.max_speed_m_s),
            ("log.max_turn_rate_deg_s", self.max_turn_rate_deg_s),
            ("log.extrinsics_tolerance_m", self.extrinsics_tolerance_m),
            ("log.extrinsics_tolerance_deg", self.extrinsics_tolerance_deg),
            ("log.far_delay_s", self.far_delay_s),
        ] {
            if finite(name, v)? <= 0.0 {
                return Err(err(name, format!("must be > 0, got {v}")));
            }
        }
        if finite("log.reorder_window_s", self.reorder_window_s)? < 0.0 {
            return Err(err("log.reorder_window_s", format!("must be >= 0, got {}", self.reorder_window_s)));
        }
        if self.base_frame.trim().is_empty() {
            return Err(err("log.base_frame", "must not be empty"));
        }
        Ok(())
    }
}
