//! The mapping pass's inserts: each scan released by the ordered merge goes into the
//! engine with the pose of its own stamp (de-skewed beam by beam where the scan says how
//! long it took), from its own frame's sensor; repeated scans, scans whose beams cannot be
//! placed and scans without a pose are counted, not drawn. Each insert gets one
//! observation id, so evidence of one instant is counted once (OctoMap's per-scan update,
//! Hornung et al. 2013).

use crate::camera::MappedCamera;
use crate::outputs::map_formats::endpoint_bytes;
use crate::recording::{line_key, LineKey, RangeMessage};
use crate::report::LidarReport;
use crate::track::{LinePoses, Track};
use crate::{PipelineError, Stage};
use fusemap_core::calibration::SurfaceHits;
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::{CellIndex, GridGeometry};
use fusemap_core::measurement::{ObservationId, RangeData, SensorId};
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::log::ScanMessage;
use std::collections::{HashMap, HashSet};

/// One lidar as the second pass uses it.
pub(crate) struct Mapped {
    pub(crate) id: SensorId,
    pub(crate) offset_ns: i64,
    pub(crate) stream: usize,
    pub(crate) report: LidarReport,
    /// Scan lines whose pose is a glitch (a scan-line track only).
    pub(crate) line_glitches: HashSet<LineKey>,
    /// Why the first scan refused for its beam angles was refused.
    pub(crate) bad_angles_example: Option<String>,
    /// The scan before, to insert a repeated message once.
    pub(crate) repeats: crate::repeats::RepeatFilter,
    /// The sensors of the topic's other frame ids, each with its own mount.
    pub(crate) by_frame: HashMap<String, SensorId>,
}

/// Inserts one released message: a lidar's scan, or a camera's image (a frame when it
/// completes a label + depth pair).
pub(crate) fn release(
    inserter: &mut Inserter<'_>,
    lidars: &mut [Mapped],
    cameras: &mut [MappedCamera],
    stream: usize,
    key: Stamp,
    msg: RangeMessage,
) -> Result<(), PipelineError> {
    match msg {
        RangeMessage::Scan(scan) => {
            let l = lidars.iter_mut().find(|l| l.stream == stream).expect("a scan stream is a lidar's");
            inserter.insert(l, key, &scan)
        }
        RangeMessage::Image(image) => {
            let c = cameras
                .iter_mut()
                .find(|c| c.label_stream == stream || c.depth_stream == stream)
                .expect("an image stream is a camera's");
            if let Some(frame) = c.take(stream, key, image) {
                let id = ObservationId(inserter.next_id);
                inserter.next_id += 1;
                c.insert(inserter.engine, inserter.track, inserter.mode, id, &frame)?;
            }
            Ok(())
        }
    }
}

/// The pose of a scan line: SLAM's optimised pose of the line when SLAM placed it, else
/// (its pose was a glitch) interpolated between its neighbours in time where it can be;
/// without SLAM, the line's own pose unless it is a glitch. `None`, counted in the lidar's
/// report, when the line has no usable pose.
fn line_pose(
    corrected: Option<&LinePoses>,
    lines_seen: &mut HashMap<LineKey, usize>,
    l: &mut Mapped,
    msg: &ScanMessage,
) -> Option<Pose2> {
    let stamp = msg.scan.stamp;
    let Some(line) = msg.pose.filter(|p| p.is_finite()) else {
        l.report.scans_skipped.no_pose_on_line += 1;
        return None;
    };
    let key = line_key(stamp, line);
    let glitch = l.line_glitches.contains(&key);
    let pose = match corrected {
        None if glitch => None,
        None => Some(line),
        Some(c) => {
            let k = lines_seen.entry(key).or_insert(0);
            *k += 1;
            let placed = if glitch { None } else { c.pose(stamp, line, *k - 1) };
            placed.or_else(|| c.interpolated(stamp))
        }
    };
    if pose.is_none() {
        match glitch {
            true => l.report.scans_skipped.pose_glitch += 1,
            false => l.report.scans_skipped.no_pose_on_line += 1,
        }
    }
    pose
}

/// Inserts released scans with their poses.
pub(crate) struct Inserter<'a> {
    pub(crate) engine: &'a mut Engine,
    pub(crate) track: &'a Track,
    pub(crate) mode: SyncMode,
    pub(crate) deskew: bool,
    pub(crate) scan: LaserScan,
    pub(crate) last: Option<Stamp>,
    /// The pose each scan was placed with, at its stamp, in the order inserted (what
    /// `trajectory.tum` holds beside the track's own samples).
    pub(crate) placed: Vec<(Stamp, Pose2)>,
    /// Lines met so far by their key (the `k`-th line with a key takes the `k`-th pose).
    pub(crate) lines_seen: HashMap<LineKey, usize>,
    /// The next observation id: one per scan released by the merge, so that every insert
    /// is named (evidence of one instant from several sensors will share one).
    pub(crate) next_id: u64,
    /// The lidars' returns per cell, when a calibration asked (see [`SurfaceHits`]).
    pub(crate) surface: Option<SurfaceHits>,
    /// Every scan's returns, one a cell a scan, when `[output] points = "endpoints"`.
    pub(crate) endpoints: Option<Endpoints>,
}

/// The lidar returns as placed, one point per cell per scan (`[output] points =
/// "endpoints"`): a localisation map that keeps where in its cell each wall was hit.
#[derive(Default)]
pub(crate) struct Endpoints {
    pub(crate) points: Vec<[f32; 2]>,
    seen: HashSet<CellIndex>,
}

impl Endpoints {
    /// Adds the hit rays' ends of one scan, the first in each cell.
    fn add(&mut self, data: &RangeData, geometry: &GridGeometry) {
        self.seen.clear();
        for r in data.rays.iter().filter(|r| r.hit) {
            if geometry.cell_of(r.end).is_some_and(|c| self.seen.insert(c)) {
                self.points.push([r.end.x as f32, r.end.y as f32]);
            }
        }
    }
}

impl Inserter<'_> {
    /// Keeps the last inserted scan's returns, when asked; an error once they no longer
    /// fit in `[limits] memory_mib` beside the maps (at [`endpoint_bytes`]: a log's returns
    /// grow with its length, and an hour of them can take gigabytes).
    fn keep_endpoints(&mut self, stamp: Stamp) -> Result<(), PipelineError> {
        let Some(e) = &mut self.endpoints else { return Ok(()) };
        e.add(self.engine.last_range_data(), self.engine.maps().primary().grid().geometry());
        let Some((maps, limit)) = self.engine.memory_use() else { return Ok(()) };
        let kept = endpoint_bytes(e.points.len(), e.points.capacity());
        if maps.saturating_add(kept) <= limit {
            return Ok(());
        }
        Err(PipelineError::refused(
            Stage::Budget,
            format!(
                "the lidar returns kept for [output] points = \"endpoints\" reached limits.memory_mib = {} MiB at the \
             scan stamped {:.6} s ({} returns need {} MiB to hold and write, beside the maps' {} MiB); raise \
             limits.memory_mib, or write the occupied cells (points = \"cells\")",
                limit >> 20,
                stamp.as_secs_f64(),
                e.points.len(),
                kept >> 20,
                maps >> 20
            ),
        ))
    }

    fn insert(&mut self, l: &mut Mapped, key: Stamp, msg: &ScanMessage) -> Result<(), PipelineError> {
        if l.repeats.is_repeat(msg) {
            l.report.scans_skipped.repeated += 1;
            return Ok(());
        }
        if let Some(why) = msg.angle_fault() {
            l.report.scans_skipped.bad_angles += 1;
            l.bad_angles_example.get_or_insert(why);
            return Ok(());
        }
        // Angles at LaserScan's float32 precision whatever the format, so that the same
        // scan read from CARMEN text or from a ROS message gives the same rays.
        let scan = &mut self.scan;
        scan.angle_min = msg.scan.angle_min as f32 as f64;
        scan.angle_increment = msg.scan.angle_increment as f32 as f64;
        scan.ranges.clone_from(&msg.scan.ranges);
        let stamp = msg.scan.stamp;
        // The sensor of the scan's own frame (its own mount), else the lidar's.
        let sensor = l.by_frame.get(msg.frame_id.as_str()).copied().unwrap_or(l.id);
        let id = ObservationId(self.next_id);
        self.next_id += 1;
        match self.track {
            Track::ScanLine(corrected) => {
                // Judged by the line's own pose (as SLAM judged it, leaving the same lines
                // out), before SLAM's pose is looked up.
                let own =
                    msg.pose.filter(|p| p.is_finite() && !l.line_glitches.contains(&line_key(msg.scan.stamp, *p)));
                if own.is_some_and(|p| l.repeats.is_frozen(p)) {
                    l.report.scans_skipped.frozen += 1;
                    return Ok(());
                }
                let Some(pose) = line_pose(corrected.as_ref(), &mut self.lines_seen, l, msg) else {
                    return Ok(());
                };
                // Line poses do not depend on the stamp: applied in file order.
                scan.stamp = self.last.map_or(stamp, |last| last.max(stamp));
                self.engine.insert_scan_observed(sensor, id, scan, msg.range_min, msg.range_max, |_| pose)?;
                self.placed.push((scan.stamp, pose));
                let at = scan.stamp;
                self.last = Some(at);
                self.keep_endpoints(at)?;
            }
            Track::Timed(track) => {
                let t = key;
                let pose = match track.pose_at(t, self.mode) {
                    Ok(p) => p,
                    Err(why) => {
                        l.report.scans_skipped.count(why);
                        return Ok(());
                    }
                };
                if l.repeats.is_frozen(pose) {
                    l.report.scans_skipped.frozen += 1;
                    return Ok(());
                }
                scan.stamp = t;
                let n = scan.ranges.len();
                let ti = msg.time_increment as f64;
                let can_deskew = self.deskew && self.mode == SyncMode::Interpolate && ti > 0.0 && n > 1;
                let end = Stamp(t.0.saturating_add((ti * (n - 1) as f64 * 1e9) as i64));
                if can_deskew && track.pose_at(end, SyncMode::Interpolate).is_ok() {
                    l.report.scans_deskewed += 1;
                    self.engine.insert_scan_observed(sensor, id, scan, msg.range_min, msg.range_max, |i| {
                        let tb = Stamp(t.0.saturating_add((ti * i as f64 * 1e9) as i64));
                        track.pose_at(tb, SyncMode::Interpolate).unwrap_or(pose)
                    })?;
                } else {
                    self.engine.insert_scan_observed(sensor, id, scan, msg.range_min, msg.range_max, |_| pose)?;
                }
                if let Some(s) = &mut self.surface {
                    s.add(self.engine.last_range_data(), self.engine.maps().primary().grid().geometry());
                }
                self.keep_endpoints(t)?;
                self.placed.push((t, pose));
                self.last = Some(t);
            }
        }
        l.report.scans_used += 1;
        Ok(())
    }
}
