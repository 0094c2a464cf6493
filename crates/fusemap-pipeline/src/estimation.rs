//! The estimator's inputs from a log's messages, and its track.
//!
//! Every pose sensor enters the one estimator (`fusemap_core::estimator`):
//! * wheel odometry as `odom_from_base` samples (a zero quaternion arrives as a NaN pose and
//!   is counted by the estimator, never a panic);
//! * the IMU's gyro, rotated from the IMU's frame into `base_link` with its mount (TF or
//!   config), as the yaw rate; its orientation only when the message provides one (REP 145:
//!   `orientation_covariance[0] = -1` means none) and the sensor table allows it;
//! * GNSS fixes ([`gnss_fixes`]) converted exactly (WGS84 → ECEF → ENU)
//!   into one local map frame around the datum — configured, or the first good fix the
//!   next ones agree with — x east, y north, never UTM zones (whose borders make
//!   robot_localization's UTM track jump); `NO_FIX` and receiver faults (a latitude of 91°,
//!   a status NavSatFix does not define) dropped and counted; the covariance by
//!   `position_covariance_type`, floored per fix status (an RTK fixed solution earns a
//!   tighter floor than a plain fix); the antenna's lever arm from TF or config;
//! * absolute poses (`PoseWithCovarianceStamped`) with their covariance.
//!
//! Each sensor's `time_offset_s` is added to its stamps. What is not used is counted by
//! reason in the report, beside the estimator's own figures.

pub use crate::estimation_report::{EstimationReport, GnssInputReport};
use crate::extrinsics::{frame_tree, sensor_mount};
use crate::gnss_fixes;
use crate::recording::{planar_covariance, Inventory};
use crate::sensors::{Bound, BoundSensor};
use crate::track::{glitch_note, ChosenTrack, Track, TrackCounts};
use crate::{PipelineError, Stage};
use fusemap_core::config::{LogConfig, Plan, PoseSource, SensorKind};
use fusemap_core::estimator::{
    base_yaw_rate, estimate, odometry_increment_covariance, Estimate, EstimatorConfig, EstimatorError, EstimatorInput,
    Repeated, StaleOrientation,
};
use fusemap_core::frames::FrameTree;
use fusemap_core::geometry::{quaternion_yaw, Pose2, Pose3};
use fusemap_core::time::{plausible_samples, Stamp};

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
    let datum = gnss_fixes::shared_datum(inv, bound);
    let odometers: Vec<&str> =
        bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::WheelOdometry).map(|s| s.topic.as_str()).collect();
    if odometers.len() > 1 {
        return Err(PipelineError::refused(
            Stage::Sensors,
            format!(
                "the estimator fuses one wheel odometry, the config lists {} ({}): disable all but one",
                odometers.len(),
                odometers.join(", ")
            ),
        ));
    }
    for s in &bound.sensors {
        match s.sensor.kind {
            SensorKind::WheelOdometry => odometry_inputs(s, inv, cfg, &mut all),
            SensorKind::Imu => imu_inputs(s, inv, cfg, &tree, &mut all)?,
            SensorKind::Gnss => {
                let (inputs, mut report, n) = gnss_fixes::gnss_inputs(s, inv, &tree, cfg, datum)?;
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
                let mut repeated = Repeated::new();
                for m in &inv.poses[&s.topic] {
                    let covariance = repeated.share(planar_covariance(&m.covariance).unwrap_or([[0.0; 3]; 3]));
                    let (stamp, pose) = (s.stamp(m.stamp), m.pose2());
                    all.inputs.push(EstimatorInput::Pose { stamp, pose, covariance });
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
    let samples: Vec<(Stamp, Pose2)> = msgs.iter().map(|m| (s.stamp(m.stamp), m.pose)).collect();
    let keep = plausible_samples(&samples, &cfg.motion_limits());
    let glitches = keep.iter().filter(|k| !**k).count() as u64;
    if glitches > 0 {
        all.notes.push(glitch_note(&format!("odometry `{}`", s.topic), glitches, cfg));
    }
    all.odometry_glitches += glitches;
    let mut prev: Option<(&[[f64; 3]; 3], f64)> = None;
    let mut repeated = Repeated::new();
    for (m, _) in msgs.iter().zip(&keep).filter(|(_, k)| **k) {
        let covariance = match (m.covariance.as_deref(), prev) {
            (Some(c), Some((p, yaw))) => odometry_increment_covariance(c, p, yaw).map(|i| repeated.share(i)),
            _ => None,
        };
        prev = m.covariance.as_deref().map(|c| (c, m.pose.theta));
        all.inputs.push(EstimatorInput::Odometry { stamp: s.stamp(m.stamp), pose: m.pose, covariance });
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
    let m3 = sensor_mount(s, cfg, tree, &frame, msgs.first().map(|m| m.stamp), &mut all.notes)?;
    let r = m3.rotation();
    let q_mount = m3.quaternion();
    let (mut stale, mut stale_count, mut floored) = (StaleOrientation::default(), 0u64, 0u64);
    for m in msgs {
        let stamp = s.stamp(m.stamp);
        // `angular_velocity_covariance[0] = -1`: no rate in this message.
        let mut rate = f64::NAN;
        if m.rate_covariance[0] != -1.0 {
            let (yaw_rate, variance) = base_yaw_rate(&r, m.angular_velocity, &m.rate_covariance);
            all.inputs.push(EstimatorInput::Gyro { stamp, yaw_rate, variance });
            rate = yaw_rate;
        }
        if let Some((orientation, var)) = m.orientation.filter(|_| s.sensor.use_orientation) {
            if stale.is_stale(stamp, orientation, rate) {
                stale_count += 1;
                continue;
            }
            // world_from_base = world_from_imu · (base_from_imu)⁻¹.
            let world_from_imu = Pose3::new([0.0; 3], orientation);
            let q = world_from_imu.compose(&Pose3::new([0.0; 3], q_mount).inverse()).rotation;
            let yaw = quaternion_yaw(q);
            // A variance that is not positive (all zeros: "unknown", REP 145) goes to the
            // estimator as it is, which gives it `fallback_heading_sigma_rad` and counts it;
            // a positive one below the floor is raised to it.
            let floor = all.config.imu_heading_floor_sigma_rad.powi(2);
            let raised = var > 0.0 && var < floor;
            floored += u64::from(raised);
            let variance = if raised { floor } else { var };
            if yaw.is_finite() {
                all.inputs.push(EstimatorInput::Heading { stamp, yaw, variance });
            }
        }
    }
    if floored > 0 {
        all.notes.push(format!(
            "IMU `{}`: {floored} orientation readings claimed a heading σ below estimator.imu_heading_floor_sigma_rad \
             = {:.2}° and were given that σ",
            s.topic,
            all.config.imu_heading_floor_sigma_rad.to_degrees()
        ));
    }
    if stale_count > 0 {
        all.notes.push(format!(
            "IMU `{}`: {stale_count} orientation readings left out as stale: the orientation repeated, bit for bit, while the gyro turned more than {:.0}° (a frozen attitude filter)",
            s.topic,
            fusemap_core::estimator::STALE_TURN_RAD.to_degrees()
        ));
    }
    Ok(())
}

/// Runs the estimator, and returns its estimate with the number of inputs it used. When
/// fixes exist but never make the heading observable (all too imprecise, or the robot
/// never drove far enough between them), the fixes are dropped with a note and the track
/// is estimated from the other sensors: one unusable stream does not sink the run.
fn estimate_without_unusable_fixes(
    inputs: Vec<EstimatorInput>,
    config: &EstimatorConfig,
    notes: &mut Vec<String>,
) -> Result<(Estimate, usize), PipelineError> {
    let refused = |e: EstimatorError| PipelineError::refused(Stage::Poses, format!("pose estimator: {e}"));
    match estimate(&inputs, config) {
        Err(EstimatorError::HeadingNotObservable { travelled_m, needed_m }) => {
            let is_fix = |i: &EstimatorInput| matches!(i, EstimatorInput::Position { .. });
            let fixes = inputs.iter().filter(|i| is_fix(i)).count();
            let rest: Vec<EstimatorInput> = inputs.into_iter().filter(|i| !is_fix(i)).collect();
            notes.push(format!(
                "GNSS: {fixes} fixes, but they never made the heading observable (the fixes precise \
                 enough to use, heading_init_max_fix_sigma_m = {:.2} m, span {travelled_m:.2} m; \
                 heading_init_distance_m = {needed_m:.2} m): the track is estimated without them",
                config.heading_init_max_fix_sigma_m
            ));
            let e = estimate(&rest, config).map_err(refused)?;
            Ok((e, rest.len()))
        }
        r => {
            let n = inputs.len();
            r.map(|e| (e, n)).map_err(refused)
        }
    }
}

/// Runs the estimator and its smoother over the log's pose sensors.
pub fn estimator_track(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<ChosenTrack, PipelineError> {
    let Inputs { inputs, gnss, config, mut notes, odometry_glitches } = inputs(plan, inv, bound)?;
    let (mut e, inputs) = estimate_without_unusable_fixes(inputs, &config, &mut notes)?;
    // The map pass reads the smoothed track; the filter's own samples (a sample a step,
    // 22 MB an hour of 40 Hz odometry) would only be held through it.
    e.filtered = Vec::new();
    if e.report.gate_resets_refused > 0 {
        notes.push(format!(
            "GNSS: {} fixes rejected by the filter's gate; {} times a run of them (and the fixes after it) agreed with each other but lay farther from the track than the odometry could have drifted since the last fix taken (estimator.gate_reset_max_drift = {} of the distance driven): a jump of the receiver, not followed",
            e.report.fixes.rejected_gate, e.report.gate_resets_refused, config.gate_reset_max_drift
        ));
    }
    let odom = bound.first(SensorKind::WheelOdometry);
    let names: Vec<String> =
        bound.sensors.iter().map(|s| format!("{} `{}`", s.sensor.kind.as_str().replace('_', " "), s.topic)).collect();
    let report = EstimationReport { estimator: e.report.clone(), gnss_input: gnss, inputs };
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
    if let Some(o) = odom {
        notes.extend(crate::track::unusable_note(&format!("odometry `{}`", o.topic), &counts));
    }
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
        odom_frame: None,
    })
}

/// The planar pose of a ROS pose, for callers that need one without the estimator.
pub fn planar(position: [f64; 3], orientation: [f64; 4]) -> Pose2 {
    fusemap_io::log::planar_pose(position, orientation)
}
