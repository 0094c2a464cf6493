//! The run report: the `log` part of `summary.json`, in figures a user can check.

use crate::extrinsics::ExtrinsicsReport;
use crate::merge::StreamStats;
pub use crate::sync::Skipped;
use crate::track::TrackCounts;
use fusemap_core::time::StreamTiming;
use serde::Serialize;
use std::collections::BTreeMap;

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
    pub slam: Option<crate::slam_summary::SlamSummary>,
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
    pub estimator: Option<Box<crate::estimation_report::EstimationReport>>,
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
    /// What `fusemap doctor` finds in the log's streams and pose sensors (stamps going
    /// backwards or repeated, delays, pauses, GNSS fix quality, odometry against the gyro).
    pub log_findings: Vec<String>,
}
