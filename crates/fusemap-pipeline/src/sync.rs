//! When a measurement gets its pose: the time offsets, the sync mode, the timing limits,
//! and the reasons a scan got none. A leaf of the pipeline, used by every stage that
//! places a measurement in time.

use fusemap_core::config::{LogConfig, SyncConfig};
use fusemap_core::time::{NoPose, Stamp, StreamTiming, SyncMode, TimingLimits};
use serde::Serialize;

/// Nanoseconds of a time offset in seconds (configs bound it to ±1 h).
pub(crate) fn offset_ns(s: f64) -> i64 {
    (s * 1e9).round() as i64
}

/// The sync mode from the config, with the nearest tolerance resolved (half the median
/// period of `stamps`, taken in stamp order as the scans are mapped).
pub fn sync_mode(cfg: &LogConfig, stamps: &[Stamp]) -> SyncMode {
    match cfg.sync {
        SyncConfig::Interpolate => SyncMode::Interpolate,
        SyncConfig::Nearest => {
            let tol = if cfg.nearest_tolerance_s > 0.0 {
                cfg.nearest_tolerance_s
            } else {
                let mut h = stamps.to_vec();
                h.sort_unstable();
                let median_period_s = StreamTiming::analyze(&h, &[], TimingLimits::default()).median_period_s;
                if median_period_s > 0.0 {
                    median_period_s / 2.0
                } else {
                    0.05
                }
            };
            SyncMode::Nearest { tolerance_s: tol }
        }
    }
}

/// The timing limits of the config.
pub fn limits(cfg: &LogConfig) -> TimingLimits {
    TimingLimits { gap_s: cfg.max_pose_gap_s, far_delay_s: cfg.far_delay_s }
}

/// Scans skipped, by reason.
#[derive(Debug, Default, Clone, Serialize)]
pub struct Skipped {
    /// Before the first pose.
    pub before_first_pose: u64,
    /// After the last pose.
    pub after_last_pose: u64,
    /// Inside a gap of the pose track.
    pub in_pose_gap: u64,
    /// No pose within the nearest-neighbour tolerance.
    pub no_pose_within_tolerance: u64,
    /// No pose on the scan line.
    pub no_pose_on_line: u64,
    /// The pose on the scan line is a glitch (`log.max_speed_m_s`, `max_turn_rate_deg_s`).
    pub pose_glitch: u64,
    /// Arrived later than the merge's reorder window behind the other scans.
    pub late: u64,
    /// Its beam angles cannot be placed (`ScanMessage::angle_fault`): a zero or non-finite
    /// `angle_increment`, or a `ranges` count that disagrees with `angle_min … angle_max`.
    pub bad_angles: u64,
    /// The same scan again (same stamp and ranges as the one before it): inserted once.
    pub repeated: u64,
    /// Frozen: the ranges of the scan before, bit for bit, at a new stamp, while the pose
    /// track moved (a driver republishing its last reading; `repeats.rs`).
    pub frozen: u64,
}

impl Skipped {
    /// Counts a scan that got no pose, by the reason.
    pub fn count(&mut self, why: NoPose) {
        match why {
            NoPose::Empty | NoPose::BeforeStart(_) => self.before_first_pose += 1,
            NoPose::AfterEnd(_) => self.after_last_pose += 1,
            NoPose::Gap { .. } => self.in_pose_gap += 1,
            NoPose::TooFar { .. } => self.no_pose_within_tolerance += 1,
        }
    }

    /// All skipped scans.
    pub fn total(&self) -> u64 {
        self.before_first_pose
            + self.after_last_pose
            + self.in_pose_gap
            + self.no_pose_within_tolerance
            + self.no_pose_on_line
            + self.pose_glitch
            + self.late
            + self.bad_angles
            + self.repeated
            + self.frozen
    }

    /// Adds another lidar's counts.
    pub fn add(&mut self, o: &Skipped) {
        self.before_first_pose += o.before_first_pose;
        self.after_last_pose += o.after_last_pose;
        self.in_pose_gap += o.in_pose_gap;
        self.no_pose_within_tolerance += o.no_pose_within_tolerance;
        self.no_pose_on_line += o.no_pose_on_line;
        self.pose_glitch += o.pose_glitch;
        self.late += o.late;
        self.bad_angles += o.bad_angles;
        self.repeated += o.repeated;
        self.frozen += o.frozen;
    }
}
