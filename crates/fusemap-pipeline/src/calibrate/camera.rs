//! The cameras' clock offsets and mount yaws against the lidar: each camera's frames, as
//! the mapping pass placed them, scored on the lidar-only map of the same pass
//! ([`fusemap_core::calibration::camera_against_map`]).
//!
//! The camera's height above the floor and its tilt (the mount's z, roll and pitch) come
//! from the floor its depth pixels see ([`fusemap_core::calibration::camera_floor`]): the
//! lidar's map cannot give them, the floor fixes exactly them.

use super::{claim, shifted, SensorCalibration};
use crate::map_pass::MapRun;
use crate::track::Track;
use fusemap_core::calibration::{
    camera_against_map, camera_floor, CameraLidarFit, CameraSearch, DistanceField, FloorFit,
};
use fusemap_core::config::SensorKind;
use fusemap_core::fusion::OBSTACLE_PROBABILITY;
use fusemap_core::geometry::{Mount3, Point2, Pose3};
use fusemap_core::grid::logodds::logit;
use fusemap_core::time::SyncMode;
use std::fmt::Write;

/// The name of the lidar-only map of the calibration's pass.
pub(super) const LIDAR_MAP: &str = "lidars";
/// Distances beyond this cost the same: farther than any clock or mount error this
/// search corrects moves a wall point, and near enough that a shelf the lidar cannot see
/// does not pull the estimate. Metres.
const FIELD_REACH_M: f64 = 0.3;

/// One camera's estimate.
pub(super) struct CameraEstimate {
    name: String,
    report: crate::camera::CameraReport,
    fit: CameraLidarFit,
    /// The height and tilt from the floor, or why the floor could not give them.
    floor: Result<FloorFit, String>,
    /// The lidar's yaw correction written beside it: the pass placed the base through the
    /// configured lidar mount, so the camera's fitted yaw is relative to a base turned by
    /// the lidar's error, and turns back with it.
    pub(super) base_turn: f64,
}

/// Each camera that made samples, scored on the lidar map; what could not be fitted, and
/// why, in `undetermined`.
pub(super) fn cameras_against_lidar(run: &MapRun, undetermined: &mut Vec<String>) -> Vec<CameraEstimate> {
    let mut out = Vec::new();
    for (name, samples) in &run.camera_samples {
        let why = |s: String| format!("`{name}`'s clock offset and mount yaw: {s}");
        let Some(report) = run.report.cameras.iter().find(|c| &c.name == name) else { continue };
        let lidar_map = run.engine.maps().by_name(LIDAR_MAP).map(|m| m.grid());
        let Some((grid, area)) = lidar_map.and_then(|g| g.known_box().map(|b| (g, b))) else {
            undetermined.push(why("the lidars observed nothing to score the camera on".into()));
            continue;
        };
        let threshold = logit(OBSTACLE_PROBABILITY) as f32;
        let Some(field) =
            DistanceField::new(&grid.raster(area), |l| l > threshold, run.lidar_surface.as_ref(), FIELD_REACH_M)
        else {
            undetermined.push(why("the lidars' map has no obstacle to score the camera on".into()));
            continue;
        };
        let Track::Timed(track) = &run.track else {
            undetermined.push(why("the poses are on the scan lines, not a timed track".into()));
            continue;
        };
        let pose_at = |t| track.pose_at(t, SyncMode::Interpolate).ok();
        let mount = report.extrinsics.base_from_sensor;
        let centre = Point2::new(mount.x, mount.y);
        let search = CameraSearch::default();
        match camera_against_map(samples, centre, &pose_at, &field, &search) {
            Ok(fit) => {
                if fit.clock.is_none() {
                    undetermined.push(why(format!(
                        "the clock offset: its cost is flat or least at the edge of ±{} s (a robot that never turns \
                         while the camera sees the lidar's walls does not fix it)",
                        search.clock_span_s
                    )));
                }
                if fit.yaw.is_none() {
                    undetermined.push(why(format!(
                        "the mount yaw: its cost is flat or least at the edge of ±{:.0}°",
                        search.yaw_span_rad.to_degrees()
                    )));
                }
                let configured = Pose3::new([mount.x, mount.y, mount.z], mount.quaternion());
                let floor = camera_floor(samples.iter().map(|s| s.floor.as_slice()), &configured);
                match &floor {
                    Err(e) => {
                        undetermined.push(format!("`{name}`'s height above the floor and tilt (z, roll, pitch): {e}"))
                    }
                    Ok(f) => undetermined.extend(refit_needed(name, &configured, f)),
                }
                out.push(CameraEstimate { name: name.clone(), report: report.clone(), fit, floor, base_turn: 0.0 });
            }
            Err(e) => undetermined.push(why(e)),
        }
    }
    out
}

/// A tilt or a height this far from the configured one moves the camera's wall points by
/// more than the clock and yaw fits resolve (1° tilts a wall point 3 m away by 5 cm).
const REFIT_TILT_DEG: f64 = 0.5;
/// … metres.
const REFIT_HEIGHT_M: f64 = 0.02;

/// The clock offset and the yaw were fitted on wall points the pass placed through the
/// configured tilt and height: when the floor puts those far off, the note that says to
/// calibrate again with `calibration.toml`'s camera table pasted in, whose corrected mount
/// places them right. (On the production line with the camera 5 cm high and 3° off in
/// tilt: clock +0.0011 s and yaw −90.083° through the wrong tilt; +0.0038 s and −90.068°
/// with the pasted table, as with the right configuration.)
fn refit_needed(name: &str, configured: &Pose3, f: &FloorFit) -> Option<String> {
    let up = |p: &Pose3| p.inverse().rotate([0.0, 0.0, 1.0]);
    let (a, b) = (up(configured), up(&f.base_from_optical));
    let tilt = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).clamp(-1.0, 1.0).acos().to_degrees();
    let dz = f.z.value - configured.translation[2];
    (tilt > REFIT_TILT_DEG || dz.abs() > REFIT_HEIGHT_M).then(|| {
        format!(
            "`{name}`'s clock offset and yaw as they would be with its tilt and height right: the floor puts the \
             configured ones {tilt:.2}° and {:.1} cm off, and the wall points were placed through them; paste \
             calibration.toml's camera table into the configuration and calibrate again",
            dz.abs() * 100.0
        )
    })
}

/// A yaw interval moved into (−π, π] as a whole (its ends by the same turn).
fn wrapped(i: fusemap_core::calibration::Interval) -> fusemap_core::calibration::Interval {
    let turn = fusemap_core::geometry::normalize_angle(i.value) - i.value;
    shifted(i, turn)
}

impl CameraEstimate {
    /// The configured mount.
    fn mount(&self) -> Mount3 {
        self.report.extrinsics.base_from_sensor
    }

    /// `summary.json`'s entry.
    pub(super) fn entry(&self) -> SensorCalibration {
        let f = &self.fit;
        SensorCalibration {
            name: self.name.clone(),
            kind: SensorKind::Camera,
            x: None,
            y: None,
            yaw: f.yaw.map(|y| wrapped(shifted(y, self.mount().yaw + self.base_turn))),
            z: self.floor.as_ref().ok().map(|f| f.z),
            roll: self.floor.as_ref().ok().map(|f| f.roll),
            pitch: self.floor.as_ref().ok().map(|f| f.pitch),
            time_offset_s: f.clock.map(|c| shifted(c, self.report.time_offset_s)),
            scale: None,
            wheel_base: None,
            cost_before: f.cost_before_m,
            cost_after: f.cost_after_m,
            steps: [f.frames as u64, f.points as u64],
            clock_curve: f.clock_curve.iter().map(|[x, c]| [x + self.report.time_offset_s, *c]).collect(),
            yaw_curve: f.yaw_curve.iter().map(|[x, c]| [x + self.mount().yaw + self.base_turn, *c]).collect(),
        }
    }

    /// Its `[[sensor]]` table for `calibration.toml`.
    pub(super) fn toml(&self, s: &mut String) {
        let (f, r, m) = (&self.fit, &self.report, self.mount());
        let q = |v: &str| serde_json::to_string(v).unwrap_or_default();
        let _ = writeln!(
            s,
            "\n# The camera's obstacle points on the lidars' map, {} frames, {} points; root mean\n\
             # truncated squared distance {:.4} m before, {:.4} m after. 95 % intervals:",
            f.frames, f.points, f.cost_before_m, f.cost_after_m
        );
        let e = self.entry();
        match e.time_offset_s {
            Some(c) => {
                let _ = writeln!(
                    s,
                    "#   time_offset_s {:.4} s ({:.4} .. {:.4}), against the lidar",
                    c.value, c.low, c.high
                );
            }
            None => {
                let _ = writeln!(s, "#   time_offset_s: not determined by this log; kept as configured");
            }
        }
        if let Some(y) = e.yaw {
            let _ = writeln!(s, "#   yaw {:.5} rad ({:.5} .. {:.5})", y.value, y.low, y.high);
            if self.base_turn != 0.0 {
                let _ = writeln!(
                    s,
                    "#   (with the lidar's yaw correction, {:.5} rad, which turns the base)",
                    self.base_turn
                );
            }
        }
        match &self.floor {
            Ok(f) => {
                let _ = writeln!(
                    s,
                    "#   from the floor ({} frames, {} points; RMS height {:.4} m before, {:.4} m after):\n\
                     #   z {:.4} m ({:.4} .. {:.4}), roll {:.5} rad ({:.5} .. {:.5}), pitch {:.5} rad ({:.5} .. {:.5})",
                    f.frames,
                    f.points,
                    f.rms_before_m,
                    f.rms_after_m,
                    f.z.value,
                    f.z.low,
                    f.z.high,
                    f.roll.value,
                    f.roll.low,
                    f.roll.high,
                    f.pitch.value,
                    f.pitch.low,
                    f.pitch.high
                );
            }
            Err(why) => {
                let _ = writeln!(s, "#   z, roll, pitch: kept as configured; the floor does not fix them: {why}");
            }
        }
        let _ = writeln!(
            s,
            "[[sensor]]\nkind = \"camera\"\nname = {}\ntopic = {}\ndepth_topic = {}\ninfo_topic = {}",
            q(&self.name),
            q(&r.topic),
            q(&r.depth_topic),
            q(&r.info_topic)
        );
        let offset = e.time_offset_s.map_or(r.time_offset_s, |c| claim(c, r.time_offset_s));
        let _ = writeln!(s, "time_offset_s = {offset}");
        let yaw = e.yaw.map_or(m.yaw, |y| claim(y, m.yaw));
        let z = e.z.map_or(m.z, |v| claim(v, m.z));
        let roll = e.roll.map_or(m.roll, |v| claim(v, m.roll));
        let pitch = e.pitch.map_or(m.pitch, |v| claim(v, m.pitch));
        let _ = writeln!(s, "\n[sensor.base_from_sensor]");
        for (k, v) in [("x", m.x), ("y", m.y), ("z", z), ("roll", roll), ("pitch", pitch), ("yaw", yaw)] {
            let _ = writeln!(s, "{k} = {v}");
        }
    }
}
