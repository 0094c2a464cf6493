//! `fusemap map LOG`: a robot log to a map.
//!
//! Steps: read the whole log (decoding is fast; logs of this kind fit in memory), choose
//! the scan stream and the pose source, find the laser's mount, then insert the scans in
//! time order with the pose at each scan's own stamp (or each beam's, de-skewed). Every
//! scan that cannot be posed is skipped and counted with its reason; clock faults are
//! detected and reported, and the usable part of the log is still mapped.
//!
//! With a pose track (odometry or TF), both the track and the scans are taken in header
//! stamp order (the design document's "time-sorted odometry and scans", §4.1), not in the
//! order the log holds them: a pose sample or a scan that arrives after a later-stamped
//! one is still good data at its own stamp. So the map depends only on the stamps and
//! values, and the same messages give the same map whatever the container and its
//! storage order (CARMEN file order, a bag's log-time order). Only messages with equal
//! stamps keep their log order: the first pose sample of a stamp is used.

use super::map::{engine_for, finish, progress};
use crate::output;
use crate::summary::Summary;
use anyhow::{bail, Result};
use fusemap_core::config::{ExtrinsicsSource, LogConfig, Plan, PoseSource, SyncConfig};
use fusemap_core::geometry::{normalize_angle, Mount3, PlanarMount, Pose2, Pose3};
use fusemap_core::measurement::SensorId;
use fusemap_core::sensor::LidarModel;
use fusemap_core::time::{NoPose, PoseBuffer, PushOutcome, Stamp, StreamTiming, SyncMode, TimingLimits};
use fusemap_io::log::{LogMessage, OdomMessage, ReadStats, ScanMessage, Transform};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A log read into memory.
pub struct LoadedLog {
    /// Format name.
    pub format: String,
    /// Scans by topic, in file order.
    pub scans: BTreeMap<String, Vec<ScanMessage>>,
    /// Odometry by topic, in file order.
    pub odom: BTreeMap<String, Vec<OdomMessage>>,
    /// Static transforms (`/tf_static`).
    pub tf_static: Vec<Transform>,
    /// Dynamic transforms (`/tf`), with their receive times.
    pub tf_dynamic: Vec<Transform>,
    /// IMU messages by topic (counted only, for now).
    pub imu: BTreeMap<String, u64>,
    /// What the reader skipped.
    pub stats: ReadStats,
    /// Seconds spent reading and decoding.
    pub decode_s: f64,
}

/// Reads every message of `path`.
pub fn load(path: &Path) -> Result<LoadedLog> {
    let t0 = Instant::now();
    let opened = fusemap_io::log::open_log(path)?;
    let mut reader = opened.reader;
    let mut log = LoadedLog {
        format: opened.format.to_string(),
        scans: BTreeMap::new(),
        odom: BTreeMap::new(),
        tf_static: Vec::new(),
        tf_dynamic: Vec::new(),
        imu: BTreeMap::new(),
        stats: ReadStats::default(),
        decode_s: 0.0,
    };
    let mut tf = Vec::new();
    let mut undecodable = ReadStats::default();
    while let Some(m) = reader.next_message() {
        let m = match m {
            Ok(m) => m,
            // One message that does not decode (a corrupt payload, a big-endian CDR
            // message) is skipped and counted: a user wants the rest of the log. Errors
            // of the container itself end the read.
            Err(e @ fusemap_io::Error::Format { location: fusemap_io::Location::Message { .. }, .. }) => {
                undecodable.malformed(e.to_string());
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        match m {
            LogMessage::Scan(s) => log.scans.entry(s.topic.clone()).or_default().push(s),
            LogMessage::Odometry(o) => log.odom.entry(o.topic.clone()).or_default().push(o),
            LogMessage::Tf(t) => tf.push(t),
            LogMessage::Imu(i) => *log.imu.entry(i.topic).or_default() += 1,
            LogMessage::Gnss(_) | LogMessage::Pose(_) => {}
        }
    }
    log.stats = reader.stats().clone();
    for e in undecodable.malformed_examples {
        log.stats.malformed(e);
    }
    log.stats.malformed += undecodable.malformed - undecodable.malformed.min(10);
    if opened.format != fusemap_io::log::LogFormat::Carmen {
        // ROS containers are played back in log-time order (what `rosbag play` and
        // `ros2 bag play` do), whatever order their chunks hold the records in. CARMEN
        // text is kept in file order: the logger wrote it in that order.
        for v in log.scans.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        for v in log.odom.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        tf.sort_by_key(|m| m.receive_stamp);
    }
    for t in tf {
        if t.is_static {
            log.tf_static.extend(t.transforms);
        } else {
            log.tf_dynamic.extend(t.transforms);
        }
    }
    log.decode_s = t0.elapsed().as_secs_f64();
    Ok(log)
}

/// The scan topic to map: the configured one, else the only one, else CARMEN's front laser.
pub fn choose_scan_topic(log: &LoadedLog, cfg: &LogConfig, notes: &mut Vec<String>) -> Result<String> {
    if log.scans.contains_key(&cfg.scan_topic) {
        return Ok(cfg.scan_topic.clone());
    }
    for preferred in ["FLASER", "ROBOTLASER1", "RAWLASER1"] {
        if log.scans.contains_key(preferred) {
            return Ok(preferred.to_string());
        }
    }
    match log.scans.keys().collect::<Vec<_>>().as_slice() {
        [] if log.stats.malformed > 0 => bail!(
            "the log holds no usable laser scans; {} records could not be decoded, the first: {}",
            log.stats.malformed,
            log.stats.malformed_examples.first().map_or("", |s| s.as_str())
        ),
        [] => bail!("the log holds no laser scans"),
        [only] => {
            notes.push(format!("scan topic `{}` not in the log; using its only scan topic `{only}`", cfg.scan_topic));
            Ok((*only).clone())
        }
        many => bail!(
            "scan topic `{}` not in the log, which has several: {}; set log.scan_topic",
            cfg.scan_topic,
            many.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// The odometry topic: the configured one, CARMEN's `ODOM`, or the only one.
pub fn choose_odom_topic(log: &LoadedLog, cfg: &LogConfig) -> Option<String> {
    if log.odom.contains_key(&cfg.odom_topic) {
        return Some(cfg.odom_topic.clone());
    }
    if log.odom.contains_key("ODOM") {
        return Some("ODOM".into());
    }
    (log.odom.len() == 1).then(|| log.odom.keys().next().cloned()).flatten()
}

/// Counters of the pose track.
#[derive(Debug, Default, Serialize)]
pub struct TrackCounts {
    /// Samples offered.
    pub samples: u64,
    /// Samples kept.
    pub used: u64,
    /// Same stamp as an earlier sample (the first one is kept).
    pub duplicates: u64,
    /// Arrived after a sample with a later stamp: put back in stamp order and used.
    pub reordered: u64,
    /// NaN or infinite poses.
    pub not_finite: u64,
}

/// Where scans get their poses.
pub enum Track {
    /// From each scan line.
    ScanLine,
    /// From a time-indexed buffer.
    Buffer(PoseBuffer),
}

/// Builds the pose track for `source` (resolved from `auto`).
pub fn build_track(
    log: &LoadedLog,
    cfg: &LogConfig,
    scans: &[ScanMessage],
    counts: &mut TrackCounts,
) -> Result<(PoseSource, Track, String)> {
    let odom_topic = choose_odom_topic(log, cfg);
    let has_tf = log.tf_dynamic.iter().any(|t| t.child == cfg.base_frame);
    let source = match cfg.pose_source {
        PoseSource::Auto if scans.iter().any(|s| s.pose.is_some()) => PoseSource::ScanLine,
        PoseSource::Auto if odom_topic.is_some() => PoseSource::Odometry,
        PoseSource::Auto if has_tf => PoseSource::Tf,
        PoseSource::Auto => {
            bail!("the log has no poses: no pose on scan lines, no odometry topic, no TF to `{}`", cfg.base_frame)
        }
        s => s,
    };
    let mut buffer = PoseBuffer::new(cfg.max_pose_gap_s)
        .bridging_gaps(cfg.gap_bridge_motion_m, cfg.gap_bridge_motion_deg.to_radians());
    // The samples in stamp order (stable: equal stamps keep their log order).
    let mut fill = |samples: Vec<(Stamp, Pose2)>, counts: &mut TrackCounts| {
        counts.samples += samples.len() as u64;
        counts.reordered += count_reordered(samples.iter().map(|s| s.0));
        let mut samples = samples;
        samples.sort_by_key(|s| s.0);
        for (stamp, pose) in samples {
            match buffer.push(stamp, pose) {
                PushOutcome::Added => counts.used += 1,
                PushOutcome::Duplicate => counts.duplicates += 1,
                PushOutcome::NotFinite => counts.not_finite += 1,
                PushOutcome::OutOfOrder => unreachable!("the samples are sorted by stamp"),
            }
        }
    };
    let name = match source {
        PoseSource::ScanLine => {
            if !scans.iter().any(|s| s.pose.is_some()) {
                bail!("log.pose_source = \"scan_line\" but the scans carry no pose");
            }
            return Ok((source, Track::ScanLine, "pose on each scan line".into()));
        }
        PoseSource::Odometry => {
            let Some(topic) = odom_topic else {
                bail!("log.pose_source = \"odometry\" but the log has no odometry topic `{}`", cfg.odom_topic)
            };
            fill(log.odom[&topic].iter().map(|o| (o.stamp, o.pose)).collect(), counts);
            format!("odometry `{topic}`")
        }
        PoseSource::Tf => {
            let samples = log.tf_dynamic.iter().filter(|t| t.child == cfg.base_frame).map(|t| {
                let m = Mount3::from_translation_quaternion(t.translation, t.rotation);
                (t.stamp, Pose2::new(m.x, m.y, m.yaw))
            });
            fill(samples.collect(), counts);
            format!("TF `… → {}`", cfg.base_frame)
        }
        PoseSource::Auto => unreachable!("resolved above"),
    };
    if buffer.is_empty() {
        bail!("the pose source ({name}) holds no usable pose");
    }
    Ok((source, Track::Buffer(buffer), name))
}

/// How many of `stamps` (in log order) come after a later stamp.
pub fn count_reordered(stamps: impl IntoIterator<Item = Stamp>) -> u64 {
    let mut latest: Option<Stamp> = None;
    let mut n = 0;
    for s in stamps {
        match latest {
            Some(l) if s < l => n += 1,
            _ => latest = Some(s),
        }
    }
    n
}

/// The scans in the order they are inserted: stamp order (stable) for a pose track, log
/// order for poses on the scan lines (which do not depend on the stamps; some corrected
/// CARMEN logs have broken or all-zero stamps).
pub fn insertion_order<'a>(scans: &'a [ScanMessage], track: &Track) -> Vec<&'a ScanMessage> {
    let mut v: Vec<&ScanMessage> = scans.iter().collect();
    if matches!(track, Track::Buffer(_)) {
        v.sort_by_key(|s| s.scan.stamp);
    }
    v
}

/// The transform `base_from_frame` through the static TF tree (either direction per edge).
pub fn static_chain(transforms: &[Transform], base: &str, frame: &str) -> Option<Pose3> {
    let mut edges: HashMap<&str, Vec<(&str, Pose3)>> = HashMap::new();
    for t in transforms {
        let p = Pose3::new(t.translation, t.rotation);
        edges.entry(t.parent.as_str()).or_default().push((t.child.as_str(), p));
        edges.entry(t.child.as_str()).or_default().push((t.parent.as_str(), p.inverse()));
    }
    let mut seen: HashMap<&str, Pose3> = HashMap::from([(base, Pose3::IDENTITY)]);
    let mut queue = VecDeque::from([base]);
    while let Some(f) = queue.pop_front() {
        let here = seen[f];
        if f == frame {
            return Some(here);
        }
        for (next, p) in edges.get(f).into_iter().flatten() {
            if !seen.contains_key(next) {
                seen.insert(next, here.compose(p));
                queue.push_back(next);
            }
        }
    }
    None
}

/// What was decided about the laser's mount.
#[derive(Debug, Serialize)]
pub struct ExtrinsicsReport {
    /// `tf_static`, `scan_line` (CARMEN ROBOTLASER1) or `config`.
    pub source: String,
    /// The mount used.
    pub base_from_laser: Mount3,
    /// The log's own mount, when it has one.
    pub from_log: Option<Mount3>,
    /// |translation difference| between log and config, metres.
    pub translation_difference_m: Option<f64>,
    /// |yaw difference| between log and config, degrees.
    pub yaw_difference_deg: Option<f64>,
}

/// Resolves the mount of the laser of `frame`.
pub fn extrinsics(
    log: &LoadedLog,
    cfg: &LogConfig,
    config_mount: Mount3,
    compare: bool,
    frame: &str,
    scans: &[ScanMessage],
    notes: &mut Vec<String>,
) -> Result<ExtrinsicsReport> {
    let from_tf = if frame.is_empty() {
        None
    } else {
        static_chain(&log.tf_static, &cfg.base_frame, frame)
            .or_else(|| static_chain(&log.tf_dynamic, &cfg.base_frame, frame))
            .map(|p| p.to_mount())
    };
    let from_line = scans.iter().find_map(|s| match (s.pose, s.laser_pose) {
        (Some(robot), Some(laser)) => {
            let p = robot.inverse() * laser;
            Some(Mount3 { x: p.x, y: p.y, yaw: p.theta, ..Default::default() })
        }
        _ => None,
    });
    let (log_mount, log_name) = match (from_tf, from_line) {
        (Some(m), _) => (Some(m), "tf"),
        (None, Some(m)) => (Some(m), "scan_line"),
        (None, None) => (None, "none"),
    };
    let (mut dt, mut dyaw) = (None, None);
    if let Some(m) = log_mount {
        let t = (m.x - config_mount.x).hypot(m.y - config_mount.y);
        let y = normalize_angle(m.yaw - config_mount.yaw).abs().to_degrees();
        dt = Some(t);
        dyaw = Some(y);
        if compare && (t > cfg.extrinsics_tolerance_m || y > cfg.extrinsics_tolerance_deg) {
            notes.push(format!(
                "the log's mount of `{frame}` ({log_name}: x {:.3}, y {:.3}, yaw {:.2}°) differs from the config's \
                 (x {:.3}, y {:.3}, yaw {:.2}°) by {t:.3} m and {y:.2}° (tolerances {} m, {}°)",
                m.x,
                m.y,
                m.yaw.to_degrees(),
                config_mount.x,
                config_mount.y,
                config_mount.yaw.to_degrees(),
                cfg.extrinsics_tolerance_m,
                cfg.extrinsics_tolerance_deg
            ));
        }
    }
    let (source, mount) = match (cfg.extrinsics, log_mount) {
        (ExtrinsicsSource::Config, _) | (ExtrinsicsSource::Auto, None) => ("config".to_string(), config_mount),
        (ExtrinsicsSource::Auto | ExtrinsicsSource::Tf, Some(m)) => (log_name.to_string(), m),
        (ExtrinsicsSource::Tf, None) => {
            bail!("log.extrinsics = \"tf\" but the log has no transform {} → `{frame}`", cfg.base_frame)
        }
    };
    Ok(ExtrinsicsReport {
        source,
        base_from_laser: mount,
        from_log: log_mount,
        translation_difference_m: dt,
        yaw_difference_deg: dyaw,
    })
}

/// Scans skipped, by reason.
#[derive(Debug, Default, Serialize)]
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
    }
}

/// The log part of `summary.json`.
#[derive(Debug, Serialize)]
pub struct LogReport {
    /// Detected format.
    pub format: String,
    /// The scan topic mapped.
    pub scan_topic: String,
    /// Where poses came from.
    pub pose_source: String,
    /// `interpolate` or `nearest (tolerance s)`.
    pub sync: String,
    /// Whether beams were de-skewed.
    pub deskew: bool,
    /// Scans in the topic.
    pub scans_read: u64,
    /// Scans mapped.
    pub scans_used: u64,
    /// Scans skipped, by reason.
    pub scans_skipped: Skipped,
    /// Scans de-skewed beam by beam.
    pub scans_deskewed: u64,
    /// Scans inserted out of log order, after a later-stamped one (pose tracks map in
    /// stamp order).
    pub scans_reordered: u64,
    /// The pose track's counters.
    pub pose_track: TrackCounts,
    /// Timing of the scan stream.
    pub scan_timing: StreamTiming,
    /// Timing of the pose stream (odometry or TF), when it is one.
    pub pose_timing: Option<StreamTiming>,
    /// The laser mount.
    pub extrinsics: ExtrinsicsReport,
    /// Records skipped by type.
    pub skipped_by_type: BTreeMap<String, u64>,
    /// Malformed records skipped.
    pub malformed_records: u64,
    /// Seconds reading and decoding.
    pub decode_s: f64,
    /// Seconds inserting.
    pub map_s: f64,
}

/// The sync mode from the config, with the nearest tolerance resolved (half the median
/// period of `scans`, taken in stamp order as the scans are mapped).
pub fn sync_mode(cfg: &LogConfig, scans: &[ScanMessage]) -> SyncMode {
    match cfg.sync {
        SyncConfig::Interpolate => SyncMode::Interpolate,
        SyncConfig::Nearest => {
            let tol = if cfg.nearest_tolerance_s > 0.0 {
                cfg.nearest_tolerance_s
            } else {
                let mut h: Vec<Stamp> = scans.iter().map(|s| s.scan.stamp).collect();
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

/// The timing of a topic's header stamps.
pub fn scan_stream_timing(scans: &[ScanMessage], cfg: &LogConfig) -> StreamTiming {
    let h: Vec<Stamp> = scans.iter().map(|s| s.scan.stamp).collect();
    let r: Vec<Option<Stamp>> = scans.iter().map(|s| s.receive_stamp).collect();
    StreamTiming::analyze(&h, &r, TimingLimits { gap_s: cfg.max_pose_gap_s, far_delay_s: cfg.far_delay_s })
}

/// Runs the whole log pipeline and writes the outputs.
pub fn run(plan: &Plan, config_given: bool, path: &Path, out: &Path, inputs: &[PathBuf]) -> Result<Summary> {
    let started = Instant::now();
    let files = output::prepare(out, inputs)?;
    let mut plan = plan.clone();
    if !config_given {
        // Defaults suited to a typical indoor 2D lidar rather than the document's 10 m corridor.
        for l in plan.lidars.iter_mut() {
            let mut p = *l.model.params();
            p.max_range = 40.0;
            l.model = LidarModel::new(p, *l.model.mount());
        }
    }
    let cfg = plan.log.clone();
    // fusemap-io errors already name the file (and the line or message): no context.
    let log = load(path)?;
    let mut notes = Vec::new();
    let topic = choose_scan_topic(&log, &cfg, &mut notes)?;
    let scans = &log.scans[&topic];
    let frame = scans.iter().find(|s| !s.frame_id.is_empty()).map(|s| s.frame_id.clone()).unwrap_or_default();

    let mut track_counts = TrackCounts::default();
    let (source, track, source_name) = build_track(&log, &cfg, scans, &mut track_counts)?;
    let scan_timing = scan_stream_timing(scans, &cfg);
    let pose_timing = match &track {
        Track::Buffer(_) => {
            let limits = TimingLimits { gap_s: cfg.max_pose_gap_s, far_delay_s: cfg.far_delay_s };
            match source {
                PoseSource::Odometry => choose_odom_topic(&log, &cfg).map(|t| {
                    let o = &log.odom[&t];
                    let h: Vec<Stamp> = o.iter().map(|m| m.stamp).collect();
                    let r: Vec<Option<Stamp>> = o.iter().map(|m| m.receive_stamp).collect();
                    StreamTiming::analyze(&h, &r, limits)
                }),
                _ => {
                    let h: Vec<Stamp> =
                        log.tf_dynamic.iter().filter(|t| t.child == cfg.base_frame).map(|t| t.stamp).collect();
                    Some(StreamTiming::analyze(&h, &[], limits))
                }
            }
        }
        Track::ScanLine => None,
    };
    let mode = sync_mode(&cfg, scans);

    // The laser's mount: from the log's TF / scan lines or the config.
    let config_mount = plan.lidars[0].mount;
    // Without a config file there is no mount of the user's to check the log's against.
    let ext = extrinsics(&log, &cfg, config_mount, config_given, &frame, scans, &mut notes)?;
    let mut lidar = plan.lidars[0].clone();
    let planar: PlanarMount = ext
        .base_from_laser
        .to_planar(lidar.max_tilt)
        .map_err(|e| anyhow::anyhow!("laser mount ({}): {e}", ext.source))?;
    lidar.model = LidarModel::new(*lidar.model.params(), planar);
    lidar.mount = ext.base_from_laser;
    plan.lidars = vec![lidar];

    let mut engine = engine_for(&plan);
    let laser = SensorId(0);
    let mut skipped = Skipped::default();
    let mut deskewed = 0u64;
    let mut last: Option<Stamp> = None;
    let t_map = Instant::now();
    let pb = progress(scans.len() as u64, "mapping");
    let mut scan = fusemap_core::sensor::LaserScan {
        stamp: Stamp::ZERO,
        angle_min: 0.0,
        angle_increment: 0.0,
        ranges: Vec::new(),
    };
    let scans_reordered = match track {
        Track::Buffer(_) => count_reordered(scans.iter().map(|s| s.scan.stamp)),
        Track::ScanLine => 0,
    };
    for msg in insertion_order(scans, &track) {
        pb.inc(1);
        let stamp = msg.scan.stamp;
        // Angles at LaserScan's float32 precision whatever the format, so that the same
        // scan read from CARMEN text or from a ROS message gives the same rays.
        scan.angle_min = msg.scan.angle_min as f32 as f64;
        scan.angle_increment = msg.scan.angle_increment as f32 as f64;
        scan.ranges.clone_from(&msg.scan.ranges);
        match &track {
            Track::ScanLine => {
                let Some(pose) = msg.pose.filter(|p| p.is_finite()) else {
                    skipped.no_pose_on_line += 1;
                    continue;
                };
                // Line poses do not depend on the stamp: apply in file order (some
                // corrected CARMEN logs have broken or all-zero stamps).
                scan.stamp = last.map_or(stamp, |l| l.max(stamp));
                engine.insert_scan_limited(laser, &scan, msg.range_min, msg.range_max, |_| pose)?;
            }
            Track::Buffer(buf) => {
                let pose = match buf.pose_at(stamp, mode) {
                    Ok(p) => p,
                    Err(why) => {
                        skipped.count(why);
                        continue;
                    }
                };
                scan.stamp = stamp;
                let n = scan.ranges.len();
                let ti = msg.time_increment as f64;
                let can_deskew = cfg.deskew && mode == SyncMode::Interpolate && ti > 0.0 && n > 1;
                let end = Stamp(stamp.0 + (ti * (n - 1) as f64 * 1e9) as i64);
                if can_deskew && buf.interpolate(end).is_ok() {
                    deskewed += 1;
                    engine.insert_scan_limited(laser, &scan, msg.range_min, msg.range_max, |i| {
                        let t = Stamp(stamp.0 + (ti * i as f64 * 1e9) as i64);
                        buf.interpolate(t).unwrap_or(pose)
                    })?;
                } else {
                    engine.insert_scan_limited(laser, &scan, msg.range_min, msg.range_max, |_| pose)?;
                }
            }
        }
        last = Some(last.map_or(stamp, |l| l.max(stamp)));
    }
    pb.finish_and_clear();
    let map_s = t_map.elapsed().as_secs_f64();

    if scan_timing.regressions > 0 {
        let order = if scans_reordered > 0 {
            format!(": {scans_reordered} scans mapped in stamp order")
        } else {
            String::new()
        };
        notes.push(format!("`{topic}` stamps go backwards {} times{order}", scan_timing.regressions));
    }
    if skipped.total() > 0 {
        notes.push(format!("{} of {} scans skipped without a pose", skipped.total(), scans.len()));
    }
    if log.stats.malformed > 0 {
        notes.push(format!(
            "{} malformed records skipped; first: {}",
            log.stats.malformed,
            log.stats.malformed_examples.join("; ")
        ));
    }
    let report = LogReport {
        format: log.format.clone(),
        scan_topic: topic.clone(),
        pose_source: source_name,
        sync: match mode {
            SyncMode::Interpolate => "interpolate".into(),
            SyncMode::Nearest { tolerance_s } => format!("nearest (tolerance {tolerance_s:.3} s)"),
        },
        deskew: deskewed > 0,
        scans_read: scans.len() as u64,
        scans_used: engine.stats().measurements,
        scans_skipped: skipped,
        scans_deskewed: deskewed,
        scans_reordered,
        pose_track: track_counts,
        scan_timing,
        pose_timing,
        extrinsics: ext,
        skipped_by_type: log.stats.skipped_by_type.clone(),
        malformed_records: log.stats.malformed,
        decode_s: log.decode_s,
        map_s,
    };
    let value = serde_json::to_value(&report)?;
    finish(&engine, &files, &log.format, &path.display().to_string(), started, notes, Some(value))
}
