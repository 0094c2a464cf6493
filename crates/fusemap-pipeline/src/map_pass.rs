//! The second pass: every lidar's scans and every camera's images, merged in stamp order
//! (file order for poses on the scan lines, which do not depend on the stamps: some
//! corrected CARMEN logs have broken or all-zero stamps), each placed with the pose track
//! at its own stamp and inserted into the engine's maps; then the notes and the report of
//! what happened to them.

use crate::camera::{build_camera, BuiltCamera, MappedCamera};
use crate::extrinsics::frame_tree;
use crate::insert::{release, Endpoints, Inserter, Mapped};
use crate::lidar_frames::{lidar_setup, other_frames};
use crate::merge::{OrderedMerge, Pushed};
use crate::pass_notes::lidar_notes;
use crate::progress::Progress;
use crate::recording::{for_each_range_message, Inventory, RangeMessage};
use crate::report::{LidarReport, LogReport};
use crate::sensors::Bound;
use crate::sync::{limits, offset_ns, sync_mode, Skipped};
use crate::track::{count_reordered, ChosenTrack, Track};
use crate::{PipelineError, Stage};
use fusemap_core::calibration::{CameraSample, SurfaceHits};
use fusemap_core::config::{default_camera, Plan, PlannedCamera, SensorKind};
use fusemap_core::frames::FrameTree;
use fusemap_core::fusion::{Correlation, Engine, MapSet};
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::FusionGrid;
use fusemap_core::measurement::SensorId;
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::{Stamp, StreamTiming, SyncMode};
use fusemap_io::log::LogFormat;
use fusemap_io::map_mcap::MAP_FRAME;
use std::collections::HashSet;
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
    /// The track the pass placed the scans with.
    pub track: Track,
    /// Each camera's frames as a calibration reads them (by name), when
    /// [`PassMaps::camera_samples`] asked.
    pub camera_samples: Vec<(String, Vec<CameraSample>)>,
    /// The lidars' returns per cell, kept with the camera samples.
    pub lidar_surface: Option<SurfaceHits>,
    /// Every lidar return as placed, one point per cell per scan, when `[output] points =
    /// "endpoints"` asked (empty otherwise).
    pub endpoints: Vec<[f32; 2]>,
    /// `map → odom` at the track's last stamp, with the odometry frame's name, where the
    /// track is odometry (identity) or SLAM's correction of it; for `map.mcap`'s
    /// `/tf_static`.
    pub map_from_odom: Option<(String, Pose2)>,
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

/// The cameras to map: the configured ones, else a default camera when the log carries
/// the usual camera topics (and the camera kind is not disabled).
pub(crate) fn planned_cameras(
    plan: &Plan,
    inv: &Inventory,
    notes: &mut Vec<String>,
) -> Result<Vec<PlannedCamera>, PipelineError> {
    if !plan.cameras.is_empty() || plan.disabled_kinds.contains(&SensorKind::Camera) {
        return Ok(plan.cameras.clone());
    }
    let c = default_camera(plan.occupancy.prior)
        .map_err(|e| PipelineError::refused(Stage::Configuration, e.to_string()))?;
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

/// What the pass reads from: the plan, the recording's inventory, the bound sensors, the
/// pose track and the frame tree.
struct Inputs<'a> {
    plan: &'a Plan,
    inv: &'a Inventory,
    bound: &'a Bound,
    track: &'a Track,
    tree: &'a FrameTree,
}

/// The merge and the sensors that feed it, each with its streams and its report.
struct Streams {
    merge: OrderedMerge<RangeMessage>,
    lidars: Vec<Mapped>,
    cameras: Vec<MappedCamera>,
    /// The cameras the plan asked for (or found), mapped or not.
    planned: Vec<PlannedCamera>,
}

/// The pose every scan was placed with, the lidars' returns per cell if kept, and their
/// returns as points if kept.
type Placed = (Vec<(Stamp, Pose2)>, Option<SurfaceHits>, Vec<[f32; 2]>);

/// The maps a pass builds, and whether the log's later part is held out of them.
#[derive(Default)]
pub struct PassMaps {
    /// Several maps fed in one pass, each from its own subset of sensors (the design
    /// document's leave-one-out maps, §5.2); the lidars get sensor ids 0, 1, … in the order
    /// of `bound.lidars`. `None`: one map of every sensor.
    pub set: Option<MapSet>,
    /// The share of the log, at its end, held out of the maps: its observations' endpoints
    /// are counted instead ([`Engine::held_out`]), §5.2's later period. By time span on a
    /// timed track; by scan count on poses of the scan lines, whose stamps may be broken.
    pub holdout_share: Option<f64>,
    /// Keep every placed camera frame's obstacle points in the base frame
    /// ([`MapRun::camera_samples`]): what the camera's calibration scores.
    pub camera_samples: bool,
    /// Keep the lidar returns for endpoint clouds ([`MapRun::endpoints`]): only a run that
    /// writes them asks (`OutputConfig::endpoint_clouds`).
    pub endpoints: bool,
}

impl From<MapSet> for PassMaps {
    fn from(set: MapSet) -> Self {
        Self { set: Some(set), holdout_share: None, camera_samples: false, endpoints: false }
    }
}

/// Maps a recording whose first pass is done with a given pose track (a calibration
/// search, or a comparison of tracks on one log, maps the same scans with several), into
/// `maps`.
pub fn map_with_track(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    mut chosen: ChosenTrack,
    track_s: f64,
    maps: PassMaps,
    progress: &mut dyn FnMut(Progress),
) -> Result<MapRun, PipelineError> {
    let cfg = &plan.log;
    let mut notes = bound.notes.clone();
    let slam_summary = chosen.slam.take();
    if bound.lidars.is_empty() {
        return Err(PipelineError::refused(
            Stage::Sensors,
            "no lidar to map: every [[sensor]] of kind lidar is disabled",
        ));
    }
    let mode = sync_mode(cfg, &inv.scans[&bound.lidars[0].topic].stamps);
    let mut engine = match maps.set {
        Some(m) => Engine::with_maps(m),
        None => Engine::new(FusionGrid::new(plan.geometry, plan.occupancy)),
    };
    engine.set_limits(&plan.limits);
    let (tree, tree_notes) = frame_tree(cfg, &inv.tf_static, &inv.tf_dynamic);
    notes.extend(tree_notes);
    let input = Inputs { plan, inv, bound, track: &chosen.track, tree: &tree };
    let mut streams = Streams::open(&input, &mut engine, &mut notes)?;
    if maps.camera_samples {
        streams.cameras.iter_mut().for_each(|c| c.samples = Some(Vec::new()));
    }

    let t_map = Instant::now();
    let hold_from = maps.holdout_share.and_then(|share| streams.holdout_key(&input, share));
    // On poses of the scan lines the keys of scans count them; only scans start the
    // held-out period there (the images of such a log, if any, carry stamps).
    let scans_only = matches!(chosen.track, Track::ScanLine(_));
    let hold_from = hold_from.map(|k| (k, scans_only));
    let keep_endpoints = maps.endpoints;
    let (placed, lidar_surface, endpoints) =
        streams.run(&input, &mut engine, mode, hold_from, (maps.camera_samples, keep_endpoints), progress)?;
    let map_s = t_map.elapsed().as_secs_f64();
    let trajectory = match &chosen.track {
        Track::ScanLine(_) => placed,
        Track::Timed(t) => with_scan_poses(t.samples(), placed),
    };
    let map_from_odom = map_from_odom(&chosen, &tree, &trajectory, &mut notes);

    let skipped = lidar_notes(&streams.lidars, cfg, &mut notes);
    if let Some(cut) = &inv.truncated {
        notes.push(format!("the log is cut short, and was mapped up to the cut: {cut}"));
    }
    notes.extend(inv.malformed_note());
    camera_notes(&engine, &mut streams, &mut notes);
    let camera_samples =
        streams.cameras.iter_mut().filter_map(|c| Some((c.report.name.clone(), c.samples.take()?))).collect();
    let mut report = log_report(&input, &chosen, streams, mode, skipped, &tree);
    (report.track_s, report.map_s) = (track_s, map_s);
    report.correlated_merged = engine.stats().correlated_merged;
    report.log_findings = crate::log_findings::log_findings(plan, inv, bound, &chosen, slam_summary.is_some());
    report.slam = slam_summary.map(|s| *s);
    notes.extend(chosen.notes.iter().cloned());
    Ok(MapRun {
        engine,
        format: inv.format,
        report,
        trajectory,
        notes,
        track: chosen.track,
        camera_samples,
        lidar_surface,
        endpoints,
        map_from_odom,
    })
}

/// The `map → odom` transform map.mcap's `/tf_static` gives, when the track is a timed one
/// in an odometry frame: the frame correction at the last scan (identity without SLAM).
/// `None` when the log's own TF already parents that frame (a localiser's `map → odom`: a
/// second parent would break the tree a player of both files builds) or it is the map frame.
fn map_from_odom(
    chosen: &ChosenTrack,
    tree: &FrameTree,
    trajectory: &[(Stamp, Pose2)],
    notes: &mut Vec<String>,
) -> Option<(String, Pose2)> {
    match (&chosen.track, &chosen.odom_frame, trajectory.last()) {
        // The log's own TF already places the odometry frame (a localiser's `map → odom`):
        // a second parent would break the tree a player of both files builds.
        (Track::Timed(_), Some(frame), Some(_))
            if frame == MAP_FRAME || [frame.clone(), format!("/{frame}")].iter().any(|f| tree.parent(f).is_some()) =>
        {
            notes.push(format!(
                "map.mcap has no /tf_static: the log's TF already gives `{frame}` a parent, or it is the map frame"
            ));
            None
        }
        // Without SLAM the odometry frame is the map frame.
        (Track::Timed(t), Some(frame), Some(&(last, _))) => {
            Some((frame.clone(), t.frame_correction_at(last).unwrap_or(Pose2::IDENTITY)))
        }
        _ => None,
    }
}

/// Opens the pass's streams as [`map_with_track`] does (each lidar's model and mount, each
/// camera's intrinsics and images) and inserts nothing: the refusal, or the notes. `fusemap
/// doctor` runs this, so it fails wherever `map` would before the first scan, for the
/// same reason.
pub(crate) fn check_streams(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    track: &Track,
) -> Result<Vec<String>, PipelineError> {
    let (tree, mut notes) = frame_tree(&plan.log, &inv.tf_static, &inv.tf_dynamic);
    let mut engine = Engine::new(FusionGrid::new(plan.geometry, plan.occupancy));
    let input = Inputs { plan, inv, bound, track, tree: &tree };
    Streams::open(&input, &mut engine, &mut notes)?;
    Ok(notes)
}

impl Streams {
    /// Registers every lidar (one engine sensor per frame id its topic carries) and every
    /// camera with the engine and the merge, and the correlation groups of the plan.
    fn open(input: &Inputs, engine: &mut Engine, notes: &mut Vec<String>) -> Result<Self, PipelineError> {
        let window = match input.track {
            Track::ScanLine(_) => 0,
            Track::Timed(_) => offset_ns(input.plan.log.reorder_window_s),
        };
        let mut s =
            Streams { merge: OrderedMerge::new(window), lidars: Vec::new(), cameras: Vec::new(), planned: Vec::new() };
        for b in &input.bound.lidars {
            s.add_lidar(input, b, engine, notes)?;
        }
        s.planned = planned_cameras(input.plan, input.inv, notes)?;
        for c in &s.planned.clone() {
            let built = build_camera(
                c,
                &input.plan.classes,
                input.plan.geometry.resolution(),
                input.inv,
                input.tree,
                &input.plan.log,
                notes,
            );
            let (model, report) = match built {
                Ok(BuiltCamera::Ready(b)) => *b,
                // Streams that are there but unusable never stop a run the lidar maps, nor
                // does any fault of a camera the config did not ask for: the log is mapped
                // without it, and the note says why.
                Ok(BuiltCamera::Unusable(why)) => {
                    notes.push(format!("camera `{}` is not mapped, the other sensors are: {why}", c.name));
                    continue;
                }
                Err(e) if !c.explicit => {
                    notes.push(format!("the camera found on `{}` is not mapped: {e}", c.topic));
                    continue;
                }
                Err(e) => return Err(e),
            };
            let id = engine.add_camera(c.name.clone(), model);
            let label_stream = s.merge.add_stream(c.topic.clone());
            let depth_stream = s.merge.add_stream(c.depth_topic.clone());
            s.cameras.push(MappedCamera::new(id, c, label_stream, depth_stream, report));
        }
        if !s.cameras.is_empty() {
            engine.set_dynamic(input.plan.dynamic, input.plan.fusion.route_lidar_hits_to_dynamic);
        }
        s.set_correlation(input, engine, notes);
        Ok(s)
    }

    /// One lidar: its main frame's model, a sensor for each other frame id on its topic,
    /// its merge stream and its report.
    fn add_lidar(
        &mut self,
        input: &Inputs,
        b: &crate::sensors::BoundLidar,
        engine: &mut Engine,
        notes: &mut Vec<String>,
    ) -> Result<(), PipelineError> {
        let (inv, cfg) = (input.inv, &input.plan.log);
        let topic = &inv.scans[&b.topic];
        let (frame, ext, model) = lidar_setup(b, inv, input.tree, cfg, notes)?;
        let id = engine.add_lidar(b.lidar.name.clone(), model);
        let by_frame = other_frames(b, &frame, inv, input.tree, cfg, notes)
            .into_iter()
            .map(|(f, (_, model))| {
                let sensor = engine.add_lidar(format!("{}@{f}", b.lidar.name), model);
                (f, sensor)
            })
            .collect();
        let mut other_frames = topic.frames.clone();
        other_frames.remove(&frame);
        other_frames.remove("");
        let timed = matches!(input.track, Track::Timed(_));
        self.lidars.push(Mapped {
            id,
            offset_ns: offset_ns(b.lidar.time_offset_s),
            stream: self.merge.add_stream(b.topic.clone()),
            report: LidarReport {
                name: b.lidar.name.clone(),
                topic: b.topic.clone(),
                frame,
                other_frames,
                scans_read: topic.stamps.len() as u64,
                scans_used: 0,
                scans_skipped: Skipped::default(),
                scans_deskewed: 0,
                scans_reordered: if timed { count_reordered(topic.stamps.iter().copied()) } else { 0 },
                time_offset_s: b.lidar.time_offset_s,
                timing: StreamTiming::analyze(&topic.stamps, &topic.receive, limits(cfg)),
                extrinsics: ext,
            },
            line_glitches: if timed { HashSet::new() } else { topic.line_glitches(&cfg.motion_limits()) },
            bad_angles_example: None,
            repeats: Default::default(),
            by_frame,
        });
        Ok(())
    }

    /// The plan's correlation groups by sensor id (`fusion.correlated`), named sensors
    /// this run does not map left out with a note.
    fn set_correlation(&self, input: &Inputs, engine: &mut Engine, notes: &mut Vec<String>) {
        let fusion = &input.plan.fusion;
        if fusion.correlated.is_empty() {
            return;
        }
        let id_of = |name: &str| {
            self.lidars
                .iter()
                .zip(&input.bound.lidars)
                .find(|(_, b)| b.lidar.name == name)
                .map(|(l, _)| l.id)
                .or_else(|| self.cameras.iter().find(|c| c.report.name == name).map(|c| c.id))
        };
        let mut groups = Vec::new();
        for g in &fusion.correlated {
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
            window_ns: offset_ns(fusion.correlation_window_s),
            rule: fusion.merge,
        });
    }

    /// Streams the recording's scans and images through the merge into the engine; the
    /// pose every scan was placed with.
    fn run(
        &mut self,
        input: &Inputs,
        engine: &mut Engine,
        mode: SyncMode,
        hold_from: Option<(i64, bool)>,
        (sample, keep_endpoints): (bool, bool),
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Placed, PipelineError> {
        let inv = input.inv;
        let topics: Vec<String> = input.bound.lidars.iter().map(|b| b.topic.clone()).collect();
        let image_topics: Vec<String> =
            self.planned.iter().flat_map(|c| [c.topic.clone(), c.depth_topic.clone()]).collect();
        let total: u64 = self.lidars.iter().map(|l| l.report.scans_read).sum::<u64>()
            + image_topics.iter().map(|t| inv.images.get(t).map_or(0, |i| i.stamps.len() as u64)).sum::<u64>();
        progress(Progress::Phase { name: "mapping", total });
        let mut inserter = Inserter {
            engine,
            track: input.track,
            mode,
            deskew: input.plan.log.deskew,
            scan: LaserScan { stamp: Stamp::ZERO, angle_min: 0.0, angle_increment: 0.0, ranges: Vec::new() },
            last: None,
            placed: Vec::new(),
            lines_seen: Default::default(),
            next_id: 0,
            surface: sample.then(SurfaceHits::default),
            endpoints: keep_endpoints.then(Endpoints::default),
        };
        let mut seq = 0i64;
        for_each_range_message(&inv.path, &inv.limits, &topics, &image_topics, |msg| {
            let Some((stream, key)) = self.key_of(&msg, input.track, &mut seq) else { return Ok(()) };
            if self.merge.push(stream, key, msg) == Pushed::Late {
                self.count_late(stream);
                progress(Progress::Advance(1));
            }
            while let Some((s, key, msg)) = self.merge.pop_ready() {
                hold_out_from(inserter.engine, hold_from, key, &msg);
                release(&mut inserter, &mut self.lidars, &mut self.cameras, s, Stamp(key), msg)?;
                progress(Progress::Advance(1));
            }
            Ok(())
        })?;
        while let Some((s, key, msg)) = self.merge.pop_final() {
            hold_out_from(inserter.engine, hold_from, key, &msg);
            release(&mut inserter, &mut self.lidars, &mut self.cameras, s, Stamp(key), msg)?;
            progress(Progress::Advance(1));
        }
        for c in &mut self.cameras {
            c.finish();
        }
        progress(Progress::Done);
        let endpoints = inserter.endpoints.take().map_or_else(Vec::new, |e| e.points);
        Ok((std::mem::take(&mut inserter.placed), inserter.surface.take(), endpoints))
    }

    /// The merge key from which the later `share` of the log is held out: the
    /// `(1 − share)` quantile of the observations' keys (their stamps with each sensor's
    /// clock offset) on a timed track, so that a stray stamp years off moves it by one
    /// observation, not by years; by the scan count on poses of the scan lines (their keys
    /// count the scans). `None` when the log has nothing to split.
    fn holdout_key(&self, input: &Inputs, share: f64) -> Option<i64> {
        let inv = input.inv;
        if matches!(input.track, Track::ScanLine(_)) {
            let n: u64 = self.lidars.iter().map(|l| l.report.scans_read).sum();
            return Some(((1.0 - share) * n as f64).floor() as i64 + 1);
        }
        let lidar = self.lidars.iter().map(|l| (&inv.scans[&l.report.topic].stamps, l.offset_ns));
        let camera =
            self.cameras.iter().filter_map(|c| inv.images.get(&c.report.topic).map(|i| (&i.stamps, c.offset_ns)));
        let mut keys: Vec<i64> = lidar
            .chain(camera)
            .flat_map(|(stamps, offset)| stamps.iter().map(move |s| s.0.saturating_add(offset)))
            .collect();
        keys.sort_unstable();
        let at = ((1.0 - share) * keys.len() as f64).floor() as usize;
        keys.get(at.min(keys.len().saturating_sub(1))).copied()
    }

    /// The merge stream of a message and its merge key (its stamp with the sensor's time
    /// offset; for poses on the scan lines, the file order); `None` for a topic no mapped
    /// sensor reads.
    fn key_of(&self, msg: &RangeMessage, track: &Track, seq: &mut i64) -> Option<(usize, i64)> {
        match msg {
            RangeMessage::Scan(scan) => {
                let l = self.lidars.iter().find(|l| l.report.topic == scan.topic)?;
                let key = match track {
                    Track::ScanLine(_) => {
                        *seq += 1;
                        *seq
                    }
                    Track::Timed(_) => scan.scan.stamp.0.saturating_add(l.offset_ns),
                };
                Some((l.stream, key))
            }
            RangeMessage::Image(image) => self.cameras.iter().find_map(|c| {
                (c.report.topic == image.topic)
                    .then_some(c.label_stream)
                    .or_else(|| (c.report.depth_topic == image.topic).then_some(c.depth_stream))
                    .map(|s| (s, image.stamp.0.saturating_add(c.offset_ns)))
            }),
        }
    }

    /// Counts a message the merge dropped for arriving behind its reorder window.
    fn count_late(&mut self, stream: usize) {
        if let Some(l) = self.lidars.iter_mut().find(|l| l.stream == stream) {
            l.report.scans_skipped.late += 1;
        } else if let Some(c) = self.cameras.iter_mut().find(|c| c.label_stream == stream || c.depth_stream == stream) {
            c.report.frames_skipped.late += 1;
        }
    }
}

/// Holds the rest of the pass out of the maps once the merge reaches `hold_from`'s key
/// (with its flag set, only a scan's key counts).
fn hold_out_from(engine: &mut Engine, hold_from: Option<(i64, bool)>, key: i64, msg: &RangeMessage) {
    let counts = |scans_only: bool| !scans_only || matches!(msg, RangeMessage::Scan(_));
    if hold_from.is_some_and(|(h, scans_only)| key >= h && counts(scans_only)) {
        engine.hold_out();
    }
}

/// The cameras' pixel counts from the engine, and a note for a camera that mapped no
/// frame or dropped unpaired images.
fn camera_notes(engine: &Engine, streams: &mut Streams, notes: &mut Vec<String>) {
    for c in &mut streams.cameras {
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
                streams.planned.iter().find(|c| c.name == r.name).map_or(0.0, |c| c.pair_tolerance_s)
            ));
        }
    }
}

/// The run report of the pass (its timings, the engine's counters, the SLAM summary and
/// the log's findings are the caller's to fill in).
fn log_report(
    input: &Inputs,
    chosen: &ChosenTrack,
    streams: Streams,
    mode: SyncMode,
    skipped: Skipped,
    tree: &FrameTree,
) -> LogReport {
    let (inv, bound, lidars) = (input.inv, input.bound, &streams.lidars);
    let pose_timing = (!chosen.stamps.is_empty())
        .then(|| StreamTiming::analyze(&chosen.stamps, &chosen.receive, limits(&input.plan.log)));
    let first = &lidars[0].report;
    let sensors = bound
        .lidars
        .iter()
        .map(|b| (b.lidar.name.clone(), format!("lidar {}", b.topic)))
        .chain(bound.sensors.iter().map(|b| (b.sensor.name.clone(), format!("{} {}", b.sensor.kind.as_str(), b.topic))))
        .collect();
    LogReport {
        format: inv.format.to_string(),
        scan_topic: first.topic.clone(),
        pose_source: chosen.name.clone(),
        sync: match mode {
            SyncMode::Interpolate => "interpolate".into(),
            SyncMode::Nearest { tolerance_s } => format!("nearest (tolerance {tolerance_s:.3} s)"),
        },
        deskew: lidars.iter().any(|l| l.report.scans_deskewed > 0),
        scans_read: lidars.iter().map(|l| l.report.scans_read).sum(),
        scans_used: lidars.iter().map(|l| l.report.scans_used).sum(),
        scans_skipped: skipped,
        scans_deskewed: lidars.iter().map(|l| l.report.scans_deskewed).sum(),
        scans_reordered: lidars.iter().map(|l| l.report.scans_reordered).sum(),
        sensors,
        pose_track: chosen.counts.clone(),
        scan_timing: first.timing,
        pose_timing,
        extrinsics: first.extrinsics.clone(),
        estimator: chosen.estimator.clone(),
        merge: streams.merge.stats().to_vec(),
        merge_peak_queued: streams.merge.peak_queued(),
        frames: tree.report(),
        skipped_by_type: inv.stats.skipped_by_type.clone(),
        malformed_records: inv.stats.malformed,
        decode_s: inv.read_s,
        track_s: 0.0,
        map_s: 0.0,
        lidars: streams.lidars.into_iter().map(|l| l.report).collect(),
        cameras: streams.cameras.into_iter().map(|c| c.report).collect(),
        correlated_merged: 0,
        slam: None,
        log_findings: Vec::new(),
    }
}
