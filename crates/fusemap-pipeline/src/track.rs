//! Choosing and building the pose track a run maps with.
//!
//! `pose_source = "auto"` takes, in order: poses written on the scan lines (CARMEN
//! corrected logs), the estimator when the log carries an IMU, GNSS or absolute poses next
//! to its odometry, the odometry alone, dynamic TF to the base frame. With odometry alone,
//! `map = odom` (identity `map_from_odom`); the estimator gives `map_from_base` directly.
//!
//! With a pose track (odometry or TF), samples are taken in header-stamp order (the design
//! document's "time-sorted odometry and scans", §4.1), not in the order the log holds them:
//! a sample that arrives after a later-stamped one is still good data at its own stamp.

use crate::recording::Inventory;
use crate::sensors::{Bound, BoundSensor};
use crate::{PipelineError, Stage};
use fusemap_core::config::{LogConfig, PoseSource, SensorKind};
use fusemap_core::frames::{FrameTree, LookupError};
use fusemap_core::geometry::{Mount3, Pose2};
use fusemap_core::time::{plausible_samples, NoPose, PoseBuffer, PoseTrack, PushOutcome, Stamp, SyncMode};
use fusemap_io::log::Transform;
use serde::Serialize;
use std::collections::BTreeMap;

/// Counters of the pose track.
#[derive(Debug, Default, Clone, Serialize)]
pub struct TrackCounts {
    /// Samples offered.
    pub samples: u64,
    /// Samples kept.
    pub used: u64,
    /// Same stamp as an earlier sample (the first one is kept).
    pub duplicates: u64,
    /// Arrived after a sample with a later stamp: put back in stamp order and used.
    pub reordered: u64,
    /// NaN or infinite poses (a zero quaternion among them), and poses beyond 10⁹ m
    /// (`MAX_POSITION_M`: an odometry reset to garbage).
    pub not_finite: u64,
    /// Pose glitches: samples implying a motion beyond `log.max_speed_m_s` or
    /// `log.max_turn_rate_deg_s` from their neighbours, rejected.
    pub glitches: u64,
}

/// Where scans get their poses.
pub enum Track {
    /// From each scan line (CARMEN corrected logs), or, after SLAM over them, from the
    /// optimised pose of each line.
    ScanLine(Option<LinePoses>),
    /// From a time-indexed track.
    Timed(Box<dyn PoseTrack>),
}

/// The chosen track.
pub struct ChosenTrack {
    /// The source, resolved from `auto`.
    pub source: PoseSource,
    /// The track.
    pub track: Track,
    /// A name for reports (`odometry `/odom``).
    pub name: String,
    /// Its counters.
    pub counts: TrackCounts,
    /// The header stamps of the stream the track was built from (for the timing report).
    pub stamps: Vec<Stamp>,
    /// … and their receive stamps.
    pub receive: Vec<Option<Stamp>>,
    /// The estimator's report, when it made the track.
    pub estimator: Option<Box<crate::estimation_report::EstimationReport>>,
    /// Facts about the track a user should know.
    pub notes: Vec<String>,
    /// What SLAM did, when it corrected the track.
    pub slam: Option<Box<crate::slam_summary::SlamSummary>>,
    /// The odometry frame the track's poses were given in (REP 105's `odom`: an odometry
    /// topic's frame, or TF's root when it is `odom`), for `map → odom` in `map.mcap`;
    /// `None` for a track in the map frame already (the estimator, poses on scan lines).
    pub odom_frame: Option<String>,
}

/// SLAM's optimised poses of scan lines, found by the line's own stamp and pose: placed in
/// file order, one per scan, whatever the stamps (some logs print every stamp as the same
/// number, and a track by stamp would keep one pose of them all).
#[derive(Clone, Debug, Default)]
pub struct LinePoses {
    by_line: std::collections::HashMap<crate::recording::LineKey, Vec<Pose2>>,
    samples: Vec<(Stamp, Pose2)>,
}

impl LinePoses {
    /// From the lines' `(stamp, pose on the line)` and their optimised poses, in file order.
    pub fn new(lines: &[(Stamp, Pose2)], optimised: &[Pose2]) -> Self {
        let mut out = Self::default();
        for (&(t, line), &pose) in lines.iter().zip(optimised) {
            out.by_line.entry(crate::recording::line_key(t, line)).or_default().push(pose);
            out.samples.push((t, pose));
        }
        out
    }

    /// The optimised pose of the `k`-th line (0-based) with this stamp and line pose.
    pub fn pose(&self, t: Stamp, line: Pose2, k: usize) -> Option<Pose2> {
        self.by_line.get(&crate::recording::line_key(t, line))?.get(k).copied()
    }

    /// Every line's stamp and optimised pose, in file order.
    pub fn samples(&self) -> &[(Stamp, Pose2)] {
        &self.samples
    }

    /// The optimised pose at `t` interpolated between the nearest lines before and after
    /// it in time, for a scan SLAM did not place (a line whose pose was a glitch); `None`
    /// when no two lines with distinct stamps enclose `t` (an equal-stamp log).
    pub fn interpolated(&self, t: Stamp) -> Option<Pose2> {
        let before = self.samples.iter().filter(|s| s.0 < t).max_by_key(|s| s.0)?;
        let after = self.samples.iter().filter(|s| s.0 > t).min_by_key(|s| s.0)?;
        let f = (t.0 - before.0 .0) as f64 / (after.0 .0 - before.0 .0) as f64;
        Some(before.1.interpolate(after.1, f))
    }
}

/// `root_from_base` looked up in the frame tree at each stamp: the TF pose source when the
/// base frame hangs below more than one dynamic edge (`map ← odom ← base_link` with a
/// localiser publishing `map → odom`). Lookups interpolate every dynamic edge on the
/// chain at the stamp and never extrapolate.
pub struct TfTrack {
    tree: FrameTree,
    root: String,
    base: String,
    stamps: Vec<Stamp>,
}

impl TfTrack {
    /// The frame at the top of `base`'s chain in `tree`.
    pub fn root_of(tree: &FrameTree, base: &str) -> Option<String> {
        let mut f = base;
        let mut depth = 0;
        while let Some(p) = tree.parent(f) {
            f = p;
            depth += 1;
            if depth > 1000 {
                return None;
            }
        }
        (f != base).then(|| f.to_string())
    }
}

fn no_pose(e: LookupError) -> NoPose {
    match e {
        LookupError::BeforeSamples { by_s, .. } => NoPose::BeforeStart(by_s),
        LookupError::AfterSamples { by_s, .. } => NoPose::AfterEnd(by_s),
        LookupError::Gap { gap_s, limit_s, .. } => NoPose::Gap { gap_s, limit_s },
        _ => NoPose::Empty,
    }
}

impl PoseTrack for TfTrack {
    fn pose_at(&self, t: Stamp, _mode: SyncMode) -> Result<Pose2, NoPose> {
        let p = self.tree.lookup(&self.root, &self.base, t).map_err(no_pose)?;
        let m = p.to_mount();
        Ok(Pose2::new(m.x, m.y, m.yaw))
    }

    fn span(&self) -> Option<(Stamp, Stamp)> {
        Some((*self.stamps.first()?, *self.stamps.last()?))
    }

    fn samples(&self) -> Vec<(Stamp, Pose2)> {
        self.stamps.iter().filter_map(|&t| self.pose_at(t, SyncMode::Interpolate).ok().map(|p| (t, p))).collect()
    }
}

impl ChosenTrack {
    /// A track given by the caller (e.g. ground truth, or odometry placed in the map frame).
    pub fn given(name: impl Into<String>, track: Box<dyn PoseTrack>) -> Self {
        ChosenTrack {
            source: PoseSource::Auto,
            track: Track::Timed(track),
            name: name.into(),
            counts: TrackCounts::default(),
            stamps: Vec::new(),
            receive: Vec::new(),
            estimator: None,
            notes: Vec::new(),
            slam: None,
            odom_frame: None,
        }
    }
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

/// A buffer of `samples` put in stamp order (stable: equal stamps keep their log order, and
/// the first one is used), pose glitches left out and counted.
pub fn buffer_of(cfg: &LogConfig, samples: Vec<(Stamp, Pose2)>, counts: &mut TrackCounts) -> PoseBuffer {
    let mut buffer = PoseBuffer::new(cfg.max_pose_gap_s)
        .bridging_gaps(cfg.gap_bridge_motion_m, cfg.gap_bridge_motion_deg.to_radians());
    counts.samples += samples.len() as u64;
    counts.reordered += count_reordered(samples.iter().map(|s| s.0));
    let keep = plausible_samples(&samples, &cfg.motion_limits());
    counts.glitches += keep.iter().filter(|k| !**k).count() as u64;
    let mut samples: Vec<(Stamp, Pose2)> = samples.into_iter().zip(keep).filter_map(|(s, k)| k.then_some(s)).collect();
    samples.sort_by_key(|s| s.0);
    for (stamp, pose) in samples {
        match buffer.push(stamp, pose) {
            PushOutcome::Added => counts.used += 1,
            PushOutcome::Duplicate | PushOutcome::OutOfOrder => counts.duplicates += 1,
            PushOutcome::NotFinite => counts.not_finite += 1,
        }
    }
    buffer
}

/// The dynamic transforms of `all` without the glitches of the edges whose child is on
/// `chain` (each edge judged as its own pose stream, in x, y and yaw), and how many were
/// left out.
fn without_edge_glitches(all: &[Transform], chain: &[String], cfg: &LogConfig) -> (Vec<Transform>, u64) {
    let strip = |f: &str| f.strip_prefix('/').unwrap_or(f).to_string();
    let mut edges: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for (i, t) in all.iter().enumerate() {
        let child = strip(&t.child);
        if chain.contains(&child) {
            edges.entry((strip(&t.parent), child)).or_default().push(i);
        }
    }
    let mut drop = vec![false; all.len()];
    for indices in edges.values() {
        let samples: Vec<(Stamp, Pose2)> = indices
            .iter()
            .map(|&i| {
                let m = Mount3::from_translation_quaternion(all[i].translation, all[i].rotation);
                (all[i].stamp, Pose2::new(m.x, m.y, m.yaw))
            })
            .collect();
        for (&i, keep) in indices.iter().zip(plausible_samples(&samples, &cfg.motion_limits())) {
            drop[i] = !keep;
        }
    }
    let glitches = drop.iter().filter(|d| **d).count() as u64;
    let kept = all.iter().zip(&drop).filter(|(_, d)| !**d).map(|(t, _)| t.clone()).collect();
    (kept, glitches)
}

/// The note a run prints when `source` had pose glitches.
pub fn glitch_note(source: &str, glitches: u64, cfg: &LogConfig) -> String {
    format!(
        "{source}: {glitches} pose sample(s) rejected as glitches, implying more than log.max_speed_m_s = {} m/s or log.max_turn_rate_deg_s = {} °/s from their neighbours",
        cfg.max_speed_m_s, cfg.max_turn_rate_deg_s
    )
}

/// The notes on `source`'s samples left out: poses no robot can have, and glitches.
fn sample_notes(source: &str, counts: &TrackCounts, cfg: &LogConfig) -> Vec<String> {
    let glitches = (counts.glitches > 0).then(|| glitch_note(source, counts.glitches, cfg));
    unusable_note(source, counts).into_iter().chain(glitches).collect()
}

/// The note on `source`'s samples that are no pose at all, if any.
pub fn unusable_note(source: &str, counts: &TrackCounts) -> Option<String> {
    (counts.not_finite > 0).then(|| {
        format!(
            "{source}: {} pose sample(s) left out as NaN, infinite, or more than {:e} m from their frame's origin (a reset to garbage): the track has a gap there",
            counts.not_finite,
            fusemap_core::geometry::MAX_POSITION_M
        )
    })
}

/// Whether the log carries a sensor the estimator fuses beyond odometry.
pub fn has_fusion_sensors(bound: &Bound) -> bool {
    [SensorKind::Imu, SensorKind::Gnss, SensorKind::Pose].iter().any(|k| bound.first(*k).is_some())
}

/// Chooses and builds the pose track of a run. `estimate` builds the estimator's track
/// when the source is the estimator.
pub fn choose(
    inv: &Inventory,
    cfg: &LogConfig,
    bound: &Bound,
    estimate: impl FnOnce() -> Result<ChosenTrack, PipelineError>,
) -> Result<ChosenTrack, PipelineError> {
    let lines_have_poses = bound.lidars.iter().any(|l| inv.scans.get(&l.topic).is_some_and(|t| t.with_pose > 0));
    let odom = bound.first(SensorKind::WheelOdometry);
    let tf = TfChain::of(inv, cfg);
    let source = match cfg.pose_source {
        PoseSource::Auto if lines_have_poses => PoseSource::ScanLine,
        // The estimator's motion model is the wheel odometry: without it, TF is next.
        PoseSource::Auto if odom.is_some() && has_fusion_sensors(bound) => PoseSource::Estimator,
        PoseSource::Auto if odom.is_some() => PoseSource::Odometry,
        PoseSource::Auto if !tf.chain_stamps.is_empty() => PoseSource::Tf,
        PoseSource::Auto => {
            return Err(PipelineError::refused(
                Stage::Poses,
                format!(
                    "the log has no poses: no pose on scan lines, no odometry topic, no TF to `{}`",
                    cfg.base_frame
                ),
            ))
        }
        s => s,
    };
    match source {
        PoseSource::ScanLine if !lines_have_poses => {
            Err(PipelineError::refused(Stage::Poses, "log.pose_source = \"scan_line\" but the scans carry no pose"))
        }
        PoseSource::ScanLine => Ok(scan_line_track(inv, cfg, bound)),
        PoseSource::Odometry => {
            let Some(o) = odom else {
                return Err(PipelineError::refused(
                    Stage::Poses,
                    "log.pose_source = \"odometry\" but the log has no odometry topic",
                ));
            };
            odometry_track(inv, cfg, o)
        }
        PoseSource::Tf => tf.track(inv, cfg),
        PoseSource::Estimator => estimate(),
        PoseSource::Auto => unreachable!("resolved above"),
    }
}

impl ChosenTrack {
    /// A track of `source` with its counts, its message stamps, and the notes of its
    /// glitches.
    fn of(
        source: PoseSource,
        track: Track,
        name: String,
        counts: TrackCounts,
        (stamps, receive): (Vec<Stamp>, Vec<Option<Stamp>>),
        cfg: &LogConfig,
    ) -> Self {
        let notes = sample_notes(&name, &counts, cfg);
        ChosenTrack {
            source,
            track,
            name,
            notes,
            counts,
            stamps,
            receive,
            estimator: None,
            slam: None,
            odom_frame: None,
        }
    }
}

/// The poses on the scan lines.
fn scan_line_track(inv: &Inventory, cfg: &LogConfig, bound: &Bound) -> ChosenTrack {
    // The mapping pass leaves the glitches out (`Skipped::pose_glitch`); counted here for
    // the track's report.
    let mut counts = TrackCounts::default();
    for l in &bound.lidars {
        let topic = &inv.scans[&l.topic];
        counts.samples += topic.with_pose;
        counts.used += topic.line_poses.len() as u64;
        counts.not_finite += topic.with_pose - topic.line_poses.len() as u64;
        let glitches = topic.line_glitches(&cfg.motion_limits()).len() as u64;
        counts.used -= glitches;
        counts.glitches += glitches;
    }
    let name = "pose on each scan line".to_string();
    ChosenTrack::of(PoseSource::ScanLine, Track::ScanLine(None), name, counts, Default::default(), cfg)
}

/// The wheel odometry's poses, at their stamps with the sensor's time offset.
pub(crate) fn odometry_track(inv: &Inventory, cfg: &LogConfig, o: &BoundSensor) -> Result<ChosenTrack, PipelineError> {
    let mut counts = TrackCounts::default();
    let msgs = &inv.odom[&o.topic];
    let off = crate::offset_ns(o.sensor.time_offset_s);
    let samples = msgs.iter().map(|m| (Stamp(m.stamp.0.saturating_add(off)), m.pose)).collect();
    let buffer = buffer_of(cfg, samples, &mut counts);
    if buffer.is_empty() {
        return Err(PipelineError::refused(Stage::Poses, format!("the odometry `{}` holds no usable pose", o.topic)));
    }
    let stamps = (msgs.iter().map(|m| m.stamp).collect(), msgs.iter().map(|m| m.receive_stamp).collect());
    let name = format!("odometry `{}`", o.topic);
    let frame = inv.frames.get(&o.topic).map(|f| f.trim_start_matches('/')).filter(|f| !f.is_empty());
    Ok(ChosenTrack {
        odom_frame: Some(frame.unwrap_or("odom").to_string()),
        ..ChosenTrack::of(PoseSource::Odometry, Track::Timed(Box::new(buffer)), name, counts, stamps, cfg)
    })
}

/// The TF edges that pose the base frame: its own dynamic edge, and every dynamic edge on
/// its chain to the root (`odom → base_footprint → base_link` with a static last edge; a
/// leading `/`, as ROS 1 writes frames, is not part of the name).
struct TfChain {
    tree: FrameTree,
    base: String,
    /// The base frame and its ancestors, up to the root.
    chain: Vec<String>,
    /// The samples of the base frame's own dynamic edge.
    samples: Vec<(Stamp, Pose2)>,
    /// The stamps of every dynamic edge on the chain, sorted, without repeats.
    chain_stamps: Vec<Stamp>,
}

impl TfChain {
    fn of(inv: &Inventory, cfg: &LogConfig) -> Self {
        let strip = |f: &str| f.strip_prefix('/').unwrap_or(f).to_string();
        let base = strip(&cfg.base_frame);
        let (tree, _) = crate::extrinsics::frame_tree(cfg, &inv.tf_static, &inv.tf_dynamic);
        let mut chain = vec![base.clone()];
        while let Some(p) = tree.parent(chain.last().map_or("", |s| s.as_str())) {
            if chain.len() > 1000 || chain.iter().any(|c| c == p) {
                break;
            }
            chain.push(p.to_string());
        }
        let samples = inv
            .tf_dynamic
            .iter()
            .filter(|t| strip(&t.child) == base)
            .map(|t| {
                let m = Mount3::from_translation_quaternion(t.translation, t.rotation);
                (t.stamp, Pose2::new(m.x, m.y, m.yaw))
            })
            .collect();
        let mut chain_stamps: Vec<Stamp> =
            inv.tf_dynamic.iter().filter(|t| chain.contains(&strip(&t.child))).map(|t| t.stamp).collect();
        chain_stamps.sort_unstable();
        chain_stamps.dedup();
        TfChain { tree, base, chain, samples, chain_stamps }
    }

    /// The base frame's pose from TF: its own edge's samples when that is the one edge to
    /// the root, else the chain composed at each stamp of its dynamic edges.
    fn track(self, inv: &Inventory, cfg: &LogConfig) -> Result<ChosenTrack, PipelineError> {
        let mut counts = TrackCounts::default();
        let root = TfTrack::root_of(&self.tree, &self.base);
        let parent = self.tree.parent(&self.base).map(str::to_string);
        let single_edge = root.is_some() && root == parent && !self.samples.is_empty();
        // TF under `odom` is odometry (as SLAM takes it, `slam::applies`).
        let odom_frame = root.as_deref().map(|r| r.trim_start_matches('/')).filter(|r| *r == "odom").map(String::from);
        let no_pose = || PipelineError::refused(Stage::Poses, format!("no usable TF pose of `{}`", cfg.base_frame));
        if let (Some(root), false) = (root, single_edge) {
            // Several edges above the base, or a static one under a dynamic one: compose
            // the chain at each stamp where one of its dynamic edges has a sample. Each
            // dynamic edge of the chain is a pose stream of its own: its glitches are
            // left out before the tree is built again from what remains.
            let (kept, glitches) = without_edge_glitches(&inv.tf_dynamic, &self.chain, cfg);
            counts.glitches = glitches;
            let tree =
                if glitches > 0 { crate::extrinsics::frame_tree(cfg, &inv.tf_static, &kept).0 } else { self.tree };
            let stamps = self.chain_stamps;
            counts.samples = stamps.len() as u64;
            let name = format!("TF `{root} → … → {}`", self.base);
            let track = TfTrack { tree, root, base: self.base, stamps: stamps.clone() };
            counts.used = track.samples().len() as u64;
            if counts.used == 0 {
                return Err(no_pose());
            }
            let receive = vec![None; stamps.len()];
            let timed = Track::Timed(Box::new(track));
            return Ok(ChosenTrack {
                odom_frame,
                ..ChosenTrack::of(PoseSource::Tf, timed, name, counts, (stamps, receive), cfg)
            });
        }
        let stamps: Vec<Stamp> = self.samples.iter().map(|s| s.0).collect();
        let buffer = buffer_of(cfg, self.samples, &mut counts);
        if buffer.is_empty() {
            return Err(no_pose());
        }
        let name = format!("TF `… → {}`", cfg.base_frame);
        let receive = vec![None; stamps.len()];
        let timed = Track::Timed(Box::new(buffer));
        Ok(ChosenTrack { odom_frame, ..ChosenTrack::of(PoseSource::Tf, timed, name, counts, (stamps, receive), cfg) })
    }
}
