//! Cameras in a log run: the model built from the log's `CameraInfo` and the camera's
//! mount, label and depth images paired by stamp, and each frame inserted with the pose at
//! its own (offset-corrected) stamp.
//!
//! Pairing: the merge releases images in stamp order; a label image and a depth image
//! whose stamps differ by at most `pair_tolerance_s` are one frame (the stamp of the
//! label image is the frame's). An image with no partner within the tolerance is counted
//! and dropped, never paired with a far one.

use crate::extrinsics::{from_tf, resolve, ExtrinsicsReport};
use crate::recording::Inventory;
use crate::sync::Skipped;
use crate::track::Track;
use crate::{PipelineError, Stage};
use fusemap_core::calibration::CameraSample;
use fusemap_core::config::{ExtrinsicsSource, LogConfig, PlannedCamera};
use fusemap_core::frames::FrameTree;
use fusemap_core::fusion::{Engine, EngineError};
use fusemap_core::geometry::{Point2, Pose2, Pose3};
use fusemap_core::measurement::{ObservationId, SensorId};
use fusemap_core::sensor::camera::{Band, CameraModel, ClassTable, DepthImage, Pinhole, PixelCounts};
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::log::{image_over_limit, ImageMessage};
use serde::Serialize;

/// What happened to one camera's images.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CameraReport {
    /// The camera's name.
    pub name: String,
    /// Label image topic.
    pub topic: String,
    /// Depth image topic.
    pub depth_topic: String,
    /// Camera-info topic.
    pub info_topic: String,
    /// The optical frame.
    pub frame: String,
    /// Label images read.
    pub labels_read: u64,
    /// Depth images read.
    pub depths_read: u64,
    /// Label + depth pairs formed.
    pub frames_paired: u64,
    /// Label images with no depth image within the tolerance.
    pub labels_unpaired: u64,
    /// Depth images with no label image within the tolerance.
    pub depths_unpaired: u64,
    /// Frames inserted into the map.
    pub frames_used: u64,
    /// Frames with no pose at their stamp, by reason.
    pub frames_skipped: Skipped,
    /// Images whose encoding or layout could not be decoded (the first reason kept).
    pub undecodable: u64,
    /// The first undecodable image's reason.
    pub undecodable_example: Option<String>,
    /// Frames whose images do not fit the camera (sizes).
    pub frames_refused: u64,
    /// The first refusal's reason.
    pub refused_example: Option<String>,
    /// The clock offset applied, seconds.
    pub time_offset_s: f64,
    /// Intrinsics used: width, height, fx, fy, cx, cy.
    pub intrinsics: [f64; 6],
    /// Camera-info messages that differ from the first (intrinsics are taken from the first).
    pub camera_info_differing: u64,
    /// Where the mount came from.
    pub extrinsics: ExtrinsicsReport,
    /// What became of the pixels.
    pub pixels: PixelCounts,
}

/// A label + depth pair ready to insert.
pub(crate) struct Frame {
    /// The label image's (offset-corrected) stamp: the frame's pose is taken there.
    pub(crate) label_stamp: Stamp,
    /// The later of the two stamps: the frame enters the time-ordered engine there.
    pub(crate) release: Stamp,
    pub(crate) label: ImageMessage,
    pub(crate) depth: ImageMessage,
}

/// One camera as the second pass uses it.
pub(crate) struct MappedCamera {
    pub(crate) id: SensorId,
    pub(crate) offset_ns: i64,
    pub(crate) label_stream: usize,
    pub(crate) depth_stream: usize,
    tolerance_ns: i64,
    pending_label: Option<(Stamp, ImageMessage)>,
    pending_depth: Option<(Stamp, ImageMessage)>,
    pub(crate) report: CameraReport,
    /// Every placed frame's obstacle points in the base frame, when a calibration asked.
    pub(crate) samples: Option<Vec<CameraSample>>,
}

/// A calibration keeps obstacle points at least this far inside the obstacle band, metres:
/// nearer its edges depth noise decides the band (a wall's foot measured long falls into
/// the floor band and is dropped, one measured short stays), so the points kept there lie
/// nearer the camera than the wall, and would read as a clock running late while the
/// robot drives at a wall.
const BAND_MARGIN_M: f64 = 0.3;

/// The most obstacle points a calibration keeps of one frame (evenly spread over the
/// frame's points): enough to trace the walls it sees, and a bounded memory per frame.
const SAMPLE_POINTS: usize = 400;

/// The floor fit's points a frame keeps, at most: the pixels on a regular grid.
const FLOOR_POINTS: usize = 300;
/// How far from the configured floor a depth point may lie and still be kept for the floor
/// fit, metres: a camera 5° off in pitch sees the floor 0.35 m off at 4 m.
const FLOOR_REACH_M: f64 = 0.5;

/// A frame's depth points (optical frame) on a grid of about [`FLOOR_POINTS`] pixels,
/// within the camera's depth range and [`FLOOR_REACH_M`] of the floor as the configured
/// mount places them: what the floor fit of `calibrate` needs, whatever their labels.
fn floor_points(model: &CameraModel, depths: &DepthImage) -> Vec<[f32; 3]> {
    let (pin, mount, p) = (model.pinhole(), model.base_from_optical(), model.params());
    let stride = ((pin.pixels() as f64 / FLOOR_POINTS as f64).sqrt().ceil() as usize).max(1);
    let mut out = Vec::new();
    for v in (0..depths.height).step_by(stride) {
        for u in (0..depths.width).step_by(stride) {
            let d = f64::from(depths.at(u, v));
            if !(d.is_finite() && d >= p.min_depth_m && d <= p.max_depth_m) {
                continue;
            }
            let q = pin.ray(f64::from(u), f64::from(v)).map(|c| c * d);
            if (mount.rotate(q)[2] + mount.translation[2]).abs() < FLOOR_REACH_M {
                out.push(q.map(|c| c as f32));
            }
        }
    }
    out
}

/// A camera as the log lets it be built.
pub(crate) enum BuiltCamera {
    /// Its model and the report to fill.
    Ready(Box<(CameraModel, CameraReport)>),
    /// Its streams are in the log but unusable (every image malformed, intrinsics no
    /// pinhole camera has): the run maps with the other sensors, and this says why.
    Unusable(String),
}

/// Builds a camera's model from the inventory: intrinsics from its `CameraInfo`, mount
/// from TF or the config. A topic the log lacks is an error (most often a typo in the
/// config); streams that are there but unusable give [`BuiltCamera::Unusable`], so that
/// one broken stream never sinks a run the lidar can map.
pub(crate) fn build_camera(
    c: &PlannedCamera,
    classes: &ClassTable,
    resolution: f64,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    notes: &mut Vec<String>,
) -> Result<BuiltCamera, PipelineError> {
    let unusable = |m: String| Ok(BuiltCamera::Unusable(m));
    let refuse = |m: String| PipelineError::refused(Stage::Sensors, format!("camera `{}`: {m}", c.name));
    let info = inv.camera_info.get(&c.info_topic).ok_or_else(|| {
        refuse(format!(
            "the log has no camera info on `{}` (the intrinsics of the label and depth images); log camera-info topics: {}",
            c.info_topic,
            list(inv.camera_info.keys())
        ))
    })?;
    if let Some(why) = image_streams(c, inv).map_err(refuse)? {
        return unusable(why);
    }
    let i = &info.first;
    let pinhole = match Pinhole::from_camera_info(i.width, i.height, i.k, &i.distortion_model, &i.d) {
        Ok(p) => p,
        Err(e) => return unusable(format!("camera info on `{}`: {e}", c.info_topic)),
    };
    if info.differing > 0 {
        notes.push(format!(
            "camera `{}`: {} of {} camera-info messages differ from the first; the first is used",
            c.name, info.differing, info.count
        ));
    }
    let labels = &inv.images[&c.topic];
    let first_image = labels.stamps.iter().min().copied();
    if first_image.is_some_and(|s| s < i.stamp) {
        notes.push(format!(
            "camera `{}`: the first camera info arrives after the first image; its intrinsics are used for every frame",
            c.name
        ));
    }
    let frame = c.frame.clone().or_else(|| labels.frame().map(str::to_string)).unwrap_or_default();
    let log_mount = from_tf(tree, &cfg.base_frame, &frame, first_image);
    // Without a mount in the config or the log, the planned default (a level camera looking
    // forward at base_link's origin, REP 103 optical axes), never the identity, whose
    // optical axis would point up.
    let no_mount = !c.mount_given && (log_mount.is_none() || cfg.extrinsics == ExtrinsicsSource::Config);
    if no_mount {
        notes.push(format!(
            "camera `{}`: no mount in the config or the log's TF for `{frame}`; assumed a level camera looking forward at {}'s origin",
            c.name, cfg.base_frame
        ));
    }
    let config_mount = (c.mount_given || no_mount).then_some(c.mount);
    let ext = resolve(&frame, cfg, config_mount, log_mount, notes)?;
    let m = ext.base_from_sensor;
    let base_from_optical = Pose3::new([m.x, m.y, m.z], m.quaternion());
    let model = CameraModel::new(pinhole, base_from_optical, c.params, resolution, classes.clone())
        .map_err(|e| refuse(e.to_string()))?;
    let report = CameraReport {
        name: c.name.clone(),
        topic: c.topic.clone(),
        depth_topic: c.depth_topic.clone(),
        info_topic: c.info_topic.clone(),
        frame,
        time_offset_s: c.time_offset_s,
        intrinsics: [pinhole.width as f64, pinhole.height as f64, pinhole.fx, pinhole.fy, pinhole.cx, pinhole.cy],
        camera_info_differing: info.differing,
        extrinsics: ext,
        ..Default::default()
    };
    Ok(BuiltCamera::Ready(Box::new((model, report))))
}

/// The camera's label and depth topics as the first pass found them: why they are
/// unusable (every message malformed), or the refusal (a topic the log lacks, images over
/// `limits.image_pixels`).
fn image_streams(c: &PlannedCamera, inv: &Inventory) -> Result<Option<String>, String> {
    for t in [&c.topic, &c.depth_topic] {
        if let (false, Some((n, first))) = (inv.images.contains_key(t), inv.stats.malformed_by_topic.get(t)) {
            return Ok(Some(format!("the log's {n} messages on `{t}` are all malformed; the first: {first}")));
        }
        if !inv.images.contains_key(t) {
            return Err(format!("the log has no images on `{t}`; log image topics: {}", list(inv.images.keys())));
        }
    }
    over_image_pixels(c, inv).map_or(Ok(None), Err)
}

/// The refusal the second pass would give at the camera's first image over
/// `limits.image_pixels`, found from the first pass's image sizes: so that `doctor`,
/// which reads no pixels, fails where `map` would, and `map` before it inserts a scan.
fn over_image_pixels(c: &PlannedCamera, inv: &Inventory) -> Option<String> {
    let max = inv.limits.max_image_pixels;
    [&c.topic, &c.depth_topic].into_iter().find_map(|t| {
        let sizes = &inv.images.get(t)?.sizes;
        sizes
            .iter()
            .find_map(|(&(w, h), n)| image_over_limit(w, h, max).map(|why| format!("{n} images on `{t}`: {why}")))
    })
}

fn list<'a>(it: impl Iterator<Item = &'a String>) -> String {
    let v: Vec<&str> = it.map(String::as_str).collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

impl MappedCamera {
    pub(crate) fn new(
        id: SensorId,
        c: &PlannedCamera,
        label_stream: usize,
        depth_stream: usize,
        report: CameraReport,
    ) -> Self {
        Self {
            id,
            offset_ns: crate::sync::offset_ns(c.time_offset_s),
            label_stream,
            depth_stream,
            tolerance_ns: crate::sync::offset_ns(c.pair_tolerance_s),
            pending_label: None,
            pending_depth: None,
            report,
            samples: None,
        }
    }

    /// Takes one released image (`key`: its offset-corrected stamp) and returns a frame
    /// when it completes a pair.
    pub(crate) fn take(&mut self, stream: usize, key: Stamp, msg: ImageMessage) -> Option<Frame> {
        let is_label = stream == self.label_stream;
        if is_label {
            self.report.labels_read += 1;
        } else {
            self.report.depths_read += 1;
        }
        let tol = self.tolerance_ns;
        let (mine, other) = if is_label {
            (&mut self.pending_label, &mut self.pending_depth)
        } else {
            (&mut self.pending_depth, &mut self.pending_label)
        };
        if let Some((t, _)) = other {
            if key.0.abs_diff(t.0) <= tol as u64 {
                let (t_other, m_other) = other.take().expect("checked");
                self.report.frames_paired += 1;
                // The frame is taken at its label image's stamp; it is inserted at `key`,
                // the later of the two (the merge has released everything before it).
                let (label_stamp, label, depth) = if is_label { (key, msg, m_other) } else { (t_other, m_other, msg) };
                return Some(Frame { label_stamp, release: key, label, depth });
            }
            // Released in stamp order: an older partner can no longer be paired.
            other.take();
            if is_label {
                self.report.depths_unpaired += 1;
            } else {
                self.report.labels_unpaired += 1;
            }
        }
        if mine.replace((key, msg)).is_some() {
            if is_label {
                self.report.labels_unpaired += 1;
            } else {
                self.report.depths_unpaired += 1;
            }
        }
        None
    }

    /// Keeps the frame just projected as a calibration's sample: its obstacle points
    /// ([`ClassTable::is_static_obstacle`](fusemap_core::sensor::camera::ClassTable::is_static_obstacle),
    /// obstacle band) back in the base frame, at most [`SAMPLE_POINTS`] of them, and the
    /// depth points near the configured floor ([`floor_points`]).
    fn sample(&mut self, engine: &Engine, stamp: Stamp, pose: Pose2, depths: &DepthImage) {
        let (Some(samples), Some(model)) = (&mut self.samples, engine.camera_model(self.id)) else { return };
        let classes = model.classes();
        let (low, high) =
            (model.params().floor_band_m + BAND_MARGIN_M, model.params().obstacle_max_z_m - BAND_MARGIN_M);
        let to_base = pose.inverse();
        let obstacle: Vec<Point2> = engine
            .last_camera_frame()
            .points
            .iter()
            .filter(|p| p.band == Band::Obstacle && classes.is_static_obstacle(p.class))
            .filter(|p| (low..=high).contains(&(p.height as f64)))
            .map(|p| to_base.transform_point(p.end))
            .collect();
        let step = obstacle.len().div_ceil(SAMPLE_POINTS).max(1);
        let points = obstacle.into_iter().step_by(step).collect();
        samples.push(CameraSample { stamp, points, floor: floor_points(model, depths) });
    }

    /// Counts images left unpaired at the end of the log.
    pub(crate) fn finish(&mut self) {
        self.report.labels_unpaired += self.pending_label.take().is_some() as u64;
        self.report.depths_unpaired += self.pending_depth.take().is_some() as u64;
    }

    /// Decodes and inserts one frame.
    pub(crate) fn insert(
        &mut self,
        engine: &mut Engine,
        track: &Track,
        mode: SyncMode,
        id: ObservationId,
        frame: &Frame,
    ) -> Result<(), PipelineError> {
        let (stamp, label, depth) = (frame.label_stamp, &frame.label, &frame.depth);
        let Track::Timed(track) = track else {
            // Poses written on scan lines (CARMEN) cannot place a camera frame.
            self.report.frames_skipped.no_pose_on_line += 1;
            return Ok(());
        };
        let pose = match track.pose_at(stamp, mode) {
            Ok(p) => p,
            Err(why) => {
                self.report.frames_skipped.count(why);
                return Ok(());
            }
        };
        let decoded = fusemap_io::camera::labels(label).and_then(|l| fusemap_io::camera::depth(depth).map(|d| (l, d)));
        let (labels, depths) = match decoded {
            Ok(v) => v,
            Err(e) => {
                self.report.undecodable += 1;
                self.report.undecodable_example.get_or_insert_with(|| e.to_string());
                return Ok(());
            }
        };
        match engine.insert_camera_frame(self.id, Some(id), frame.release, &labels, &depths, pose) {
            Ok(_) => {
                self.report.frames_used += 1;
                self.sample(engine, stamp, pose, &depths);
                Ok(())
            }
            // Another sensor's observation was applied after this frame's stamp (a clock
            // jump the merge let through): skipped and counted, never the end of the run.
            Err(EngineError::OutOfOrder { .. }) => {
                self.report.frames_skipped.late += 1;
                Ok(())
            }
            Err(EngineError::Camera { error, .. }) => {
                self.report.frames_refused += 1;
                self.report.refused_example.get_or_insert_with(|| error.to_string());
                Ok(())
            }
            Err(e) => Err(e.into()),
        }
    }
}
