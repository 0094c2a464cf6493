//! The SLAM pass: the lidar corrects the pose track before the map is built.
//!
//! When the poses of a log are raw (odometry, the estimator over odometry/IMU/GNSS, TF
//! under an `odom` frame, the odometry written on raw CARMEN lines), a pass over the
//! first lidar's scans runs [`fusemap_core::slam`]: each scan predicted from the track's
//! motion, matched against the local submap, turned into a pose-graph node, searched
//! against older submaps for loop closures, and the graph optimised; when the track is the
//! estimator's, the GNSS fixes it was given are position priors on the nodes too
//! ([`fusemap_core::slam::PositionFix`]). The track (odometry,
//! or the estimator's fusion of odometry, IMU and GNSS) is then corrected at every scan by
//! the optimised pose ([`track`]), and that corrected track places every measurement —
//! the scans, de-skewed, and the camera frames — at its own stamp. With poses on the scan
//! lines (raw CARMEN), the optimised scan poses are the track.

use crate::extrinsics::frame_tree;
use crate::lidar_frames::lidar_setup;
use crate::merge::{OrderedMerge, Pushed};
use crate::progress::Progress;
use crate::recording::{for_each_range_message, line_key, Inventory, LineKey, RangeMessage};
use crate::sensors::{Bound, BoundLidar};
pub use crate::slam_summary::{GraphEdge, GraphNode, GraphPrior, SlamSummary};
use crate::sync::sync_mode;
use crate::track::{ChosenTrack, LinePoses, TfTrack, Track};
use crate::{PipelineError, Stage};
use fusemap_core::config::{Plan, PoseSource, SlamMode};
use fusemap_core::estimator::{EstimatorInput, FixQuality};
use fusemap_core::geometry::{PlanarMount, Point2, Pose2};
use fusemap_core::sensor::LidarParams;
use fusemap_core::slam::pose_graph::EdgeKind;
use fusemap_core::slam::{CorrectedTrack, PositionFix, ScanInput, ScanOutcome, Slam, SlamResult};
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::log::ScanMessage;
use std::collections::{HashMap, HashSet};
use std::time::Instant;

/// The SLAM pass's result: the summary, with every scan's optimised pose.
pub struct SlamRun {
    /// The summary.
    pub summary: SlamSummary,
}

/// Whether SLAM should run on this log with this track, and why (or why not).
pub fn applies(plan: &Plan, inv: &Inventory, bound: &Bound, chosen: &ChosenTrack) -> (bool, String) {
    if bound.lidars.is_empty() {
        return (false, "no lidar".into());
    }
    match plan.slam_mode {
        SlamMode::Off => return (false, "slam.mode = \"off\"".into()),
        SlamMode::On => return (true, "slam.mode = \"on\"".into()),
        SlamMode::Auto => {}
    }
    match chosen.source {
        PoseSource::Odometry => (true, "the poses are raw odometry".into()),
        PoseSource::Estimator => (true, "the poses come from the estimator (odometry, IMU, GNSS)".into()),
        PoseSource::ScanLine => {
            // A raw CARMEN log writes its odometry as the pose of every scan line; so do
            // corrected logs (the corrected pose in both fields), but those come out of
            // GMapping with a `NEFF` line (effective particles) beside each scan.
            let t = &inv.scans[&bound.lidars[0].topic];
            if inv.stats.skipped_by_type.contains_key("NEFF") {
                (false, "the poses on the scan lines are corrected (the log has GMapping's NEFF lines)".into())
            } else if t.with_pose > 0 && t.pose_is_odometry == t.with_pose {
                (true, "the poses on the scan lines are their raw odometry".into())
            } else {
                (false, "the poses on the scan lines are corrected".into())
            }
        }
        PoseSource::Tf => {
            let (tree, _) = frame_tree(&plan.log, &inv.tf_static, &inv.tf_dynamic);
            let base = plan.log.base_frame.trim_start_matches('/');
            match TfTrack::root_of(&tree, base) {
                Some(root) if root.trim_start_matches('/') == "odom" => (true, "the TF poses are under `odom`".into()),
                Some(root) => (false, format!("the TF poses come from `{root}`, taken as corrected")),
                None => (false, "no TF root".into()),
            }
        }
        PoseSource::Auto => (false, "unresolved pose source".into()),
    }
}

/// Runs SLAM over the first lidar's scans with `chosen` as the prediction.
pub fn run(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: &ChosenTrack,
    reason: String,
    progress: &mut dyn FnMut(Progress),
) -> Result<SlamRun, PipelineError> {
    let t0 = Instant::now();
    let cfg = &plan.log;
    let b = &bound.lidars[0];
    let offset = crate::offset_ns(b.lidar.time_offset_s);
    let stamps = &inv.scans[&b.topic].stamps;
    let mode = sync_mode(cfg, stamps);
    let mut feed = ScanFeed::new(plan, inv, b, chosen, mode)?;
    feed.slam.add_fixes(&fixes(plan, inv, bound, chosen, mode)?);
    progress(Progress::Phase { name: "slam", total: stamps.len() as u64 });
    let topics = [b.topic.clone()];
    // Scans in stamp order, as the mapping pass releases them (logs hold them in arrival
    // order; CARMEN IPC stamps go backwards now and then).
    let mut merge: OrderedMerge<ScanMessage> = OrderedMerge::new(crate::offset_ns(cfg.reorder_window_s));
    let stream = merge.add_stream(b.topic.clone());
    let (mut seq, mut late) = (0i64, 0u64);
    for_each_range_message(&inv.path, &inv.limits, &topics, &[], |msg| {
        let RangeMessage::Scan(scan) = msg else { return Ok(()) };
        if scan.topic != b.topic {
            return Ok(());
        }
        // Poses on the scan lines do not depend on the stamps: file order.
        let key = match chosen.track {
            Track::ScanLine(_) => {
                seq += 1;
                seq
            }
            Track::Timed(_) => scan.scan.stamp.0.saturating_add(offset),
        };
        if merge.push(stream, key, scan) == Pushed::Late {
            late += 1;
        }
        while let Some((_, _, scan)) = merge.pop_ready() {
            progress(Progress::Advance(1));
            feed.feed(Stamp(scan.scan.stamp.0.saturating_add(offset)), scan)?;
        }
        Ok(())
    })?;
    while let Some((_, _, scan)) = merge.pop_final() {
        progress(Progress::Advance(1));
        feed.feed(Stamp(scan.scan.stamp.0.saturating_add(offset)), scan)?;
    }
    progress(Progress::Done);
    let result = feed.slam.finish();
    let seconds = t0.elapsed().as_secs_f64();
    let mut summary = summary(&result, reason, b.topic.clone(), feed.without_pose, late, seconds);
    let sensor = feed.mount.base_from_sensor;
    summary.sensor_in_base = [sensor.x, sensor.y, sensor.theta];
    summary.lines = feed.lines;
    Ok(SlamRun { summary })
}

/// What turns each scan, in stamp order, into SLAM's input: its pose on the track (or
/// across the track's pauses, or on its scan line), its beams as points in the base frame
/// (de-skewed as the mapping pass de-skews them), and the SLAM itself.
struct ScanFeed<'a> {
    track: &'a Track,
    mode: SyncMode,
    deskew: bool,
    /// The track's samples, to interpolate across its pauses.
    samples: Vec<(Stamp, Pose2)>,
    /// The glitches among the scan-line poses.
    line_glitches: HashSet<LineKey>,
    /// The mounts of the topic's other frame ids.
    mounts: HashMap<String, PlanarMount>,
    mount: PlanarMount,
    params: LidarParams,
    slam: Slam,
    repeats: crate::repeats::RepeatFilter,
    hits: Vec<Point2>,
    /// With poses on the scan lines: each scan's stamp and line pose.
    lines: Vec<Option<(Stamp, Pose2)>>,
    without_pose: u64,
    /// `limits.memory_mib` in bytes.
    memory_bytes: u64,
}

impl<'a> ScanFeed<'a> {
    /// The first lidar's mounts (one per frame id on its topic) and range limits, the
    /// track to predict with, and a SLAM with the plan's parameters.
    fn new(
        plan: &Plan,
        inv: &Inventory,
        b: &BoundLidar,
        chosen: &'a ChosenTrack,
        mode: SyncMode,
    ) -> Result<Self, PipelineError> {
        let cfg = &plan.log;
        let (tree, _) = frame_tree(cfg, &inv.tf_static, &inv.tf_dynamic);
        let mut scratch = Vec::new();
        let (frame, _, model) = lidar_setup(b, inv, &tree, cfg, &mut scratch)?;
        // Scans of the topic's other frame ids are placed from their own mounts, as the
        // mapping pass places them.
        let mounts = crate::lidar_frames::other_frames(b, &frame, inv, &tree, cfg, &mut scratch)
            .into_iter()
            .map(|(f, (_, m))| (f, *m.mount()))
            .collect();
        let line_glitches = match chosen.track {
            Track::ScanLine(_) => inv.scans[&b.topic].line_glitches(&cfg.motion_limits()),
            Track::Timed(_) => Default::default(),
        };
        let samples = match &chosen.track {
            Track::Timed(track) => track.samples(),
            Track::ScanLine(_) => Vec::new(),
        };
        Ok(ScanFeed {
            track: &chosen.track,
            mode,
            deskew: cfg.deskew,
            samples,
            line_glitches,
            mounts,
            mount: *model.mount(),
            params: *model.params(),
            slam: Slam::new(plan.slam),
            memory_bytes: plan.limits.memory_bytes(),
            repeats: Default::default(),
            hits: Vec::new(),
            lines: Vec::new(),
            without_pose: 0,
        })
    }

    /// Feeds one scan to SLAM; an error once SLAM's grids and nodes hold more than
    /// `limits.memory_mib`.
    fn feed(&mut self, t: Stamp, scan: ScanMessage) -> Result<(), PipelineError> {
        // A repeated message is one scan, as in the mapping pass.
        if self.repeats.is_repeat(&scan) {
            return Ok(());
        }
        // The track refuses to interpolate across its gaps (a map must not guess); a
        // prediction may: the match corrects it.
        let pose = match self.track {
            Track::ScanLine(_) => {
                scan.pose.filter(|p| p.is_finite() && !self.line_glitches.contains(&line_key(scan.scan.stamp, *p)))
            }
            Track::Timed(track) => track.pose_at(t, self.mode).ok().or_else(|| across_gap(&self.samples, t)),
        };
        // A frozen scan is left out, as the mapping pass leaves it out (`repeats.rs`).
        if pose.is_some_and(|p| self.repeats.is_frozen(p)) {
            return Ok(());
        }
        if pose.is_none() {
            self.without_pose += 1;
        }
        let mount = *self.mounts.get(scan.frame_id.as_str()).unwrap_or(&self.mount);
        self.place_beams(t, &scan, &mount);
        let origin = mount.origin_in_base();
        let outcome = self.slam.add_scan(ScanInput { stamp: t, track: pose, origin, hits: &self.hits, misses: &[] });
        if matches!(self.track, Track::ScanLine(_)) && outcome != ScanOutcome::Refused {
            self.lines.push(pose.map(|p| (scan.scan.stamp, p)));
        }
        let bytes = self.slam.held_bytes();
        if bytes as u64 > self.memory_bytes {
            return Err(PipelineError::refused(Stage::Budget, format!(
                "SLAM reached limits.memory_mib = {} MiB ({} submaps, the loop search's grids and {} nodes' points, {bytes} bytes) at the scan stamped {:.6} s; \
                 raise limits.memory_mib, lower slam.loop_closure_grid_cache_mib, coarsen slam.resolution_m, or shorten slam.max_range_m",
                self.memory_bytes >> 20,
                self.slam.report().submaps,
                self.slam.report().nodes,
                t.as_secs_f64()
            )));
        }
        Ok(())
    }

    /// The scan's beams within range as points in the base frame at the scan's stamp.
    /// De-skewed as the mapping pass does: each beam placed with the track's motion from
    /// the scan's stamp to the beam's own time, so the matcher sees the scan as it would be
    /// from one pose (a scan swept while turning is otherwise bent).
    fn place_beams(&mut self, t: Stamp, scan: &ScanMessage, mount: &PlanarMount) {
        let lo = self.params.min_range.max(scan.range_min as f64);
        let hi = self.params.max_range.min(scan.range_max as f64);
        let (a0, inc) = (scan.scan.angle_min as f32 as f64, scan.scan.angle_increment as f32 as f64);
        let origin = mount.origin_in_base();
        let n = scan.scan.ranges.len();
        let ti = scan.time_increment as f64;
        let sweep = match self.track {
            Track::Timed(track) if self.deskew && self.mode == SyncMode::Interpolate && ti > 0.0 && n > 1 => {
                track.pose_at(t, SyncMode::Interpolate).ok().map(|p0| (track, p0.inverse()))
            }
            _ => None,
        };
        let motion_at = |i: usize| -> Option<Pose2> {
            let (track, from_base) = sweep?;
            let tb = Stamp(t.0.saturating_add((ti * i as f64 * 1e9) as i64));
            Some(from_base.compose(track.pose_at(tb, SyncMode::Interpolate).ok()?))
        };
        let deskew = motion_at(n.saturating_sub(1)).is_some();
        self.hits.clear();
        // A scan whose beams cannot be placed (refused by the mapping pass too) gives no hits.
        let beams = if scan.angle_fault().is_none() { &scan.scan.ranges[..] } else { &[] };
        self.hits.extend(beams.iter().enumerate().filter_map(|(i, &r)| {
            let r = r as f64;
            (r.is_finite() && r >= lo && r < hi).then(|| {
                let a = mount.beam_angle_in_base(a0 + i as f64 * inc);
                let q = Point2::new(origin.x + r * a.cos(), origin.y + r * a.sin());
                match deskew.then(|| motion_at(i)).flatten() {
                    Some(m) => m.transform_point(q),
                    None => q,
                }
            })
        }));
    }
}

/// The GNSS fixes for the pose graph, when the track is the estimator's: its map frame is
/// the fixes' (any other track's is not, and gets none).
fn fixes(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: &ChosenTrack,
    mode: SyncMode,
) -> Result<Vec<PositionFix>, PipelineError> {
    let Track::Timed(track) = &chosen.track else { return Ok(Vec::new()) };
    if chosen.source != PoseSource::Estimator || !plan.slam.fixes {
        return Ok(Vec::new());
    }
    let inputs = crate::gnss_fixes::gnss_positions(plan, inv, bound)?;
    // The estimator's rule for which fixes are RTK fixed (white errors) and which share a
    // correlated error.
    let e = &plan.estimator;
    let rtk_var = e.rtk_fix_max_sigma_m * e.rtk_fix_max_sigma_m;
    Ok(inputs
        .into_iter()
        .filter_map(|i| match i {
            EstimatorInput::Position { stamp, enu, covariance, antenna, quality } => Some(PositionFix {
                stamp,
                position: Point2::new(enu[0], enu[1]),
                covariance: *covariance,
                antenna,
                correlation_time_s: match quality {
                    FixQuality::RtkFixed if covariance[0][0].max(covariance[1][1]) <= rtk_var => {
                        e.rtk_fix_correlation_time_s
                    }
                    _ => e.fix_correlation_time_s,
                },
                track: track
                    .pose_at(stamp, mode)
                    .ok()
                    .map(|p| (p, track.covariance_at(stamp).unwrap_or([[0.0; 3]; 3]))),
            }),
            _ => None,
        })
        .collect())
}

/// The track's pose at `t` interpolated between its samples whatever the gap between
/// them; `None` outside the samples.
pub(crate) fn across_gap(samples: &[(Stamp, Pose2)], t: Stamp) -> Option<Pose2> {
    let i = samples.partition_point(|s| s.0 < t);
    let (b, a) = (samples.get(i)?, samples.get(i.checked_sub(1)?)?);
    if b.0 == t {
        return Some(b.1);
    }
    Some(a.1.interpolate(b.1, (t.0 - a.0 .0) as f64 / (b.0 .0 - a.0 .0) as f64))
}

fn summary(r: &SlamResult, reason: String, topic: String, without_pose: u64, late: u64, seconds: f64) -> SlamSummary {
    let mut kind = vec![("scan", None); r.graph.nodes().len()];
    for (&g, &s) in r.scan_nodes.iter().zip(&r.node_stamps) {
        kind[g] = ("scan", Some(s.0));
    }
    for &g in &r.submap_nodes {
        kind[g] = ("submap", None);
    }
    let nodes = r
        .graph
        .nodes()
        .iter()
        .zip(kind)
        .map(|(p, (kind, stamp_ns))| GraphNode { kind, stamp_ns, pose: [p.x, p.y, p.theta] })
        .collect();
    let edges = r
        .graph
        .edges()
        .iter()
        .map(|e| GraphEdge {
            from: e.from,
            to: e.to,
            kind: match e.kind {
                EdgeKind::Odometry => "odometry",
                EdgeKind::Match => "match",
                EdgeKind::LoopClosure => "loop_closure",
            },
        })
        .collect();
    let priors = r
        .graph
        .position_priors()
        .iter()
        .map(|p| GraphPrior { node: p.node, position: [p.position.x, p.position.y] })
        .collect();
    SlamSummary {
        reason,
        topic,
        scans_without_pose: without_pose,
        scans_late: late,
        counts: r.report.clone(),
        seconds,
        track: String::new(),
        nodes,
        edges,
        priors,
        open_loops: r
            .open_loops
            .iter()
            .map(|o| fusemap_core::slam::OpenSearch {
                node: r.scan_nodes[o.node],
                submap: r.submap_nodes[o.submap],
                ..*o
            })
            .collect(),
        sensor_in_base: [0.0; 3],
        scan_poses: r.trajectory.clone(),
        lines: Vec::new(),
    }
}

/// The pose track from a SLAM run: the prediction track corrected at every scan by the
/// optimised pose ([`CorrectedTrack`]); for poses on the scan lines (raw CARMEN), the
/// optimised poses themselves, interpolated.
///
/// Measured alternative, not taken: the optimised poses as absolute pose inputs of the
/// EKF + smoother beside the odometry. On the Intel log its χ² gate refused 88 % of them
/// (the odometry's heading drifts faster than its noise model says) and the track's
/// relation error was 9.4 m against 0.02 m for the optimised poses. The graph already
/// fuses the estimator's motion (with the fixes in it), the matches and the loop
/// closures; the correction keeps its result exactly at every scan.
pub fn track(chosen: ChosenTrack, run: &mut SlamRun, cfg: &fusemap_core::config::LogConfig) -> ChosenTrack {
    match chosen.track {
        Track::Timed(base) => {
            run.summary.track = format!("{} corrected at every scan by the optimised pose graph", chosen.name);
            ChosenTrack {
                track: Track::Timed(Box::new(CorrectedTrack::new(base, &run.summary.scan_poses, cfg.motion_limits()))),
                name: format!("SLAM (scan matching + loop closure) over {}", chosen.name),
                ..chosen
            }
        }
        Track::ScanLine(_) => {
            run.summary.track = "the optimised pose of every scan line, in file order".into();
            let s = &run.summary;
            let (lines, poses): (Vec<(Stamp, Pose2)>, Vec<Pose2>) = if s.lines.len() == s.scan_poses.len() {
                s.lines.iter().zip(&s.scan_poses).filter_map(|(l, p)| Some(((*l)?, p.1))).unzip()
            } else {
                // Never expected: every scan fed to SLAM and not refused has one pose.
                (Vec::new(), Vec::new())
            };
            ChosenTrack {
                track: Track::ScanLine(Some(LinePoses::new(&lines, &poses))),
                name: "SLAM (scan matching + loop closure) over the odometry on the scan lines".into(),
                ..chosen
            }
        }
    }
}
