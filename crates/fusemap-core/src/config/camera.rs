//! The semantic camera's `[[sensor]]` keys and the `[[class]]` tables.
//!
//! A camera reads three topics (label images, aligned depth images, `CameraInfo`). The
//! config does not plan one it does not list; a log run maps a camera it finds on the
//! usual topics with [`default_camera`] (unless the camera kind is disabled). Its mount
//! `base_from_sensor` is `base_from_camera_optical`, the optical frame of REP 103 (x right,
//! y down, z forward).

use crate::geometry::{Mount3, Pose3};
use crate::sensor::camera::optical_mount;
use crate::sensor::{CameraError, CameraModel, CameraParams, ClassSpec, ClassTable, Pinhole};
use serde::{Deserialize, Serialize};

use super::{check_mount, err, finite, FieldError, SensorConfig};

/// Default largest stamp difference between a label image and its depth image, seconds:
/// aligned streams of one RGB-D driver carry the same stamp; 5 ms allows for rounding.
pub const DEFAULT_PAIR_TOLERANCE_S: f64 = 0.005;

/// A camera of the plan.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedCamera {
    /// Its name.
    pub name: String,
    /// The label images' topic (default `/camera/labels`).
    pub topic: String,
    /// The aligned depth images' topic (default `/camera/depth`).
    pub depth_topic: String,
    /// The `CameraInfo` topic (default `/camera/camera_info`).
    pub info_topic: String,
    /// The configured frame id of the optical frame.
    pub frame: Option<String>,
    /// The mount `base_from_camera_optical`: as configured, else a level forward camera at
    /// the base origin (roll = -π/2, pitch = 0, yaw = -π/2), which is only a placeholder
    /// for the log's TF.
    pub mount: Mount3,
    /// Whether the mount was written in the config.
    pub mount_given: bool,
    /// Seconds added to its stamps.
    pub time_offset_s: f64,
    /// The sensor model's parameters, validated.
    pub params: CameraParams,
    /// Largest stamp difference of a label image and the depth image paired with it,
    /// seconds.
    pub pair_tolerance_s: f64,
    /// `true`: written in the config; `false`: [`default_camera`], found on the usual topics.
    pub explicit: bool,
}

impl PlannedCamera {
    /// The mount as the camera model takes it: `base_from_optical`.
    pub fn base_from_optical(&self) -> Pose3 {
        let m = &self.mount;
        Pose3::new([m.x, m.y, m.z], m.quaternion())
    }

    /// The camera's model, once its intrinsics are known (from the log's `CameraInfo`),
    /// with the map's cell size and the plan's classes.
    pub fn model(&self, pinhole: Pinhole, cell_size_m: f64, classes: ClassTable) -> Result<CameraModel, CameraError> {
        CameraModel::new(pinhole, self.base_from_optical(), self.params, cell_size_m, classes)
    }
}

/// The key a [`CameraParams`] field is written as in a `[[sensor]]` table.
fn key_of(param: &'static str) -> &'static str {
    match param {
        "p_free" => "camera_p_free",
        other => other,
    }
}

/// Validates a camera table. `prior` is the map's: the camera's free evidence must be
/// below it.
pub(super) fn plan_camera(i: usize, s: &SensorConfig, name: String, prior: f64) -> Result<PlannedCamera, FieldError> {
    let f = |key: &str| format!("sensor[{i}].{key}");
    let d = CameraParams::default();
    let params = CameraParams {
        stride: s.stride.unwrap_or(d.stride),
        min_depth_m: s.min_depth_m.unwrap_or(d.min_depth_m),
        max_depth_m: s.max_depth_m.unwrap_or(d.max_depth_m),
        depth_sigma_k: s.depth_sigma_k.unwrap_or(d.depth_sigma_k),
        floor_band_m: s.floor_band_m.unwrap_or(d.floor_band_m),
        obstacle_max_z_m: s.obstacle_max_z_m.unwrap_or(d.obstacle_max_z_m),
        p_free: s.camera_p_free.unwrap_or(d.p_free),
        occupancy_weight: s.occupancy_weight.unwrap_or(d.occupancy_weight),
        inconsistent_label_weight: s.inconsistent_label_weight.unwrap_or(d.inconsistent_label_weight),
    };
    params.validate().map_err(|e| match e {
        CameraError::Parameter { name, message } => err(f(key_of(name)), message),
        other => err(format!("sensor[{i}]"), other.to_string()),
    })?;
    if params.p_free >= prior {
        return Err(err(f("camera_p_free"), format!("must be below the prior {prior}, got {}", params.p_free)));
    }
    let pair = finite(&f("pair_tolerance_s"), s.pair_tolerance_s.unwrap_or(DEFAULT_PAIR_TOLERANCE_S))?;
    if !(0.0..=1.0).contains(&pair) {
        return Err(err(f("pair_tolerance_s"), format!("must be within [0, 1] seconds, got {pair}")));
    }
    let topic = |key: &str, given: &Option<String>, default: &str| match given {
        Some(t) if t.trim().is_empty() => Err(err(f(key), "must not be empty (leave it out for the default)")),
        Some(t) => Ok(t.clone()),
        None => Ok(default.to_string()),
    };
    if let Some(m) = &s.base_from_sensor {
        check_mount(f, m)?;
    }
    Ok(PlannedCamera {
        name,
        topic: topic("topic", &s.topic, s.kind.default_topic())?,
        depth_topic: topic("depth_topic", &s.depth_topic, "/camera/depth")?,
        info_topic: topic("info_topic", &s.info_topic, "/camera/camera_info")?,
        frame: s.frame.clone(),
        mount: s.base_from_sensor.unwrap_or_else(|| optical_mount([0.0; 3], 0.0, 0.0).to_mount()),
        mount_given: s.base_from_sensor.is_some(),
        time_offset_s: s.time_offset_s,
        params,
        pair_tolerance_s: pair,
        explicit: true,
    })
}

/// The camera a log run plans when the config lists none and the log carries the usual
/// topics (`/camera/labels`, `/camera/depth`, `/camera/camera_info`): every parameter at
/// its default, the mount from the log's TF.
pub fn default_camera(prior: f64) -> Result<PlannedCamera, FieldError> {
    let mut c = plan_camera(0, &SensorConfig::new(super::SensorKind::Camera), "camera".into(), prior)?;
    c.explicit = false;
    Ok(c)
}

/// One `[[class]]` table: a semantic class of the label images.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassConfig {
    /// The id label images carry for it.
    pub id: u16,
    /// Its name (unique).
    pub name: String,
    /// Its colour in the semantic picture, `[r, g, b]`; left out, one chosen from its id
    /// ([`default_class_color`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[u8; 3]>,
    /// The occupancy probability its label suggests, in (0, 1).
    pub p_occupied: f64,
    /// Its update weight, ≥ 0 (default 1).
    #[serde(default = "one")]
    pub weight: f64,
    /// It moves: dynamic layer only, never static occupancy (default false).
    #[serde(default)]
    pub dynamic: bool,
    /// Not evidence (unlabelled, ceiling, sky) (default false).
    #[serde(default)]
    pub ignore: bool,
}

fn one() -> f64 {
    1.0
}

/// The colour of a class whose table gives none: hues a golden angle (137.5°) apart by
/// id, so any few ids get clearly different colours, at a saturation and brightness that
/// stay apart from the map's greys.
pub fn default_class_color(id: u16) -> [u8; 3] {
    let hue = (f64::from(id) * 137.507_764_050_037_85).rem_euclid(360.0) / 60.0;
    let (s, v) = (0.7, 0.9);
    let c = v * s;
    let x = c * (1.0 - (hue.rem_euclid(2.0) - 1.0).abs());
    let (r, g, b) = match hue as u8 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|u| ((u + m) * 255.0).round() as u8)
}

impl From<&ClassConfig> for ClassSpec {
    fn from(c: &ClassConfig) -> ClassSpec {
        ClassSpec {
            id: c.id,
            name: c.name.clone(),
            color: c.color.unwrap_or_else(|| default_class_color(c.id)),
            p_occupied: c.p_occupied,
            weight: c.weight,
            dynamic: c.dynamic,
            ignore: c.ignore,
        }
    }
}

impl From<&ClassSpec> for ClassConfig {
    fn from(c: &ClassSpec) -> ClassConfig {
        ClassConfig {
            id: c.id,
            name: c.name.clone(),
            color: Some(c.color),
            p_occupied: c.p_occupied,
            weight: c.weight,
            dynamic: c.dynamic,
            ignore: c.ignore,
        }
    }
}

/// The class table of the `[[class]]` tables; none given: the production default.
pub(super) fn class_table(tables: &[ClassConfig]) -> Result<ClassTable, FieldError> {
    if tables.is_empty() {
        return Ok(ClassTable::production_default());
    }
    ClassTable::new(tables.iter().map(ClassSpec::from).collect()).map_err(|m| match m.split_once(": ") {
        Some((field, rest)) if field.starts_with("class") => err(field, rest),
        _ => err("class", m),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{Config, SensorKind};
    use super::*;

    fn camera(f: impl FnOnce(&mut SensorConfig)) -> Config {
        let mut s = SensorConfig::new(SensorKind::Camera);
        f(&mut s);
        Config { sensor: vec![s], ..Default::default() }
    }

    #[test]
    fn a_camera_table_is_planned_as_written() {
        let p = Config::default().validate().unwrap();
        assert!(p.cameras.is_empty(), "cameras are never auto-detected");
        assert_eq!(p.classes, ClassTable::production_default());
        let c = camera(|s| {
            s.topic = Some("/seg/labels".into());
            s.stride = Some(2);
            s.max_depth_m = Some(4.0);
            s.camera_p_free = Some(0.4);
            s.occupancy_weight = Some(0.3);
            s.pair_tolerance_s = Some(0.01);
            s.time_offset_s = -0.03;
            s.base_from_sensor = Some(Mount3 { z: 1.1, roll: -2.0, yaw: -1.5, ..Default::default() });
        });
        let p = c.validate().unwrap();
        assert_eq!(p.lidars.len(), 1, "the default lidar is still mapped");
        assert!(p.sensors.is_empty(), "a camera is not a pose sensor");
        let cam = &p.cameras[0];
        assert_eq!(cam.name, "camera");
        assert_eq!(cam.topic, "/seg/labels");
        assert_eq!((cam.depth_topic.as_str(), cam.info_topic.as_str()), ("/camera/depth", "/camera/camera_info"));
        let want =
            CameraParams { stride: 2, max_depth_m: 4.0, p_free: 0.4, occupancy_weight: 0.3, ..Default::default() };
        assert_eq!(cam.params, want);
        assert_eq!(cam.pair_tolerance_s, 0.01);
        assert_eq!(cam.time_offset_s, -0.03);
        assert!(cam.mount_given && cam.mount.z == 1.1 && cam.explicit);
        let written = Mount3 { z: 1.1, roll: -2.0, yaw: -1.5, ..Default::default() };
        assert!(cam.base_from_optical().angle_to(&Pose3::new([0.0; 3], written.quaternion())) < 1e-12);
        assert_eq!(cam.base_from_optical().translation, [0.0, 0.0, 1.1]);
        // Defaults, and the default mount is a level forward optical frame.
        let p = camera(|_| {}).validate().unwrap();
        let cam = &p.cameras[0];
        assert_eq!(cam.topic, "/camera/labels");
        assert_eq!(cam.params, CameraParams::default());
        assert_eq!(cam.pair_tolerance_s, DEFAULT_PAIR_TOLERANCE_S);
        assert!(!cam.mount_given);
        let fwd = cam.base_from_optical().rotate([0.0, 0.0, 1.0]);
        assert!((fwd[0] - 1.0).abs() < 1e-12, "{fwd:?}");
        let pinhole = Pinhole::new(64, 48, 50.0, 50.0, 32.0, 24.0).unwrap();
        let m = cam.model(pinhole, p.geometry.resolution(), p.classes.clone()).unwrap();
        assert_eq!(m.params(), &cam.params);
        // Disabled: not planned; its kind is listed as disabled.
        let p = camera(|s| s.enabled = false).validate().unwrap();
        assert!(p.cameras.is_empty() && p.disabled_kinds == [SensorKind::Camera]);
        assert!(crate::config::auto_sensor(SensorKind::Camera).is_none());
    }

    #[test]
    fn camera_keys_are_checked_and_named() {
        let field = |f: fn(&mut SensorConfig)| camera(f).validate().unwrap_err().field;
        assert_eq!(field(|s| s.stride = Some(0)), "sensor[0].stride");
        assert_eq!(field(|s| s.min_depth_m = Some(-0.1)), "sensor[0].min_depth_m");
        assert_eq!(field(|s| s.max_depth_m = Some(0.1)), "sensor[0].max_depth_m");
        assert_eq!(field(|s| s.depth_sigma_k = Some(f64::NAN)), "sensor[0].depth_sigma_k");
        assert_eq!(field(|s| s.floor_band_m = Some(0.0)), "sensor[0].floor_band_m");
        assert_eq!(field(|s| s.obstacle_max_z_m = Some(0.01)), "sensor[0].obstacle_max_z_m");
        assert_eq!(field(|s| s.camera_p_free = Some(0.6)), "sensor[0].camera_p_free");
        assert_eq!(field(|s| s.occupancy_weight = Some(-1.0)), "sensor[0].occupancy_weight");
        assert_eq!(field(|s| s.inconsistent_label_weight = Some(2.0)), "sensor[0].inconsistent_label_weight");
        assert_eq!(field(|s| s.pair_tolerance_s = Some(-0.001)), "sensor[0].pair_tolerance_s");
        assert_eq!(field(|s| s.depth_topic = Some(" ".into())), "sensor[0].depth_topic");
        assert_eq!(field(|s| s.info_topic = Some(String::new())), "sensor[0].info_topic");
        assert_eq!(field(|s| s.p_occ = Some(0.9)), "sensor[0].p_occ", "a lidar key on a camera");
        assert_eq!(
            field(|s| s.base_from_sensor = Some(Mount3 { pitch: f64::NAN, ..Default::default() })),
            "sensor[0].base_from_sensor.pitch"
        );
        // The camera's free evidence must be below the map's prior.
        let mut c = camera(|s| s.camera_p_free = Some(0.35));
        c.map.prior = 0.3;
        c.map.clamp_min = 0.1;
        let e = c.validate().unwrap_err();
        assert_eq!(e.field, "sensor[0].camera_p_free");
        assert!(e.message.contains("prior"), "{e}");
    }

    #[test]
    fn camera_keys_on_another_kind_are_refused_by_name() {
        for (kind, set) in [
            (SensorKind::Lidar, (|s: &mut SensorConfig| s.stride = Some(2)) as fn(&mut SensorConfig)),
            (SensorKind::Imu, |s| s.depth_topic = Some("/d".into())),
            (SensorKind::Gnss, |s| s.pair_tolerance_s = Some(0.1)),
            (SensorKind::WheelOdometry, |s| s.camera_p_free = Some(0.4)),
        ] {
            let mut s = SensorConfig::new(kind);
            set(&mut s);
            let e = Config { sensor: vec![s], ..Default::default() }.validate().unwrap_err();
            assert!(e.field.starts_with("sensor[0].") && e.message.contains(kind.as_str()), "{e}");
        }
        let mut s = SensorConfig::new(SensorKind::Lidar);
        s.occupancy_weight = Some(0.5);
        let e = Config { sensor: vec![s], ..Default::default() }.validate().unwrap_err();
        assert_eq!(e.to_string(), "sensor[0].occupancy_weight: not a key of a `lidar` sensor");
    }

    fn class(id: u16, name: &str, p: f64) -> ClassConfig {
        ClassConfig {
            id,
            name: name.into(),
            color: Some([1, 2, 3]),
            p_occupied: p,
            weight: 1.0,
            dynamic: false,
            ignore: false,
        }
    }

    #[test]
    fn class_tables() {
        let c = Config { class: vec![class(10, "floor", 0.2), class(11, "rack", 0.8)], ..Default::default() };
        let t = c.validate().unwrap().classes;
        assert_eq!(t.len(), 2);
        assert_eq!(t.index_of(11), Some(1));
        assert_eq!(t.get(1).name, "rack");
        // The default table, written out, is the default.
        let written: Vec<ClassConfig> = ClassTable::production_default().iter().map(ClassConfig::from).collect();
        let c = Config { class: written, ..Default::default() };
        assert_eq!(c.validate().unwrap().classes, ClassTable::production_default());
        // Bad tables name the class and field.
        let bad = |class: Vec<ClassConfig>| Config { class, ..Default::default() }.validate().unwrap_err();
        let e = bad(vec![class(1, "a", 0.2), class(1, "b", 0.7)]);
        assert_eq!(e.field, "class[1].id");
        assert!(e.message.contains("class[0]"), "{e}");
        assert_eq!(bad(vec![class(1, "a", 0.2), class(2, "a", 0.7)]).field, "class[1].name");
        assert_eq!(bad(vec![class(1, "a", 1.0)]).field, "class[0].p_occupied");
        assert_eq!(bad(vec![ClassConfig { weight: -1.0, ..class(1, "a", 0.5) }]).field, "class[0].weight");
        let many: Vec<ClassConfig> = (0..65).map(|i| class(i, &format!("c{i}"), 0.5)).collect();
        assert_eq!(bad(many).field, "class");
    }

    #[test]
    fn a_class_without_a_colour_gets_one() {
        let c = Config {
            class: vec![ClassConfig { color: None, ..class(3, "rack", 0.8) }, class(4, "pallet", 0.7)],
            ..Default::default()
        };
        let t = c.validate().unwrap().classes;
        assert_eq!(t.get(0).color, default_class_color(3));
        assert_eq!(t.get(1).color, [1, 2, 3]);
        // Neighbouring ids get clearly different colours, none of them grey.
        let colors: Vec<[u8; 3]> = (0..16).map(default_class_color).collect();
        for (i, a) in colors.iter().enumerate() {
            let spread = a.iter().max().unwrap() - a.iter().min().unwrap();
            assert!(spread > 100, "id {i}: {a:?} is nearly grey");
            for b in &colors[i + 1..i + 2.min(colors.len() - i)] {
                let d: i32 = a.iter().zip(b).map(|(x, y)| (*x as i32 - *y as i32).abs()).sum();
                assert!(d > 120, "ids {i} and {}: {a:?} {b:?}", i + 1);
            }
        }
    }
}
