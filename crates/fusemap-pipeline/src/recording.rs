//! A recording read in two passes, never whole.
//!
//! The first pass ([`Inventory::read`]) goes through every message once and keeps only
//! what is small: the pose sensors' samples (odometry, IMU, GNSS, poses, transforms), which
//! the estimator and its smoother need over the whole log, and for each scan topic its
//! stamps and frame ids (for the timing report and the choice of topics) — not the scans.
//! The second pass ([`for_each_range_message`]) streams the range sensors' messages of the chosen
//! topics to the mapper through the time-ordered merge. Peak memory is the pose streams
//! plus one merge window of scans, whatever the number of scans.

use fusemap_core::config::LimitsConfig;
use fusemap_core::estimator::share_repeated;
use fusemap_core::geometry::Pose2;
use fusemap_core::time::{plausible_samples, MotionLimits, Stamp};
use fusemap_io::log::{
    CameraInfoMessage, GnssMessage, ImageHeader, ImageMessage, ImuMessage, LogFormat, LogMessage, OdomMessage,
    PoseMessage, ReadOptions, ReadStats, ScanMessage, Transform,
};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// What the first pass learnt about one scan topic.
#[derive(Clone, Debug, Default)]
pub struct ScanTopic {
    /// Header stamps in log order.
    pub stamps: Vec<Stamp>,
    /// Receive stamps in log order, where the format has them.
    pub receive: Vec<Option<Stamp>>,
    /// Frame ids seen, with their counts.
    pub frames: BTreeMap<String, u64>,
    /// Scans that carry a pose on their line (CARMEN).
    pub with_pose: u64,
    /// Of those, lines whose pose is their raw odometry pose (a raw CARMEN log: nothing
    /// has corrected it, so SLAM should).
    pub pose_is_odometry: u64,
    /// The first (robot pose, laser pose) pair of a line that carries both (CARMEN
    /// `ROBOTLASER1`), from which the mount follows.
    pub first_laser_pose: Option<(Pose2, Pose2)>,
    /// The finite poses on the scan lines in file order, each with its stamp (24 + 8
    /// bytes a scan, for the pose-glitch check).
    pub line_poses: Vec<(Stamp, Pose2)>,
    /// The span of the readings that can be returns (of the scans with usable angles).
    pub readings: ReadingSpan,
    /// Scans whose angles cannot be used (`ScanMessage::angle_fault`), with the first
    /// reason: the mapping pass skips them.
    pub angle_faults: (u64, Option<String>),
}

/// What a scan topic's readings could observe: the readings that can be returns (finite,
/// positive, at or above the message's `range_min` and below its `range_max` where it
/// states them) with the nearest and the farthest, and the no-returns (finite, at or
/// beyond `range_max`). Kept so that `doctor`, which maps nothing, can tell a topic that
/// could observe no cell (every reading NaN, infinite, zero or a no-return) as `map`
/// would find it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadingSpan {
    /// Readings that can be returns.
    pub returns: u64,
    /// The nearest of them, metres.
    pub nearest: f32,
    /// The farthest of them, metres.
    pub farthest: f32,
    /// Finite readings at or beyond the message's `range_max`.
    pub no_returns: u64,
}

impl ReadingSpan {
    /// Takes one scan's readings in.
    fn add(&mut self, ranges: &[f32], range_min: f32, range_max: f32) {
        let stated = |v: f32| v.is_finite() && v > 0.0;
        let min = if stated(range_min) { range_min } else { 0.0 };
        let max = if stated(range_max) { range_max } else { f32::INFINITY };
        for &r in ranges {
            if !r.is_finite() || r <= 0.0 {
                continue;
            }
            if r >= max {
                self.no_returns += 1;
            } else if r >= min {
                if self.returns == 0 {
                    (self.nearest, self.farthest) = (r, r);
                }
                self.returns += 1;
                self.nearest = self.nearest.min(r);
                self.farthest = self.farthest.max(r);
            }
        }
    }

    /// False when `model` would take no reading as evidence: no return inside its
    /// `[min_range, max_range)`, and no no-return its `clear` policy would use.
    pub fn could_observe(&self, model: &fusemap_core::sensor::lidar::LidarModel) -> bool {
        let p = model.params();
        let clears = p.max_range_policy == fusemap_core::sensor::lidar::MaxRangePolicy::Clear;
        if clears && self.returns + self.no_returns > 0 {
            return true;
        }
        self.returns > 0 && f64::from(self.nearest) < p.max_range && f64::from(self.farthest) >= p.min_range
    }
}

impl ScanTopic {
    /// Takes a scan's stamps, frame id and line pose into the inventory.
    fn add(&mut self, s: ScanMessage) {
        match s.angle_fault() {
            Some(why) => {
                self.angle_faults.0 += 1;
                self.angle_faults.1.get_or_insert(why);
            }
            None => self.readings.add(&s.scan.ranges, s.range_min, s.range_max),
        }
        self.stamps.push(s.scan.stamp);
        self.receive.push(s.receive_stamp);
        *self.frames.entry(s.frame_id).or_default() += 1;
        if let Some(p) = s.pose {
            self.with_pose += 1;
            if p.is_finite() {
                self.line_poses.push((s.scan.stamp, p));
            }
            if s.odom_pose == Some(p) {
                self.pose_is_odometry += 1;
            }
        }
        if self.first_laser_pose.is_none() {
            if let (Some(r), Some(l)) = (s.pose, s.laser_pose) {
                self.first_laser_pose = Some((r, l));
            }
        }
    }

    /// The scan-line poses that are glitches (see [`plausible_samples`]), as
    /// `(stamp, pose)` keys of [`line_key`]. The lines are judged in file order, the order
    /// their poses are applied in (a stamp that goes backwards is taken as its
    /// predecessor's).
    pub fn line_glitches(&self, limits: &MotionLimits) -> HashSet<LineKey> {
        let mut last = Stamp(i64::MIN);
        let ordered: Vec<(Stamp, Pose2)> = self
            .line_poses
            .iter()
            .map(|&(t, p)| {
                last = last.max(t);
                (last, p)
            })
            .collect();
        let keep = plausible_samples(&ordered, limits);
        self.line_poses.iter().zip(keep).filter(|(_, k)| !k).map(|(&(t, p), _)| line_key(t, p)).collect()
    }

    /// The most common non-empty frame id.
    pub fn frame(&self) -> Option<&str> {
        self.frames.iter().filter(|(f, _)| !f.is_empty()).max_by_key(|(_, n)| **n).map(|(f, _)| f.as_str())
    }
}

/// A scan line's stamp and pose, bit for bit: how a rejected line is recognised again in
/// the mapping pass.
pub type LineKey = (i64, [u64; 3]);

/// The [`LineKey`] of a line.
pub fn line_key(t: Stamp, p: Pose2) -> LineKey {
    (t.0, [p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()])
}

/// What the first pass learnt about one image topic (headers only: pixels are read in the
/// second pass, and only for the topics a camera uses).
#[derive(Clone, Debug, Default)]
pub struct ImageTopic {
    /// Header stamps in log order.
    pub stamps: Vec<Stamp>,
    /// Receive stamps in log order, where the format has them.
    pub receive: Vec<Option<Stamp>>,
    /// Frame ids seen, with their counts.
    pub frames: BTreeMap<String, u64>,
    /// Encodings seen, with their counts.
    pub encodings: BTreeMap<String, u64>,
    /// Image sizes seen (width, height), with their counts.
    pub sizes: BTreeMap<(u32, u32), u64>,
}

impl ImageTopic {
    /// Takes an image's stamps, frame id, encoding and size into the inventory.
    fn add(&mut self, h: ImageHeader) {
        self.stamps.push(h.stamp);
        self.receive.push(h.receive_stamp);
        *self.frames.entry(h.frame_id).or_default() += 1;
        *self.encodings.entry(h.encoding).or_default() += 1;
        *self.sizes.entry((h.width, h.height)).or_default() += 1;
    }

    /// The most common non-empty frame id.
    pub fn frame(&self) -> Option<&str> {
        self.frames.iter().filter(|(f, _)| !f.is_empty()).max_by_key(|(_, n)| **n).map(|(f, _)| f.as_str())
    }
}

/// What the first pass kept of one camera-info topic: the calibration is small but
/// repeated with every frame, so the first message is kept and the others compared.
#[derive(Clone, Debug)]
pub struct CameraInfoTopic {
    /// The first message (by stamp).
    pub first: CameraInfoMessage,
    /// Messages read.
    pub count: u64,
    /// Messages whose size, distortion or K differ from the first.
    pub differing: u64,
}

/// One odometry message as the pipeline keeps it: what the pose track and the estimator
/// need, not the whole message (a ten-minute log at 50 Hz is 30,000 of these). Covariances
/// are shared with the previous sample when equal ([`share_repeated`]).
#[derive(Clone, Debug, PartialEq)]
pub struct OdomSample {
    /// Header stamp.
    pub stamp: Stamp,
    /// Log/receive time.
    pub receive_stamp: Option<Stamp>,
    /// `odom_from_base` (NaN when the quaternion was zero or not finite).
    pub pose: Pose2,
    /// The (x, y, yaw) block of the message's pose covariance, when usable.
    pub covariance: Option<Arc<[[f64; 3]; 3]>>,
}

/// One IMU message as the pipeline keeps it (an hour at 100 Hz is 360,000 of these; the
/// rate covariance is shared with the previous sample when equal).
#[derive(Clone, Debug, PartialEq)]
pub struct ImuSample {
    /// Header stamp.
    pub stamp: Stamp,
    /// Log/receive time.
    pub receive_stamp: Option<Stamp>,
    /// Angular velocity in the IMU's frame, rad/s.
    pub angular_velocity: [f64; 3],
    /// `angular_velocity_covariance`, row-major in the IMU's frame; `[0] = -1` means the
    /// message carries no rate (sensor_msgs/Imu).
    pub rate_covariance: Arc<[f64; 9]>,
    /// The orientation and `orientation_covariance[8]` (yaw variance), when the message
    /// provides one (REP 145).
    pub orientation: Option<([f64; 4], f64)>,
}

/// A ROS 6 × 6 row-major covariance's (x, y, yaw) block; `None` when it is not usable
/// (zero, NaN or negative variances).
pub fn planar_covariance(c: &[f64; 36]) -> Option<[[f64; 3]; 3]> {
    let idx = [0, 1, 5];
    let mut m = [[0.0; 3]; 3];
    for (r, &i) in idx.iter().enumerate() {
        for (k, &j) in idx.iter().enumerate() {
            m[r][k] = c[i * 6 + j];
        }
    }
    let ok = m.iter().flatten().all(|v| v.is_finite()) && (0..3).all(|i| m[i][i] > 0.0);
    ok.then_some(m)
}

impl OdomSample {
    /// The sample of `m`, its covariance shared with `previous`'s when equal.
    pub fn new(m: &OdomMessage, previous: Option<&OdomSample>) -> Self {
        let covariance = planar_covariance(&m.pose_covariance)
            .map(|c| share_repeated(previous.and_then(|p| p.covariance.as_ref()), c));
        Self { stamp: m.stamp, receive_stamp: m.receive_stamp, pose: m.pose, covariance }
    }
}

impl ImuSample {
    /// The sample of `m`, its rate covariance shared with `previous`'s when equal.
    pub fn new(m: &ImuMessage, previous: Option<&ImuSample>) -> Self {
        Self {
            stamp: m.stamp,
            receive_stamp: m.receive_stamp,
            angular_velocity: m.angular_velocity,
            rate_covariance: share_repeated(previous.map(|p| &p.rate_covariance), m.angular_velocity_covariance),
            orientation: m.has_orientation().then_some((m.orientation, m.orientation_covariance[8])),
        }
    }
}

/// The first pass over a recording: every pose sensor's messages, and an inventory of the
/// range sensors.
pub struct Inventory {
    /// The file.
    pub path: PathBuf,
    /// What every pass over the file is held to (`[limits]`: bytes one chunk, message or
    /// line may inflate to, beams of a scan, pixels of an image); no image pixels.
    pub limits: ReadOptions,
    /// Where the file ends early, when it does (the reader's words): the log is what came
    /// before, and the later passes stop there too.
    pub truncated: Option<String>,
    /// Its format.
    pub format: LogFormat,
    /// Scan topics.
    pub scans: BTreeMap<String, ScanTopic>,
    /// Image topics (headers only).
    pub images: BTreeMap<String, ImageTopic>,
    /// Camera-info topics.
    pub camera_info: BTreeMap<String, CameraInfoTopic>,
    /// Odometry by topic, in log order.
    pub odom: BTreeMap<String, Vec<OdomSample>>,
    /// IMU samples by topic, in log order.
    pub imu: BTreeMap<String, Vec<ImuSample>>,
    /// The frame id of each pose-sensor topic (its first message's).
    pub frames: BTreeMap<String, String>,
    /// GNSS fixes by topic, in log order.
    pub gnss: BTreeMap<String, Vec<GnssMessage>>,
    /// Absolute poses by topic, in log order.
    pub poses: BTreeMap<String, Vec<PoseMessage>>,
    /// Static transforms (`/tf_static`), in log order.
    pub tf_static: Vec<Transform>,
    /// Dynamic transforms (`/tf`), in log order.
    pub tf_dynamic: Vec<Transform>,
    /// What the reader skipped, plus the messages that did not decode.
    pub stats: ReadStats,
    /// Seconds spent in this pass.
    pub read_s: f64,
}

/// Reads the next message, turning an undecodable message into a counted skip. Errors of
/// the container itself end the read.
fn next(
    reader: &mut dyn fusemap_io::log::LogReader,
    undecodable: &mut ReadStats,
) -> Option<fusemap_io::Result<LogMessage>> {
    loop {
        match reader.next_message()? {
            Ok(m) => return Some(Ok(m)),
            // One message that does not decode (a corrupt payload, a big-endian CDR
            // message) is skipped and counted: a user wants the rest of the log.
            Err(e) if e.is_skippable() => {
                let description = e.to_string();
                if let Some(topic) = e.message_topic() {
                    undecodable.malformed_on(topic, &description);
                }
                undecodable.malformed(description);
            }
            Err(e) => return Some(Err(e)),
        }
    }
}

/// Merges the reader's own counters with the undecodable messages.
fn merged_stats(reader: &ReadStats, undecodable: ReadStats) -> ReadStats {
    let mut stats = reader.clone();
    for e in undecodable.malformed_examples {
        stats.malformed(e);
    }
    stats.malformed += undecodable.malformed - undecodable.malformed.min(10);
    for (topic, (n, first)) in undecodable.malformed_by_topic {
        let (m, _) = stats.malformed_by_topic.entry(topic).or_insert((0, first));
        *m += n;
    }
    stats
}

impl Inventory {
    /// The first pass over `path`, within the default `[limits]`.
    pub fn read(path: &Path) -> fusemap_io::Result<Inventory> {
        Self::read_with(path, &LimitsConfig::default())
    }

    /// The first pass over `path`; no chunk, message or line may inflate past
    /// `limits`, in this pass or the later ones.
    pub fn read_with(path: &Path, limits: &LimitsConfig) -> fusemap_io::Result<Inventory> {
        let t0 = Instant::now();
        let options = ReadOptions::within(limits);
        let opened = fusemap_io::log::open_log_with(path, &options)?;
        let mut reader = opened.reader;
        let mut inv = Inventory::empty(path, options, opened.format);
        let mut undecodable = ReadStats::default();
        let mut tf = Vec::new();
        let mut read = 0u64;
        while let Some(m) = next(reader.as_mut(), &mut undecodable) {
            // A recording cut short is the recording up to the cut: it is used as the log,
            // and the cut reported. A file that ends before one message is no log.
            let m = match m {
                Err(e) if e.is_truncation() && read > 0 => {
                    inv.truncated = Some(e.to_string());
                    break;
                }
                m => m?,
            };
            read += 1;
            match m {
                LogMessage::Scan(s) => inv.scans.entry(s.topic.clone()).or_default().add(s),
                LogMessage::Odometry(o) => {
                    inv.frames.entry(o.topic.clone()).or_insert_with(|| o.frame_id.clone());
                    let samples = inv.odom.entry(o.topic.clone()).or_default();
                    samples.push(OdomSample::new(&o, samples.last()));
                }
                LogMessage::Imu(i) => {
                    inv.frames.entry(i.topic.clone()).or_insert_with(|| i.frame_id.clone());
                    let samples = inv.imu.entry(i.topic.clone()).or_default();
                    samples.push(ImuSample::new(&i, samples.last()));
                }
                LogMessage::Gnss(g) => inv.gnss.entry(g.topic.clone()).or_default().push(g),
                LogMessage::Pose(p) => inv.poses.entry(p.topic.clone()).or_default().push(p),
                LogMessage::Tf(t) => tf.push(t),
                LogMessage::ImageHeader(h) => inv.images.entry(h.topic.clone()).or_default().add(h),
                // The first pass asks for no pixels; a reader that gives them anyway is
                // inventoried the same way.
                LogMessage::Image(i) => inv.images.entry(i.topic.clone()).or_default().add(i.header()),
                LogMessage::CameraInfo(c) => inv.add_camera_info(c),
            }
        }
        inv.stats = merged_stats(reader.stats(), undecodable);
        if inv.format != LogFormat::Carmen {
            // ROS containers are played back in log-time order (what `rosbag play` and
            // `ros2 bag play` do), whatever order their chunks hold the records in.
            inv.sort_by_log_time();
            tf.sort_by_key(|m| m.receive_stamp);
        }
        for t in tf {
            if t.is_static {
                inv.tf_static.extend(t.transforms);
            } else {
                inv.tf_dynamic.extend(t.transforms);
            }
        }
        inv.read_s = t0.elapsed().as_secs_f64();
        Ok(inv)
    }

    /// An inventory of nothing yet.
    fn empty(path: &Path, limits: ReadOptions, format: LogFormat) -> Self {
        Inventory {
            path: path.to_path_buf(),
            limits,
            format,
            scans: BTreeMap::new(),
            images: BTreeMap::new(),
            camera_info: BTreeMap::new(),
            odom: BTreeMap::new(),
            imu: BTreeMap::new(),
            frames: BTreeMap::new(),
            gnss: BTreeMap::new(),
            poses: BTreeMap::new(),
            tf_static: Vec::new(),
            tf_dynamic: Vec::new(),
            stats: ReadStats::default(),
            read_s: 0.0,
            truncated: None,
        }
    }

    /// Keeps a topic's first camera info (by stamp) and counts those that differ from it.
    fn add_camera_info(&mut self, c: CameraInfoMessage) {
        let Some(t) = self.camera_info.get_mut(&c.topic) else {
            self.camera_info.insert(c.topic.clone(), CameraInfoTopic { first: c, count: 1, differing: 0 });
            return;
        };
        t.count += 1;
        let f = &t.first;
        if (f.width, f.height) != (c.width, c.height)
            || f.distortion_model != c.distortion_model
            || f.d != c.d
            || f.k != c.k
        {
            t.differing += 1;
        }
        if c.stamp < t.first.stamp {
            t.first = c;
        }
    }

    /// Every stream in receive-stamp order (a stable sort: equal receive stamps keep their
    /// order in the file).
    fn sort_by_log_time(&mut self) {
        for v in self.odom.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        for v in self.imu.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        for v in self.gnss.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        for v in self.poses.values_mut() {
            v.sort_by_key(|m| m.receive_stamp);
        }
        let by_receive = |receive: &mut Vec<Option<Stamp>>, stamps: &mut Vec<Stamp>| {
            let mut pairs: Vec<(Option<Stamp>, Stamp)> = receive.iter().copied().zip(stamps.iter().copied()).collect();
            pairs.sort_by_key(|p| p.0);
            *receive = pairs.iter().map(|p| p.0).collect();
            *stamps = pairs.iter().map(|p| p.1).collect();
        };
        for t in self.images.values_mut() {
            by_receive(&mut t.receive, &mut t.stamps);
        }
        for t in self.scans.values_mut() {
            by_receive(&mut t.receive, &mut t.stamps);
        }
    }

    /// The note on the records the reader skipped as malformed, if it skipped any (the
    /// same words for `map`'s notes and `doctor`'s findings).
    pub fn malformed_note(&self) -> Option<String> {
        (self.stats.malformed > 0).then(|| {
            format!(
                "{} malformed records skipped; first: {}",
                self.stats.malformed,
                self.stats.malformed_examples.join("; ")
            )
        })
    }

    /// Total scans in the log.
    pub fn scan_count(&self) -> u64 {
        self.scans.values().map(|t| t.stamps.len() as u64).sum()
    }
}

/// A message the second pass maps: a scan, or an image with its pixels.
#[derive(Clone, Debug)]
pub enum RangeMessage {
    /// A laser scan.
    Scan(ScanMessage),
    /// A label or depth image.
    Image(ImageMessage),
}

/// The second pass over scans of `scan_topics` and images of `image_topics` (with their
/// pixels; other images are not decoded), in log order; nothing inflates past
/// the `limits` of the first pass.
pub fn for_each_range_message(
    path: &Path,
    limits: &ReadOptions,
    scan_topics: &[String],
    image_topics: &[String],
    mut f: impl FnMut(RangeMessage) -> Result<(), crate::PipelineError>,
) -> Result<f64, crate::PipelineError> {
    let t0 = Instant::now();
    let options = limits.clone().images_of(image_topics.iter().cloned());
    let opened = fusemap_io::log::open_log_with(path, &options)?;
    let mut reader = opened.reader;
    let mut ignored = ReadStats::default();
    while let Some(m) = next(reader.as_mut(), &mut ignored) {
        // The first pass met the same cut and reported it: the log ends here.
        let m = match m {
            Err(e) if e.is_truncation() => break,
            m => m?,
        };
        match m {
            LogMessage::Scan(s) if scan_topics.contains(&s.topic) => f(RangeMessage::Scan(s))?,
            LogMessage::Image(i) if image_topics.contains(&i.topic) => f(RangeMessage::Image(i))?,
            _ => {}
        }
    }
    Ok(t0.elapsed().as_secs_f64())
}

#[cfg(test)]
mod tests {
    use super::ReadingSpan;
    use fusemap_core::sensor::{LidarModel, LidarParams, MaxRangePolicy};

    fn model(min_range: f64, max_range: f64, policy: MaxRangePolicy) -> LidarModel {
        let p = LidarParams { min_range, max_range, max_range_policy: policy, ..Default::default() };
        LidarModel::new(p, Default::default())
    }

    #[test]
    fn a_span_tells_returns_from_readings_that_observe_nothing() {
        let mut s = ReadingSpan::default();
        s.add(&[f32::NAN, f32::INFINITY, 0.0, -1.0, 81.91, 81.91], 0.0, 81.91);
        assert_eq!((s.returns, s.no_returns), (0, 2));
        let skip = model(0.1, 10.0, MaxRangePolicy::Skip);
        assert!(!s.could_observe(&skip));
        // The no-returns clear free space under the `clear` policy.
        assert!(s.could_observe(&model(0.1, 10.0, MaxRangePolicy::Clear)));
        // Readings below the message's range_min are no returns of either kind.
        s.add(&[0.05], 0.1, 81.91);
        assert_eq!(s.returns, 0);
        s.add(&[3.0, 12.0], 0.0, f32::NAN);
        assert_eq!((s.returns, s.nearest, s.farthest), (2, 3.0, 12.0));
        assert!(s.could_observe(&skip));
        // Every return beyond the model's max_range, or below its min_range: nothing.
        assert!(!s.could_observe(&model(0.1, 2.5, MaxRangePolicy::Skip)));
        assert!(!s.could_observe(&model(20.0, 30.0, MaxRangePolicy::Skip)));
    }
}
