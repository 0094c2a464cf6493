//! The design document's opening picture as a simulator: a robot drives along a
//! production line; the lidar produces flying points on a glass fence and stainless-steel
//! pillars, the wheel odometry slips over floor grooves, and RTK GNSS has good, degraded
//! and dropout zones; a semantic RGB-D camera sees the hall in 2.5D, with backlight from
//! the windows, and a person walks across the robot's loop.
//!
//! A [`Scenario`] (readable from TOML) describes the hall, the robot's loop and every
//! sensor; [`simulate`] turns it into a [`SimRecording`]: one time-ordered list of
//! messages mirroring the ROS types (`sensor_msgs/LaserScan`, `nav_msgs/Odometry`,
//! `sensor_msgs/Imu`, `sensor_msgs/NavSatFix`, `sensor_msgs/Image`,
//! `sensor_msgs/CameraInfo`, `/tf_static`) plus the ground truth an estimator and a map
//! are scored against (the true trajectory, the injected outliers, the dropout intervals,
//! the gyro bias and odometry scale, truth occupancy and semantic rasters, the person's
//! track, the camera's true stamps and backlit floor).
//!
//! Frames (REP 105): `map` is ENU at the GNSS datum, x east, y north, and the world's
//! coordinates are given in it; the robot starts at rest on its loop (where the first
//! corner's arc ends, facing the second waypoint); `odom` starts at identity at that pose.
//! Every sensor stamps with its own clock: `true time + time_offset_s`.
//! The same scenario (same `world.seed`) always gives the same recording.
//!
//! A scenario file overrides only what it names; a list it names (`[[world.objects]]`,
//! `[[gnss.zones]]`, `world.grooves`, `robot.waypoints`, `person.windows`) replaces the default
//! list whole:
//!
//! ```toml
//! [world]
//! seed = 7
//! [robot]
//! duration_s = 240.0
//! [lidar]
//! glass_pass_probability = 0.8
//! time_offset_s = 0.03          # the scan stamps lag the truth by 30 ms
//! [gnss]
//! dropout_mode = "no_fix"       # publish NO_FIX instead of nothing
//! [[gnss.zones]]
//! name = "loading_bay"
//! kind = "degraded"             # or "dropout"
//! area = { min = [20.0, 0.0], max = [30.0, 9.0] }
//! [camera]
//! time_offset_s = 0.04          # image stamps 40 ms late
//! depth_encoding = "16UC1"      # millimetres instead of 32FC1 metres
//! [camera.backlight]
//! floor_share = 0.4
//! [person]
//! windows = [[0.0, 30.0]]       # seconds since the start
//! ```
//!
//! ```
//! use fusemap_sim::{simulate, Scenario};
//! let mut scenario = Scenario::default();
//! scenario.robot.duration_s = 5.0;
//! let run = simulate(&scenario).unwrap();
//! assert!(run.messages.windows(2).all(|w| w[0].stamp() <= w[1].stamp()));
//! ```

pub mod bag;
mod camera;
mod checks;
mod gnss;
mod imu;
mod lidar;
mod messages;
mod odometry;
mod path;
mod person;
mod recording;
mod scenario;
mod semantic_truth;
mod sensors;
mod world;

#[cfg(test)]
mod tests;

pub use camera::{
    class_id, optical_rotation, BacklightConfig, CameraConfig, CameraTruth, DepthEncoding, LabelEncoding,
    CLASS_CEILING, CLASS_COLORS, CLASS_FLOOR, CLASS_GLASS, CLASS_MACHINE, CLASS_NAMES, CLASS_PERSON, CLASS_PILLAR,
    CLASS_UNLABELED, CLASS_WALL, MAX_BACKLIT_POINTS, MAX_CAMERA_BYTES,
};
pub use imu::STANDARD_GRAVITY;
pub use lidar::LidarStats;
pub use messages::{
    rpy_to_quaternion, OnTopic, SimCameraInfo, SimFix, SimImage, SimImu, SimMessage, SimOdometry, SimScan,
    SimStaticTransform,
};
pub use path::{rounded_loop, Approach, Trajectory, TruthSample, TRUTH_RATE_HZ};
pub use person::{ray_circle, PersonConfig};
pub use recording::{
    segment_meets_box, SimRecording, TruthRaster, TruthRasterError, MAX_TRUTH_CELLS, TRUTH_BYTES_PER_CELL,
};
pub use scenario::{FramesConfig, RobotConfig, Scenario, WorldConfig};
pub use semantic_truth::TruthSemantic;
pub use sensors::{DropoutMode, GnssConfig, GnssZone, ImuConfig, LidarConfig, OdometryConfig, ZoneKind};
pub use world::{production_hall_objects, Caster, EdgeHit, Hit, Material, Rect, Shape, WorldObject};

use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;

/// Why a scenario cannot be simulated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// [`Scenario::validate`] refused it, naming the field.
    #[error("invalid scenario: {0}")]
    Invalid(#[from] fusemap_core::field_error::FieldError),
}

/// Rate of [`SimRecording::truth_trajectory`], Hz.
pub const TRUTH_OUTPUT_RATE_HZ: f64 = 50.0;

/// The `/tf_static` mounts of the lidar, the IMU and the GNSS antenna on the base.
/// The scenario's `/tf_static` transforms, stamped at its start: the lidar's, the IMU's and
/// the GNSS antenna's mounts, and the camera's when it is on.
pub fn static_transforms(scenario: &Scenario) -> Vec<SimMessage> {
    let start = Stamp(scenario.world.start_time_s.saturating_mul(1_000_000_000));
    let f = &scenario.frames;
    let mut out: Vec<SimMessage> =
        [(&f.laser, &scenario.lidar.mount), (&f.imu_link, &scenario.imu.mount), (&f.gps, &scenario.gnss.mount)]
            .into_iter()
            .map(|(child, mount)| {
                SimMessage::StaticTransform(SimStaticTransform::from_mount(
                    start,
                    "/tf_static",
                    &f.base_link,
                    child,
                    mount,
                ))
            })
            .collect();
    if scenario.camera.enabled {
        let mount = camera::mount_message(&scenario.camera, start, &f.base_link, &f.camera_optical);
        out.push(SimMessage::StaticTransform(mount));
    }
    out
}

/// The true trajectory at [`TRUTH_OUTPUT_RATE_HZ`].
fn truth_trajectory(traj: &Trajectory, start: Stamp) -> Vec<(Stamp, Pose2)> {
    let mut out = Vec::new();
    let mut k = 0usize;
    while k as f64 / TRUTH_OUTPUT_RATE_HZ <= traj.duration() {
        let t = k as f64 / TRUTH_OUTPUT_RATE_HZ;
        out.push((Stamp(start.0 + (t * 1e9).round() as i64), traj.pose_at(t)));
        k += 1;
    }
    out
}

/// The person's true track at [`TRUTH_OUTPUT_RATE_HZ`], while they walk.
fn person_track(scenario: &Scenario, traj: &Trajectory, start: Stamp) -> Vec<(Stamp, Point2)> {
    (0..=(traj.duration() * TRUTH_OUTPUT_RATE_HZ).floor() as usize)
        .filter_map(|k| {
            let t = k as f64 / TRUTH_OUTPUT_RATE_HZ;
            let p = scenario.person.position_at(t)?;
            Some((Stamp(start.0 + (t * 1e9).round() as i64), p))
        })
        .collect()
}

/// Runs the scenario: the recording, its messages in time order.
pub fn simulate(scenario: &Scenario) -> Result<SimRecording, SimError> {
    let mut messages = Vec::new();
    let mut rec = simulate_with(scenario, &mut |m| messages.push(m))?;
    rec.messages = messages;
    Ok(rec)
}

/// Runs the scenario, handing every message to `sink` in time order as it is made instead
/// of holding them: the camera's images, most of a recording's bytes, are rendered a
/// chunk at a time while `sink` takes the last chunk. The messages, and their order, are
/// those of [`simulate`]; the recording returned has none.
pub fn simulate_with(scenario: &Scenario, sink: &mut dyn FnMut(SimMessage)) -> Result<SimRecording, SimError> {
    scenario.validate().map_err(SimError::Invalid)?;
    let datum = scenario.gnss.datum().map_err(SimError::Invalid)?;
    let start = Stamp(scenario.world.start_time_s.saturating_mul(1_000_000_000));
    let traj = Trajectory::generate(&scenario.robot);
    let caster = Caster::new(&scenario.world.objects);
    // One independent stream per sensor: changing one sensor's settings leaves the
    // others' noise unchanged.
    let mut seeds = SplitMix64::new(scenario.world.seed);
    let mut rng_lidar = SplitMix64::new(seeds.next_u64());
    let mut rng_odom = SplitMix64::new(seeds.next_u64());
    let mut rng_imu = SplitMix64::new(seeds.next_u64());
    let mut rng_gnss = SplitMix64::new(seeds.next_u64());
    let camera_seed = seeds.next_u64();
    let f = &scenario.frames;

    let mut messages = static_transforms(scenario);
    let camera_run = camera::CameraRun {
        cfg: &scenario.camera,
        frame_id: &f.camera_optical,
        objects: &scenario.world.objects,
        caster: &caster,
        person: &scenario.person,
        traj: &traj,
        start,
    };
    let (scans, lidar_stats) =
        lidar::simulate_scans(&scenario.lidar, &f.laser, &caster, &scenario.person, &traj, start, &mut rng_lidar);
    messages.extend(scans.into_iter().map(SimMessage::Scan));
    let (odom, slipping_steps) = odometry::simulate_odometry(
        &scenario.odometry,
        (&f.odom, &f.base_link),
        &scenario.world.grooves,
        &traj,
        start,
        &mut rng_odom,
    );
    messages.extend(odom.into_iter().map(|m| SimMessage::Odometry(Box::new(m))));
    let imu = imu::simulate_imu(&scenario.imu, &f.imu_link, &traj, start, &mut rng_imu);
    messages.extend(imu.into_iter().map(|m| SimMessage::Imu(Box::new(m))));
    let gnss = gnss::simulate_gnss(&scenario.gnss, &datum, &f.gps, &traj, start, &mut rng_gnss);
    messages.extend(gnss.fixes.into_iter().map(SimMessage::Fix));
    // Time order, ties in the order made (a stable sort); the camera's frames, made last
    // and in time order, are merged in after the messages of their stamp.
    messages.sort_by_key(|m| m.stamp());
    let mut others = messages.into_iter().peekable();
    let camera_truth = if scenario.camera.enabled {
        camera_run.stream(camera_seed, &mut |m| {
            while let Some(earlier) = others.next_if(|o| o.stamp() <= m.stamp()) {
                sink(earlier);
            }
            sink(m);
        })
    } else {
        CameraTruth::default()
    };
    others.for_each(&mut *sink);
    Ok(SimRecording {
        messages: Vec::new(),
        truth_trajectory: truth_trajectory(&traj, start),
        injected_outliers: gnss.outliers,
        dropouts: gnss.dropouts,
        gyro_bias_radps: scenario.imu.gyro_bias_radps,
        odometry_scale: scenario.odometry.scale_error,
        slipping_steps,
        lidar_stats,
        datum,
        objects: scenario.world.objects.clone(),
        extent: scenario.world.extent,
        person_track: person_track(scenario, &traj, start),
        person_radius_m: scenario.person.radius_m,
        camera_truth,
    })
}
