//! One mapping pass over a recording: the whole log → map pipeline in one library call.
//!
//! Steps: the first pass reads the pose sensors and an inventory of the scans; the sensors
//! are bound to topics; the pose track is chosen and built (the estimator and its smoother
//! over the whole log, when the log has the sensors for it); each lidar's mount is
//! resolved; then the second pass streams every lidar's scans through the time-ordered
//! merge into the engine, each scan with the pose at its own stamp (or each beam's,
//! de-skewed). Every scan that cannot be posed is skipped and counted with its reason;
//! clock faults are reported, and the usable part of the log is still mapped.

use crate::camera::{build_camera, MappedCamera};
use crate::extrinsics::frame_tree;
use crate::insert::{release, Inserter, Mapped};
use crate::lidar_frames::lidar_setup;
use crate::lidar_frames::other_frames;
use crate::merge::{OrderedMerge, Pushed};
pub use crate::progress::Progress;
use crate::recording::{for_each_range_message, Inventory, RangeMessage};
use crate::report::{LidarReport, LogReport, Skipped};
use crate::sensors::{bind, Bound};
pub(crate) use crate::sync::offset_ns;
pub use crate::sync::{limits, sync_mode};
use crate::track::{choose, count_reordered, ChosenTrack, Track};
use crate::PipelineError;
use fusemap_core::config::{default_camera, Plan, PlannedCamera, SensorKind};
use fusemap_core::fusion::{Correlation, Engine, MapSet};
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::FusionGrid;
use fusemap_core::measurement::SensorId;
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::{Stamp, StreamTiming, SyncMode};
use fusemap_io::log::LogFormat;
use std::collections::{BTreeMap, HashSet};
use std::path::Path;
use std::time::Instant;

/// A finished mapping pass.
pub struct MapRun {
    /// The engine, holding the map and its counters.
    pub engine: Engine,
    /// The log's format.
    pub format: LogFormat,
    /// The run report.
    pub report: LogReport,
    /// The pose track used, `map_from_base` in time order, with the pose of every mapped
    /// scan at its stamp (for `trajectory.tum`).
    pub trajectory: Vec<(Stamp, Pose2)>,
    /// Facts a user should know.
    pub notes: Vec<String>,
}

/// A timed track's samples with the pose every scan was placed with, by stamp (a sample
/// and a scan at one stamp: the sample). The scans' own poses let a user score the map's
/// track at the scan stamps (the SLAM benchmark's relations name them) without
/// interpolating across the odometry's pauses, which the track bridges and a reader of
/// the file could not tell apart from a gap.
fn with_scan_poses(samples: Vec<(Stamp, Pose2)>, placed: Vec<(Stamp, Pose2)>) -> Vec<(Stamp, Pose2)> {
    let mut all = samples;
    all.extend(placed);
    all.sort_by_key(|s| s.0);
    all.dedup_by_key(|s| s.0);
    all
}

/// Maps the log at `path` with `plan`.
pub fn map_log(plan: &Plan, path: &Path, progress: &mut dyn FnMut(Progress)) -> Result<MapRun, PipelineError> {
    progress(Progress::Phase { name: "reading", total: 0 });
    let inv = Inventory::read_with(path, &plan.limits)?;
    progress(Progress::Done);
    map_inventory(plan, &inv, progress)
}

/// The topics of the first pass, by kind, with their message counts.
pub fn topics_by_kind(inv: &Inventory) -> BTreeMap<SensorKind, BTreeMap<String, u64>> {
    let mut m: BTreeMap<SensorKind, BTreeMap<String, u64>> = BTreeMap::new();
    for (t, s) in &inv.scans {
        m.entry(SensorKind::Lidar).or_default().insert(t.clone(), s.stamps.len() as u64);
    }
    for (t, v) in &inv.odom {
        m.entry(SensorKind::WheelOdometry).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.imu {
        m.entry(SensorKind::Imu).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.gnss {
        m.entry(SensorKind::Gnss).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.poses {
        m.entry(SensorKind::Pose).or_default().insert(t.clone(), v.len() as u64);
    }
    m
}

/// The cameras to map: the configured ones, else a default camera when the log carries
/// the usual camera topics (and the camera kind is not disabled).
fn planned_cameras(plan: &Plan, inv: &Inventory, notes: &mut Vec<String>) -> Result<Vec<PlannedCamera>, PipelineError> {
    if !plan.cameras.is_empty() || plan.disabled_kinds.contains(&SensorKind::Camera) {
        return Ok(plan.cameras.clone());
    }
    let c = default_camera(plan.occupancy.prior).map_err(|e| PipelineError::Refused(e.to_string()))?;
    let present = inv.images.contains_key(&c.topic)
        && inv.images.contains_key(&c.depth_topic)
        && inv.camera_info.contains_key(&c.info_topic);
    if !present {
        return Ok(Vec::new());
    }
    notes.push(format!(
        "camera found on `{}`, `{}` and `{}` and mapped with the default camera parameters (list it as a [[sensor]] of kind \"camera\" to change them, or disable it)",
        c.topic, c.depth_topic, c.info_topic
    ));
    Ok(vec![c])
}

/// Binds the sensors and builds the pose track from the pose sensors alone.
pub fn prepare_track(plan: &Plan, inv: &Inventory) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    if inv.scans.is_empty() && inv.stats.malformed > 0 {
        return Err(PipelineError::Refused(format!(
            "the log holds no usable laser scans; {} records could not be decoded, the first: {}",
            inv.stats.malformed,
            inv.stats.malformed_examples.first().map_or("", |s| s.as_str())
        )));
    }
    let bound = bind(plan, &topics_by_kind(inv))?;
    let t0 = Instant::now();
    let chosen = choose(inv, &plan.log, &bound, || crate::estimation::estimator_track(plan, inv, &bound))?;
    Ok((bound, chosen, t0.elapsed().as_secs_f64()))
}

/// A SLAM run that leaves more than this share of its scans without an optimised pose is
/// reported with a warning, not as a correction.
const LOST_POSES_NOTE_SHARE: f64 = 0.01;

/// [`prepare_track`], then SLAM corrects the track when [`crate::slam::applies`] says so.
pub fn prepare(plan: &Plan, inv: &Inventory) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    prepare_with(plan, inv, &mut |_| {})
}

/// [`prepare`] with progress reports.
pub fn prepare_with(
    plan: &Plan,
    inv: &Inventory,
    progress: &mut dyn FnMut(Progress),
) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    let (bound, chosen, track_s) = prepare_track(plan, inv)?;
    let (on, reason) = crate::slam::applies(plan, inv, &bound, &chosen);
    if !on {
        return Ok((bound, chosen, track_s));
    }
    let t0 = Instant::now();
    let mut run = crate::slam::run(plan, inv, &bound, &chosen, reason, progress)?;
    let mut track = crate::slam::track(chosen, &mut run);
    // Scans SLAM was given but left without an optimised pose: a few (a refused reading)
    // are normal; more means the run did not correct the log (equal stamps collapsing the
    // track did this once), and the note says so instead of "corrected".
    let given = run.summary.counts.scans;
    let placed = run.summary.scan_poses.len() as u64;
    let lost = given.saturating_sub(placed);
    let verb = if lost as f64 > LOST_POSES_NOTE_SHARE * given as f64 {
        format!(
            "WARNING: SLAM lost the pose of {lost} of {given} scans ({:.1} %), which keep the uncorrected track; the map may be wrong",
            100.0 * lost as f64 / given.max(1) as f64
        )
    } else {
        "SLAM corrected the poses".to_string()
    };
    track.notes.push(format!(
        "{verb} ({}): {} scans matched ({} degenerate), {} nodes, {} submaps, {} of {} loop-closure searches accepted",
        run.summary.reason,
        run.summary.counts.matched + run.summary.counts.degenerate,
        run.summary.counts.degenerate,
        run.summary.counts.nodes,
        run.summary.counts.submaps,
        run.summary.counts.loop_accepted,
        run.summary.counts.loop_searches,
    ));
    // Why the result is what it is: no loop closed, a corridor, unmatched scans, searches
    // the budget left out.
    for f in run.summary.counts.findings(plan.slam.loop_closure, plan.slam.loop_closure_global_after_m) {
        track.notes.push(format!("SLAM: {f}"));
    }
    track.slam = Some(Box::new(run.summary));
    Ok((bound, track, track_s + t0.elapsed().as_secs_f64()))
}

/// Maps a recording whose first pass is done.
pub fn map_inventory(
    plan: &Plan,
    inv: &Inventory,
    progress: &mut dyn FnMut(Progress),
) -> Result<MapRun, PipelineError> {
    let (bound, chosen, track_s) = prepare_with(plan, inv, progress)?;
    map_with_track(plan, inv, &bound, chosen, track_s, None, progress)
}

/// Maps a recording whose first pass is done with a given pose track (a calibration
/// search, or a comparison of tracks on one log, maps the same scans with several).
///
/// `maps`: several maps fed in this one pass, each from its own subset of sensors (the
/// design document's leave-one-out maps, §5.2); the lidars get sensor ids 0, 1, … in the
/// order of `bound.lidars`. `None`: one map of every sensor.
pub fn map_with_track(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: ChosenTrack,
    track_s: f64,
    maps: Option<MapSet>,
    progress: &mut dyn FnMut(Progress),
) -> Result<MapRun, PipelineError> {
    let cfg = &plan.log;
    let mut notes = bound.notes.clone();
    let mut chosen = chosen;
    let slam_summary = chosen.slam.take();
    if bound.lidars.is_empty() {
        return Err(PipelineError::Refused("no lidar to map: every [[sensor]] of kind lidar is disabled".into()));
    }
    let first_stamps = &inv.scans[&bound.lidars[0].topic].stamps;
    let mode = sync_mode(cfg, first_stamps);
    let window = match chosen.track {
        Track::ScanLine(_) => 0,
        Track::Timed(_) => offset_ns(cfg.reorder_window_s),
    };
    let mut merge: OrderedMerge<RangeMessage> = OrderedMerge::new(window);
    let mut engine = match maps {
        Some(m) => Engine::with_maps(m),
        None => Engine::new(FusionGrid::new(plan.geometry, plan.occupancy)),
    };
    engine.set_map_cells_limit(&plan.limits);
    let (tree, tree_notes) = frame_tree(cfg, &inv.tf_static, &inv.tf_dynamic);
    notes.extend(tree_notes);
    let mut lidars = Vec::new();
    for b in &bound.lidars {
        let topic = &inv.scans[&b.topic];
        let (frame, ext, model) = lidar_setup(b, inv, &tree, cfg, &mut notes)?;
        let id = engine.add_lidar(b.lidar.name.clone(), model);
        let by_frame = other_frames(b, &frame, inv, &tree, cfg, &mut notes)
            .into_iter()
            .map(|(f, (_, model))| {
                let sensor = engine.add_lidar(format!("{}@{f}", b.lidar.name), model);
                (f, sensor)
            })
            .collect();
        let mut other_frames = topic.frames.clone();
        other_frames.remove(&frame);
        other_frames.remove("");
        let stream = merge.add_stream(b.topic.clone());
        let timing = StreamTiming::analyze(&topic.stamps, &topic.receive, limits(cfg));
        let scans_reordered = match chosen.track {
            Track::Timed(_) => count_reordered(topic.stamps.iter().copied()),
            Track::ScanLine(_) => 0,
        };
        lidars.push(Mapped {
            id,
            offset_ns: offset_ns(b.lidar.time_offset_s),
            stream,
            report: LidarReport {
                name: b.lidar.name.clone(),
                topic: b.topic.clone(),
                frame,
                other_frames,
                scans_read: topic.stamps.len() as u64,
                scans_used: 0,
                scans_skipped: Skipped::default(),
                scans_deskewed: 0,
                scans_reordered,
                time_offset_s: b.lidar.time_offset_s,
                timing,
                extrinsics: ext,
            },
            line_glitches: match chosen.track {
                Track::ScanLine(_) => topic.line_glitches(&cfg.motion_limits()),
                Track::Timed(_) => HashSet::new(),
            },
            bad_angles_example: None,
            repeats: Default::default(),
            by_frame,
        });
    }

    let mut cameras: Vec<MappedCamera> = Vec::new();
    let planned = planned_cameras(plan, inv, &mut notes)?;
    for c in &planned {
        let built = build_camera(c, &plan.classes, plan.geometry.resolution(), inv, &tree, cfg, &mut notes);
        let (model, report) = match built {
            Ok(b) => b,
            // A camera the config did not ask for never stops a run: the log is mapped
            // without it, and the note says why.
            Err(e) if !c.explicit => {
                notes.push(format!("the camera found on `{}` is not mapped: {e}", c.topic));
                continue;
            }
            Err(e) => return Err(e),
        };
        let id = engine.add_camera(c.name.clone(), model);
        let label_stream = merge.add_stream(c.topic.clone());
        let depth_stream = merge.add_stream(c.depth_topic.clone());
        cameras.push(MappedCamera::new(id, c, label_stream, depth_stream, report));
    }
    if !cameras.is_empty() {
        engine.set_dynamic(plan.dynamic, plan.fusion.route_lidar_hits_to_dynamic);
    }
    if !plan.fusion.correlated.is_empty() {
        let id_of = |name: &str| {
            lidars
                .iter()
                .zip(&bound.lidars)
                .find(|(_, b)| b.lidar.name == name)
                .map(|(l, _)| l.id)
                .or_else(|| cameras.iter().find(|c| c.report.name == name).map(|c| c.id))
        };
        let mut groups = Vec::new();
        for g in &plan.fusion.correlated {
            let ids: Vec<SensorId> = g.iter().filter_map(|n| id_of(n)).collect();
            if ids.len() < g.len() {
                notes.push(format!(
                    "fusion.correlated: {} of the group [{}] are not mapped in this run; the group is used without them",
                    g.len() - ids.len(),
                    g.join(", ")
                ));
            }
            if ids.len() >= 2 {
                groups.push(ids);
            }
        }
        engine.set_correlation(Correlation {
            groups,
            window_ns: offset_ns(plan.fusion.correlation_window_s),
            rule: plan.fusion.merge,
        });
    }

    // The second pass: every lidar's scans and every camera's images, merged in stamp
    // order (file order for poses on the scan lines, which do not depend on the stamps:
    // some corrected CARMEN logs have broken or all-zero stamps).
    let topics: Vec<String> = bound.lidars.iter().map(|b| b.topic.clone()).collect();
    let image_topics: Vec<String> = planned.iter().flat_map(|c| [c.topic.clone(), c.depth_topic.clone()]).collect();
    let total: u64 = lidars.iter().map(|l| l.report.scans_read).sum::<u64>()
        + image_topics.iter().map(|t| inv.images.get(t).map_or(0, |i| i.stamps.len() as u64)).sum::<u64>();
    progress(Progress::Phase { name: "mapping", total });
    let mut inserter = Inserter {
        engine: &mut engine,
        track: &chosen.track,
        mode,
        deskew: cfg.deskew,
        scan: LaserScan { stamp: Stamp::ZERO, angle_min: 0.0, angle_increment: 0.0, ranges: Vec::new() },
        last: None,
        placed: Vec::new(),
        lines_seen: Default::default(),
        next_id: 0,
    };
    let t_map = Instant::now();
    let mut seq = 0i64;
    let read_s = for_each_range_message(&inv.path, &inv.limits, &topics, &image_topics, |msg| {
        let (stream, key) = match &msg {
            RangeMessage::Scan(scan) => {
                let Some(l) = lidars.iter_mut().find(|l| l.report.topic == scan.topic) else { return Ok(()) };
                let key = match chosen.track {
                    Track::ScanLine(_) => {
                        seq += 1;
                        seq
                    }
                    Track::Timed(_) => scan.scan.stamp.0.saturating_add(l.offset_ns),
                };
                (l.stream, key)
            }
            RangeMessage::Image(image) => {
                let Some((c, stream)) = cameras.iter().find_map(|c| {
                    (c.report.topic == image.topic)
                        .then_some(c.label_stream)
                        .or_else(|| (c.report.depth_topic == image.topic).then_some(c.depth_stream))
                        .map(|s| (c, s))
                }) else {
                    return Ok(());
                };
                (stream, image.stamp.0.saturating_add(c.offset_ns))
            }
        };
        if merge.push(stream, key, msg) == Pushed::Late {
            if let Some(l) = lidars.iter_mut().find(|l| l.stream == stream) {
                l.report.scans_skipped.late += 1;
            } else if let Some(c) = cameras.iter_mut().find(|c| c.label_stream == stream || c.depth_stream == stream) {
                c.report.frames_skipped.late += 1;
            }
            progress(Progress::Advance(1));
        }
        while let Some((s, key, msg)) = merge.pop_ready() {
            release(&mut inserter, &mut lidars, &mut cameras, s, Stamp(key), msg)?;
            progress(Progress::Advance(1));
        }
        Ok(())
    })?;
    while let Some((s, key, msg)) = merge.pop_final() {
        release(&mut inserter, &mut lidars, &mut cameras, s, Stamp(key), msg)?;
        progress(Progress::Advance(1));
    }
    for c in &mut cameras {
        c.finish();
    }
    progress(Progress::Done);
    let map_s = t_map.elapsed().as_secs_f64();
    let _ = read_s;
    let placed = std::mem::take(&mut inserter.placed);
    let trajectory = match &chosen.track {
        Track::ScanLine(_) => placed,
        Track::Timed(t) => with_scan_poses(t.samples(), placed),
    };
    drop(inserter);

    let mut skipped = Skipped::default();
    for l in &lidars {
        let r = &l.report;
        skipped.add(&r.scans_skipped);
        if r.timing.regressions > 0 {
            let order = if r.scans_reordered > 0 {
                format!(": {} scans mapped in stamp order", r.scans_reordered)
            } else {
                String::new()
            };
            notes.push(format!("`{}` stamps go backwards {} times{order}", r.topic, r.timing.regressions));
        }
        if r.scans_skipped.bad_angles > 0 {
            notes.push(format!(
                "{} scans of `{}` refused: their beam angles cannot be placed (first: {})",
                r.scans_skipped.bad_angles,
                r.topic,
                l.bad_angles_example.as_deref().unwrap_or("?")
            ));
        }
        if r.scans_skipped.repeated > 0 {
            notes.push(format!(
                "{} scans of `{}` repeat the scan before them (same stamp, same ranges): each was inserted once",
                r.scans_skipped.repeated, r.topic
            ));
        }
        if r.scans_skipped.late > 0 {
            notes.push(format!(
                "{} scans of `{}` arrived more than log.reorder_window_s = {} s behind the others and were dropped",
                r.scans_skipped.late, r.topic, cfg.reorder_window_s
            ));
        }
    }
    let read: u64 = lidars.iter().map(|l| l.report.scans_read).sum();
    let without_pose = skipped.total() - skipped.bad_angles - skipped.repeated;
    if without_pose > 0 {
        notes.push(format!("{without_pose} of {read} scans skipped without a pose"));
    }
    if let Some(cut) = &inv.truncated {
        notes.push(format!("the log is cut short, and was mapped up to the cut: {cut}"));
    }
    if inv.stats.malformed > 0 {
        notes.push(format!(
            "{} malformed records skipped; first: {}",
            inv.stats.malformed,
            inv.stats.malformed_examples.join("; ")
        ));
    }
    for c in &mut cameras {
        if let Some(stats) = engine.sensor_stats().find(|s| s.name == c.report.name) {
            c.report.pixels = stats.pixels;
        }
        let r = &c.report;
        if r.frames_used == 0 {
            notes.push(format!(
                "camera `{}` mapped no frame: {} label and {} depth images read, {} pairs, {} without a pose, {} undecodable{}, {} refused{}",
                r.name,
                r.labels_read,
                r.depths_read,
                r.frames_paired,
                r.frames_skipped.total(),
                r.undecodable,
                r.undecodable_example.as_ref().map_or(String::new(), |e| format!(" ({e})")),
                r.frames_refused,
                r.refused_example.as_ref().map_or(String::new(), |e| format!(" ({e})")),
            ));
        } else if r.labels_unpaired + r.depths_unpaired > 0 {
            notes.push(format!(
                "camera `{}`: {} label and {} depth images had no partner within {} s and were dropped",
                r.name,
                r.labels_unpaired,
                r.depths_unpaired,
                planned.iter().find(|c| c.name == r.name).map_or(0.0, |c| c.pair_tolerance_s)
            ));
        }
    }
    let pose_timing =
        (!chosen.stamps.is_empty()).then(|| StreamTiming::analyze(&chosen.stamps, &chosen.receive, limits(cfg)));
    let first = &lidars[0].report;
    let report = LogReport {
        format: inv.format.to_string(),
        scan_topic: first.topic.clone(),
        pose_source: chosen.name.clone(),
        sync: match mode {
            SyncMode::Interpolate => "interpolate".into(),
            SyncMode::Nearest { tolerance_s } => format!("nearest (tolerance {tolerance_s:.3} s)"),
        },
        deskew: lidars.iter().any(|l| l.report.scans_deskewed > 0),
        scans_read: read,
        scans_used: lidars.iter().map(|l| l.report.scans_used).sum(),
        scans_skipped: skipped,
        scans_deskewed: lidars.iter().map(|l| l.report.scans_deskewed).sum(),
        scans_reordered: lidars.iter().map(|l| l.report.scans_reordered).sum(),
        sensors: bound
            .lidars
            .iter()
            .map(|b| (b.lidar.name.clone(), format!("lidar {}", b.topic)))
            .chain(
                bound
                    .sensors
                    .iter()
                    .map(|b| (b.sensor.name.clone(), format!("{} {}", b.sensor.kind.as_str(), b.topic))),
            )
            .collect(),
        pose_track: chosen.counts.clone(),
        scan_timing: first.timing,
        pose_timing,
        extrinsics: first.extrinsics.clone(),
        estimator: chosen.estimator.clone(),
        merge: merge.stats().to_vec(),
        merge_peak_queued: merge.peak_queued(),
        frames: tree.report(),
        skipped_by_type: inv.stats.skipped_by_type.clone(),
        malformed_records: inv.stats.malformed,
        decode_s: inv.read_s,
        track_s,
        map_s,
        lidars: lidars.into_iter().map(|l| l.report).collect(),
        cameras: cameras.into_iter().map(|c| c.report).collect(),
        correlated_merged: engine.stats().correlated_merged,
        slam: slam_summary.map(|s| *s),
    };
    notes.extend(chosen.notes.iter().cloned());
    Ok(MapRun { engine, format: inv.format, report, trajectory, notes })
}
