//! The scenario: every parameter of a production-line run, readable from TOML.
//!
//! Each table has `#[serde(deny_unknown_fields, default)]`: a misspelt key is an error,
//! a missing key takes the production line's value. [`Scenario::validate`] names the
//! offending field in the TOML path form (`lidar.glass_pass_probability`).

use crate::camera::{class_id, CameraConfig};
use crate::checks::{non_negative, positive};
use crate::person::PersonConfig;
use crate::sensors::{GnssConfig, ImuConfig, LidarConfig, OdometryConfig};
use crate::world::{production_hall_objects, Rect, WorldObject};
use fusemap_core::field_error::FieldError;
use serde::{Deserialize, Serialize};

/// A whole simulated run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// The hall and the random seed.
    pub world: WorldConfig,
    /// The robot's motion.
    pub robot: RobotConfig,
    /// The 2D lidar.
    pub lidar: LidarConfig,
    /// Wheel odometry.
    pub odometry: OdometryConfig,
    /// The IMU.
    pub imu: ImuConfig,
    /// The RTK GNSS receiver.
    pub gnss: GnssConfig,
    /// The semantic RGB-D camera.
    pub camera: CameraConfig,
    /// The walking person.
    pub person: PersonConfig,
    /// Frame names (REP 105).
    pub frames: FramesConfig,
}

/// The world. Coordinates are the map frame: ENU at the GNSS datum, x east, y north.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WorldConfig {
    /// The area the world occupies (truth rasters cover it).
    pub extent: Rect,
    /// Seed of every random draw: the same scenario and seed give the same recording.
    pub seed: u64,
    /// Clock reading at the start of the run, whole seconds (Unix time by default, so
    /// recordings look like real logs; integer so stamps stay exact to the nanosecond).
    pub start_time_s: i64,
    /// The objects.
    pub objects: Vec<WorldObject>,
    /// Floor grooves: the wheels slip while over them.
    pub grooves: Vec<Rect>,
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            extent: Rect::new(-0.5, -0.5, 30.5, 15.5),
            seed: 20_261_201,
            // 2026-01-01T00:00:00Z.
            start_time_s: 1_767_225_600,
            objects: production_hall_objects(),
            grooves: vec![Rect::new(9.6, 0.2, 10.2, 5.0), Rect::new(19.6, 10.7, 20.2, 14.8)],
        }
    }
}

/// The robot's motion: a closed loop of waypoints with rounded corners, followed by a
/// unicycle controller under speed, acceleration and turn-rate limits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotConfig {
    /// Top speed, m/s.
    pub max_speed_mps: f64,
    /// Top turn rate, rad/s.
    pub max_turn_rate_radps: f64,
    /// Top linear acceleration, m/s².
    pub max_accel_mps2: f64,
    /// Top angular acceleration, rad/s².
    pub max_angular_accel_radps2: f64,
    /// Length of the run, seconds.
    pub duration_s: f64,
    /// Corners of the closed loop, metres in the map frame. The robot starts at the first,
    /// facing the second, at rest.
    pub waypoints: Vec<[f64; 2]>,
    /// Radius of the arcs that round the corners, metres.
    pub corner_radius_m: f64,
    /// Pure-pursuit look-ahead distance, metres.
    pub lookahead_m: f64,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            max_speed_mps: 0.8,
            max_turn_rate_radps: 0.6,
            max_accel_mps2: 0.5,
            max_angular_accel_radps2: 1.5,
            duration_s: 180.0,
            waypoints: vec![[3.0, 3.0], [27.0, 3.0], [27.0, 12.5], [3.0, 12.5]],
            corner_radius_m: 2.0,
            lookahead_m: 1.0,
        }
    }
}

/// Frame names, as REP 105 spells them by default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FramesConfig {
    /// The global, GNSS-anchored ENU frame.
    pub map: String,
    /// The odometry frame (continuous, drifting).
    pub odom: String,
    /// The robot body.
    pub base_link: String,
    /// The lidar.
    pub laser: String,
    /// The IMU.
    pub imu_link: String,
    /// The GNSS antenna.
    pub gps: String,
    /// The camera's optical frame (REP 103 optical axes: z forward, x right, y down).
    pub camera_optical: String,
}

impl Default for FramesConfig {
    fn default() -> Self {
        Self {
            map: "map".into(),
            odom: "odom".into(),
            base_link: "base_link".into(),
            laser: "laser".into(),
            imu_link: "imu_link".into(),
            gps: "gps".into(),
            camera_optical: "camera_optical".into(),
        }
    }
}

/// Most lidar beams a run may simulate (8 bytes each in memory).
pub const MAX_BEAMS: f64 = 5e7;

/// The longest loop of waypoints a scenario may have, metres: 100 km, more than an hour
/// (the longest run) at 20 m/s.
pub const MAX_LOOP_M: f64 = 1e5;

/// The longest look-ahead of the robot's path follower, metres.
pub const MAX_LOOKAHEAD_M: f64 = 20.0;

impl Scenario {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), FieldError> {
        self.world.validate()?;
        self.robot.validate()?;
        self.lidar.validate()?;
        let beams = self.lidar.beams as f64 * self.lidar.rate_hz * self.robot.duration_s;
        if beams > MAX_BEAMS {
            return Err(FieldError::new(
                "lidar.beams",
                format!(
                "makes {beams:.3e} beams with lidar.rate_hz × robot.duration_s, more than the {MAX_BEAMS:.0e} a run \
                 may hold in memory"
            ),
            ));
        }
        self.odometry.validate()?;
        self.imu.validate()?;
        self.gnss.validate()?;
        self.camera.validate(self.robot.duration_s)?;
        self.person.validate()?;
        self.frames.validate()
    }
}

impl WorldConfig {
    /// Checks `world.*`.
    fn validate(&self) -> Result<(), FieldError> {
        let w = self;
        w.extent.check("world.extent")?;
        // The bag's log times are unsigned nanoseconds since 1970 (MCAP), and stamps must
        // fit an i64 of nanoseconds.
        if !(0..=9_000_000_000).contains(&w.start_time_s) {
            return Err(FieldError::new(
                "world.start_time_s",
                format!("must lie within 0 (1970) and 9e9 s (year 2255), got {}", w.start_time_s),
            ));
        }
        for (i, o) in w.objects.iter().enumerate() {
            o.check(&format!("world.objects[{i}]"))?;
            if class_id(&o.class).is_none_or(|c| c == 0 || c > 5) {
                return Err(FieldError::new(
                    format!("world.objects[{i}].class"),
                    format!("`{}` is not an object class of the table (wall, glass, pillar, machine)", o.class),
                ));
            }
        }
        for (i, g) in w.grooves.iter().enumerate() {
            g.check(&format!("world.grooves[{i}]"))?;
        }
        Ok(())
    }
}

impl RobotConfig {
    /// Checks `robot.*`.
    fn validate(&self) -> Result<(), FieldError> {
        let r = self;
        positive("robot.max_speed_mps", r.max_speed_mps)?;
        positive("robot.max_turn_rate_radps", r.max_turn_rate_radps)?;
        positive("robot.max_accel_mps2", r.max_accel_mps2)?;
        positive("robot.max_angular_accel_radps2", r.max_angular_accel_radps2)?;
        positive("robot.duration_s", r.duration_s)?;
        if r.duration_s > 3_600.0 {
            return Err(FieldError::new(
                "robot.duration_s",
                format!("must be at most 3600 (one hour in memory), got {}", r.duration_s),
            ));
        }
        non_negative("robot.corner_radius_m", r.corner_radius_m)?;
        positive("robot.lookahead_m", r.lookahead_m)?;
        // A pure-pursuit look-ahead is a few metres: past 20 m the robot cuts every corner
        // of a hall, and the controller's search for its place on the path, which spans
        // twice the look-ahead at every step, grows with it (10^300 m never ended).
        if r.lookahead_m > MAX_LOOKAHEAD_M {
            return Err(FieldError::new(
                "robot.lookahead_m",
                format!("must be at most {MAX_LOOKAHEAD_M} m, got {}", r.lookahead_m),
            ));
        }
        if r.waypoints.len() < 3 || r.waypoints.iter().flatten().any(|v| !v.is_finite()) {
            return Err(FieldError::new("robot.waypoints", "needs at least 3 finite points (a closed loop)"));
        }
        let mut length = 0.0;
        for i in 0..r.waypoints.len() {
            let (a, b) = (r.waypoints[i], r.waypoints[(i + 1) % r.waypoints.len()]);
            if (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-6 {
                return Err(FieldError::new(format!("robot.waypoints[{i}]"), "repeats the next waypoint"));
            }
            length += (a[0] - b[0]).hypot(a[1] - b[1]);
        }
        // The loop is sampled every 5 cm before the robot drives it: bounded, so that
        // waypoints 10⁷ m apart are an error, not 6 GB of path.
        if length > MAX_LOOP_M {
            return Err(FieldError::new(
                "robot.waypoints",
                format!("make a loop {length:.3e} m long, more than the {MAX_LOOP_M:.0e} m a simulated run may drive"),
            ));
        }
        Ok(())
    }
}

impl FramesConfig {
    /// Checks `frames.*`: every frame named.
    fn validate(&self) -> Result<(), FieldError> {
        let f = self;
        for (field, name) in [
            ("frames.map", &f.map),
            ("frames.odom", &f.odom),
            ("frames.base_link", &f.base_link),
            ("frames.laser", &f.laser),
            ("frames.imu_link", &f.imu_link),
            ("frames.gps", &f.gps),
            ("frames.camera_optical", &f.camera_optical),
        ] {
            if name.is_empty() {
                return Err(FieldError::new(field, "must not be empty"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_errors_name_the_field() {
        assert_eq!(Scenario::default().validate(), Ok(()));
        let mut s = Scenario::default();
        s.robot.max_speed_mps = -1.0;
        assert!(s.validate().unwrap_err().to_string().starts_with("robot.max_speed_mps"));
        let mut s = Scenario::default();
        s.lidar.glass_pass_probability = 1.5;
        assert!(s.validate().unwrap_err().to_string().starts_with("lidar.glass_pass_probability"));
        let mut s = Scenario::default();
        s.world.grooves[1] = Rect::new(1.0, 1.0, 0.0, 2.0);
        assert!(s.validate().unwrap_err().to_string().starts_with("world.grooves[1]"));
        let mut s = Scenario::default();
        s.gnss.datum_lat_deg = 91.0;
        assert!(s.validate().unwrap_err().to_string().starts_with("gnss.datum"));
        let mut s = Scenario::default();
        s.robot.waypoints.truncate(2);
        assert!(s.validate().unwrap_err().to_string().starts_with("robot.waypoints"));
        let mut s = Scenario::default();
        s.robot.waypoints[1] = [1e7, 3.0];
        assert!(s.validate().unwrap_err().to_string().contains("more than the 1e5 m"), "{:?}", s.validate());
        let mut s = Scenario::default();
        s.frames.gps.clear();
        assert!(s.validate().unwrap_err().to_string().starts_with("frames.gps"));
        let mut s = Scenario::default();
        s.world.start_time_s = i64::MAX;
        assert!(s.validate().unwrap_err().to_string().starts_with("world.start_time_s"));
        s.world.start_time_s = -1;
        assert!(s.validate().unwrap_err().to_string().starts_with("world.start_time_s"));
        s.world.start_time_s = 0;
        s.robot.lookahead_m = 1e300;
        assert!(s.validate().unwrap_err().to_string().starts_with("robot.lookahead_m"));
        s.robot.lookahead_m = MAX_LOOKAHEAD_M;
        assert_eq!(s.validate(), Ok(()));
        let mut s = Scenario::default();
        s.robot.duration_s = 3_600.0;
        s.lidar.beams = 2_000;
        let e = s.validate().unwrap_err();
        assert!(e.field == "lidar.beams" && e.message.contains("lidar.rate_hz × robot.duration_s"), "{e}");
        let mut s = Scenario::default();
        s.odometry.rate_hz = f64::NAN;
        assert!(s.validate().unwrap_err().to_string().starts_with("odometry.rate_hz"));
        let mut s = Scenario::default();
        s.world.objects[6].class = "fence".into();
        assert!(s.validate().unwrap_err().to_string().starts_with("world.objects[6].class"));
        let mut s = Scenario::default();
        s.camera.hfov_deg = 180.0;
        assert!(s.validate().unwrap_err().to_string().starts_with("camera.hfov_deg"));
        let mut s = Scenario::default();
        s.camera.backlight.class = "sky".into();
        assert!(s.validate().unwrap_err().to_string().starts_with("camera.backlight.class"));
        let mut s = Scenario::default();
        s.camera.width = 4096;
        s.camera.height = 4096;
        let e = s.validate().unwrap_err();
        assert!(e.field == "camera.width" && e.message.contains("camera.height × camera.rate_hz"), "{e}");
        let mut s = Scenario::default();
        s.person.speed_mps = 0.0;
        assert!(s.validate().unwrap_err().to_string().starts_with("person.speed_mps"));
    }
}
