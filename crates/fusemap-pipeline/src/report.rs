//! The run report: the `log` part of `summary.json`, in figures a user can check.

use crate::extrinsics::ExtrinsicsReport;
use crate::merge::StreamStats;
use crate::track::TrackCounts;
use fusemap_core::time::{NoPose, StreamTiming};
use serde::Serialize;
use std::collections::BTreeMap;

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
    }
}

/// One lidar of a run.
#[derive(Debug, Clone, Serialize)]
pub struct LidarReport {
    /// The configured name.
    pub name: String,
    /// The topic mapped.
    pub topic: String,
    /// Its frame id (the most common one of its messages).
    pub frame: String,
    /// Other frame ids its messages carried, with counts (each scan is still mapped with
    /// the mount of the main frame: a topic should have one frame).
    pub other_frames: BTreeMap<String, u64>,
    /// Scans in the topic.
    pub scans_read: u64,
    /// Scans mapped.
    pub scans_used: u64,
    /// Scans skipped, by reason.
    pub scans_skipped: Skipped,
    /// Scans de-skewed beam by beam.
    pub scans_deskewed: u64,
    /// Scans whose stamps came after a later-stamped one in the log (mapped in stamp order).
    pub scans_reordered: u64,
    /// Seconds added to its stamps.
    pub time_offset_s: f64,
    /// Timing of its header stamps.
    pub timing: StreamTiming,
    /// Its mount.
    pub extrinsics: ExtrinsicsReport,
}

/// The `log` part of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct LogReport {
    /// Detected format.
    pub format: String,
    /// The first lidar's topic (see `lidars` for all).
    pub scan_topic: String,
    /// Where poses came from.
    pub pose_source: String,
    /// `interpolate` or `nearest (tolerance s)`.
    pub sync: String,
    /// Whether beams were de-skewed.
    pub deskew: bool,
    /// Scans in the mapped topics.
    pub scans_read: u64,
    /// Scans mapped.
    pub scans_used: u64,
    /// Scans skipped, by reason (all lidars).
    pub scans_skipped: Skipped,
    /// Scans de-skewed beam by beam.
    pub scans_deskewed: u64,
    /// Scans inserted in stamp order after arriving behind a later-stamped one.
    pub scans_reordered: u64,
    /// Every lidar mapped.
    pub lidars: Vec<LidarReport>,
    /// Every camera mapped.
    pub cameras: Vec<crate::camera::CameraReport>,
    /// Observations merged into a correlation group another observation had opened.
    pub correlated_merged: u64,
    /// What SLAM did (scan matching, loop closure, the optimised pose graph), when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slam: Option<crate::slam::SlamSummary>,
    /// The sensors that were read, by name: `kind topic`.
    pub sensors: BTreeMap<String, String>,
    /// The pose track's counters.
    pub pose_track: TrackCounts,
    /// Timing of the first lidar's scans.
    pub scan_timing: StreamTiming,
    /// Timing of the pose stream (odometry or TF), when it is one.
    pub pose_timing: Option<StreamTiming>,
    /// The first lidar's mount.
    pub extrinsics: ExtrinsicsReport,
    /// The estimator's report, when it made the poses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<serde_json::Value>,
    /// The time-ordered merge of the range streams: per-stream counters.
    pub merge: Vec<StreamStats>,
    /// The most scans the merge held at once.
    pub merge_peak_queued: usize,
    /// The frame tree of `/tf_static` and `/tf`: frames, edges, and what it refused.
    pub frames: fusemap_core::frames::FrameReport,
    /// Records skipped by type.
    pub skipped_by_type: BTreeMap<String, u64>,
    /// Malformed records skipped.
    pub malformed_records: u64,
    /// Seconds of the first pass (pose sensors and inventory).
    pub decode_s: f64,
    /// Seconds of the pose track (the estimator, when it runs).
    pub track_s: f64,
    /// Seconds of the second pass (reading and inserting scans).
    pub map_s: f64,
}
