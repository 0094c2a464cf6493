//! The estimator's inputs from a log's messages, and its track.
//!
//! Every pose sensor enters the one estimator (`fusemap_core::estimator`):
//! * wheel odometry as `odom_from_base` samples (a zero quaternion arrives as a NaN pose and
//!   is counted by the estimator, never a panic);
//! * the IMU's gyro, rotated from the IMU's frame into `base_link` with its mount (TF or
//!   config), as the yaw rate; its orientation only when the message provides one (REP 145:
//!   `orientation_covariance[0] = -1` means none) and the sensor table allows it;
//! * GNSS fixes converted exactly (WGS84 → ECEF → ENU) into one local map frame around the
//!   datum — configured, or the first good fix — x east, y north, never UTM zones (whose
//!   borders make robot_localization's UTM track jump); `NO_FIX` ignored; the covariance by
//!   `position_covariance_type`, floored per fix status (an RTK fixed solution earns a
//!   tighter floor than a plain fix); the antenna's lever arm from TF or config;
//! * absolute poses (`PoseWithCovarianceStamped`) with their covariance.
//!
//! Each sensor's `time_offset_s` is added to its stamps. What is not used is counted by
//! reason in the report, beside the estimator's own figures.

pub use crate::estimation_report::{EstimationReport, GnssInputReport};
use crate::extrinsics::{frame_tree, from_tf, resolve};
use crate::recording::{planar_covariance, Inventory};
use crate::sensors::{Bound, BoundSensor};
use crate::track::{glitch_note, ChosenTrack, Track, TrackCounts};
use crate::PipelineError;
use fusemap_core::config::{LogConfig, Plan, PoseSource, SensorKind};
use fusemap_core::estimator::{
    base_yaw_rate, estimate, odometry_increment_covariance, EstimatorConfig, EstimatorInput, FixQuality,
    GnssCovarianceKind,
};
use fusemap_core::frames::FrameTree;
use fusemap_core::geometry::{geodetic::Datum, quaternion_yaw, Mount3, Point2, Pose2, Pose3};
use fusemap_core::time::{plausible_samples, Stamp};
use fusemap_io::log::GnssMessage;

/// The estimator's inputs from `inv`.
pub struct Inputs {
    /// Time-ordered inputs.
    pub inputs: Vec<EstimatorInput>,
    /// The GNSS part of the report, one per GNSS sensor.
    pub gnss: Vec<GnssInputReport>,
    /// The estimator's config with the sensor tables' noise figures applied.
    pub config: EstimatorConfig,
    /// Facts a user should know.
    pub notes: Vec<String>,
    /// Odometry samples rejected as pose glitches.
    pub odometry_glitches: u64,
}

fn offset(t: Stamp, s: &BoundSensor) -> Stamp {
    Stamp(t.0.saturating_add(crate::offset_ns(s.sensor.time_offset_s)))
}

/// The sensor's mount, resolved as a lidar's is: `log.extrinsics` decides between the
/// config and the log's TF, and a config mount that disagrees with TF is reported.
fn mount(
    s: &BoundSensor,
    cfg: &LogConfig,
    tree: &FrameTree,
    frame: &str,
    stamp: Option<Stamp>,
    notes: &mut Vec<String>,
) -> Result<Mount3, PipelineError> {
    let log_mount = from_tf(tree, &cfg.base_frame, frame, stamp);
    let name = if frame.is_empty() { s.sensor.name.as_str() } else { frame };
    Ok(resolve(name, cfg, s.sensor.base_from_sensor, log_mount, notes)?.base_from_sensor)
}

/// The quality of a fix, for the report and the floor.
fn quality(f: &GnssMessage) -> FixQuality {
    match f.status {
        GnssMessage::STATUS_GBAS_FIX => FixQuality::RtkFixed,
        GnssMessage::STATUS_SBAS_FIX => FixQuality::Sbas,
        GnssMessage::STATUS_FIX => FixQuality::Fix,
        _ => FixQuality::Unknown,
    }
}

/// Builds the estimator's inputs from the bound pose sensors.
pub fn inputs(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<Inputs, PipelineError> {
    let cfg = &plan.log;
    let (tree, _) = frame_tree(cfg, &inv.tf_static, &inv.tf_dynamic);
    let mut all = Inputs {
        inputs: Vec::new(),
        gnss: Vec::new(),
        config: plan.estimator.clone(),
        notes: Vec::new(),
        odometry_glitches: 0,
    };
    let datum = shared_datum(inv, bound);
    let odometers: Vec<&str> =
        bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::WheelOdometry).map(|s| s.topic.as_str()).collect();
    if odometers.len() > 1 {
        return Err(PipelineError::Refused(format!(
            "the estimator fuses one wheel odometry, the config lists {} ({}): disable all but one",
            odometers.len(),
            odometers.join(", ")
        )));
    }
    for s in &bound.sensors {
        match s.sensor.kind {
            SensorKind::WheelOdometry => odometry_inputs(s, inv, cfg, &mut all),
            SensorKind::Imu => imu_inputs(s, inv, cfg, &tree, &mut all)?,
            SensorKind::Gnss => {
                let (inputs, mut report, n) = gnss_inputs(s, inv, &tree, cfg, datum)?;
                all.inputs.extend(inputs);
                all.notes.extend(n);
                report.topic = s.topic.clone();
                all.gnss.push(report);
            }
            SensorKind::Pose => {
                let (ps, yaw) = s.sensor.pose_noise;
                if let Some(v) = ps {
                    all.config.fallback_pose_sigma_m = v;
                }
                if let Some(v) = yaw {
                    all.config.fallback_pose_sigma_rad = v;
                }
                for m in &inv.poses[&s.topic] {
                    let cov = planar_covariance(&m.covariance).unwrap_or([[0.0; 3]; 3]);
                    let (stamp, pose) = (offset(m.stamp, s), m.pose2());
                    all.inputs.push(EstimatorInput::Pose { stamp, pose, covariance: cov });
                }
            }
            // Lidars and cameras give the map evidence, not the estimator (cameras are
            // planned apart, in `Plan::cameras`, and never bound here).
            SensorKind::Lidar | SensorKind::Camera => {}
        }
    }
    Ok(all)
}

/// The wheel odometry's poses, glitches left out, each with its increment's covariance
/// where the driver's covariance grows ([`odometry_increment_covariance`]); the sensor's
/// noise figures into the estimator's config.
fn odometry_inputs(s: &BoundSensor, inv: &Inventory, cfg: &LogConfig, all: &mut Inputs) {
    let n = &s.sensor.odometry;
    if let Some(v) = n.translation_per_sqrt_m {
        all.config.odometry_translation_noise = v;
    }
    if let Some(v) = n.rotation_per_sqrt_rad {
        all.config.odometry_rotation_noise_per_rad = v;
    }
    if let Some(v) = n.rotation_per_sqrt_m {
        all.config.odometry_rotation_noise_per_m = v;
    }
    let msgs = &inv.odom[&s.topic];
    let samples: Vec<(Stamp, Pose2)> = msgs.iter().map(|m| (offset(m.stamp, s), m.pose)).collect();
    let keep = plausible_samples(&samples, &cfg.motion_limits());
    let glitches = keep.iter().filter(|k| !**k).count() as u64;
    if glitches > 0 {
        all.notes.push(glitch_note(&format!("odometry `{}`", s.topic), glitches, cfg));
    }
    all.odometry_glitches += glitches;
    let mut prev: Option<([[f64; 3]; 3], f64)> = None;
    for (m, _) in msgs.iter().zip(&keep).filter(|(_, k)| **k) {
        let covariance = match (m.covariance, prev) {
            (Some(c), Some((p, yaw))) => odometry_increment_covariance(&c, &p, yaw),
            _ => None,
        };
        prev = m.covariance.map(|c| (c, m.pose.theta));
        all.inputs.push(EstimatorInput::Odometry { stamp: offset(m.stamp, s), pose: m.pose, covariance });
    }
}

/// The IMU's yaw rates in the base frame ([`base_yaw_rate`]) and, when the config asks
/// for them, its absolute headings; its gyro noise into the estimator's config.
fn imu_inputs(
    s: &BoundSensor,
    inv: &Inventory,
    cfg: &LogConfig,
    tree: &FrameTree,
    all: &mut Inputs,
) -> Result<(), PipelineError> {
    if let Some(v) = s.sensor.gyro_noise_rad_s {
        all.config.gyro_rate_sigma = v;
    }
    let msgs = &inv.imu[&s.topic];
    let frame = s.sensor.frame.clone().or_else(|| inv.frames.get(&s.topic).cloned()).unwrap_or_default();
    let m3 = mount(s, cfg, tree, &frame, msgs.first().map(|m| m.stamp), &mut all.notes)?;
    let r = m3.rotation();
    let q_mount = m3.quaternion();
    for m in msgs {
        let stamp = offset(m.stamp, s);
        // `angular_velocity_covariance[0] = -1`: no rate in this message.
        if m.rate_covariance[0] != -1.0 {
            let (yaw_rate, variance) = base_yaw_rate(&r, m.angular_velocity, &m.rate_covariance);
            all.inputs.push(EstimatorInput::Gyro { stamp, yaw_rate, variance });
        }
        if let Some((orientation, var)) = m.orientation.filter(|_| s.sensor.use_orientation) {
            // world_from_base = world_from_imu · (base_from_imu)⁻¹.
            let world_from_imu = Pose3::new([0.0; 3], orientation);
            let q = world_from_imu.compose(&Pose3::new([0.0; 3], q_mount).inverse()).rotation;
            let yaw = quaternion_yaw(q);
            if yaw.is_finite() && var.is_finite() && var > 0.0 {
                all.inputs.push(EstimatorInput::Heading { stamp, yaw, variance: var });
            }
        }
    }
    Ok(())
}

/// The GNSS fixes as the estimator is given them: antenna positions in its map frame
/// (the shared local ENU frame), covariances floored per fix quality, lever arms.
pub fn gnss_positions(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<Vec<EstimatorInput>, PipelineError> {
    let (tree, _) = frame_tree(&plan.log, &inv.tf_static, &inv.tf_dynamic);
    let datum = shared_datum(inv, bound);
    let mut out = Vec::new();
    for s in bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::Gnss) {
        out.extend(gnss_inputs(s, inv, &tree, &plan.log, datum)?.0);
    }
    Ok(out)
}

/// One map frame for every GNSS sensor: the first configured datum, else the earliest good
/// fix of any GNSS topic (two receivers must not get two ENU frames metres apart).
fn shared_datum(inv: &Inventory, bound: &Bound) -> Option<((f64, f64, f64), &'static str)> {
    let gnss = bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::Gnss);
    if let Some([lat, lon, alt]) = gnss.clone().find_map(|s| s.sensor.datum) {
        return Some(((lat, lon, alt), "config"));
    }
    gnss.flat_map(|s| inv.gnss[&s.topic].iter())
        .filter(|f| usable_fix(f) && f.altitude.is_finite())
        .min_by_key(|f| f.stamp)
        .map(|f| ((f.latitude, f.longitude, f.altitude), "first good fix"))
}

/// A fix with a position: not `NO_FIX`, latitude and longitude finite (the doctor's rule
/// too).
pub fn usable_fix(f: &GnssMessage) -> bool {
    f.status != GnssMessage::STATUS_NO_FIX && f.latitude.is_finite() && f.longitude.is_finite()
}

fn gnss_inputs(
    s: &BoundSensor,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    datum: Option<((f64, f64, f64), &'static str)>,
) -> Result<(Vec<EstimatorInput>, GnssInputReport, Vec<String>), PipelineError> {
    let msgs = &inv.gnss[&s.topic];
    let mut r = GnssInputReport { read: msgs.len() as u64, ..Default::default() };
    let mut notes = Vec::new();
    let good = |f: &&GnssMessage| usable_fix(f) && f.altitude.is_finite();
    if let Some((_, src)) = datum {
        r.datum_source = src.to_string();
    }
    let datum = datum.map(|d| d.0);
    let Some((lat0, lon0, alt0)) = datum else {
        notes.push(format!(
            "GNSS `{}`: {} messages but no usable fix and no datum configured: the fixes are not used",
            s.topic,
            msgs.len()
        ));
        r.no_fix = msgs.iter().filter(|f| f.status == GnssMessage::STATUS_NO_FIX).count() as u64;
        return Ok((Vec::new(), r, notes));
    };
    let datum =
        Datum::new(lat0, lon0, alt0).map_err(|e| PipelineError::Refused(format!("GNSS `{}`: datum: {e}", s.topic)))?;
    r.datum = Some([lat0, lon0, alt0]);
    let frame = s.sensor.frame.clone().or_else(|| msgs.first().map(|m| m.frame_id.clone())).unwrap_or_default();
    let lever = mount(s, cfg, tree, &frame, msgs.first().map(|m| m.stamp), &mut notes)?;
    r.lever_arm = Some([lever.x, lever.y]);
    let floors = s.sensor.gnss;
    let mut out = Vec::new();
    for f in msgs {
        if f.status == GnssMessage::STATUS_NO_FIX {
            r.no_fix += 1;
            continue;
        }
        if !good(&f) {
            r.not_finite += 1;
            continue;
        }
        let enu = datum.to_enu(f.latitude, f.longitude, f.altitude);
        let q = quality(f);
        // NavSatFix's covariance is ENU (east, north, up), m².
        let kind = match f.position_covariance_type {
            GnssMessage::COVARIANCE_TYPE_UNKNOWN => GnssCovarianceKind::Unknown,
            GnssMessage::COVARIANCE_TYPE_KNOWN => GnssCovarianceKind::Known,
            _ => GnssCovarianceKind::Diagonal,
        };
        let cov = floors.covariance(&f.position_covariance, kind, q);
        r.unknown_covariance += u64::from(cov.unknown);
        r.floored += u64::from(cov.floored);
        r.passed += 1;
        out.push(EstimatorInput::Position {
            stamp: offset(f.stamp, s),
            enu: [enu[0], enu[1]],
            covariance: cov.enu,
            antenna: Point2::new(lever.x, lever.y),
            quality: q,
        });
    }
    Ok((out, r, notes))
}

/// Runs the estimator and its smoother over the log's pose sensors.
pub fn estimator_track(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<ChosenTrack, PipelineError> {
    let Inputs { inputs, gnss, config, notes, odometry_glitches } = inputs(plan, inv, bound)?;
    let e = estimate(&inputs, &config).map_err(|e| PipelineError::Refused(format!("pose estimator: {e}")))?;
    let odom = bound.first(SensorKind::WheelOdometry);
    let names: Vec<String> =
        bound.sensors.iter().map(|s| format!("{} `{}`", s.sensor.kind.as_str().replace('_', " "), s.topic)).collect();
    let report = EstimationReport { estimator: e.report.clone(), gnss_input: gnss, inputs: inputs.len() };
    let stamps: Vec<Stamp> = odom.map(|o| inv.odom[&o.topic].iter().map(|m| m.stamp).collect()).unwrap_or_default();
    let receive = odom.map(|o| inv.odom[&o.topic].iter().map(|m| m.receive_stamp).collect()).unwrap_or_default();
    // The track's own counters are the odometry's: the samples the track is built on.
    let counts = TrackCounts {
        samples: e.report.odometry.received as u64,
        used: e.report.odometry.used as u64,
        duplicates: e.report.odometry.duplicate_stamps as u64,
        not_finite: e.report.odometry.not_finite as u64,
        glitches: odometry_glitches,
        ..Default::default()
    };
    Ok(ChosenTrack {
        source: PoseSource::Estimator,
        track: Track::Timed(Box::new(e)),
        name: format!("estimator ({})", names.join(", ")),
        counts,
        stamps,
        receive,
        estimator: Some(Box::new(report)),
        notes,
        slam: None,
    })
}

/// The planar pose of a ROS pose, for callers that need one without the estimator.
pub fn planar(position: [f64; 3], orientation: [f64; 4]) -> Pose2 {
    fusemap_io::log::planar_pose(position, orientation)
}
