//! The configuration's validation: every rule names its field.

use super::*;
use crate::geometry::Mount3;
use crate::grid::PassThroughParams;

#[test]
fn unlisted_kinds_are_auto_and_disabled_lidars_are_not_mapped() {
    let p = Config::default().validate().unwrap();
    assert_eq!(p.lidars.len(), 1);
    assert!(!p.lidars[0].explicit && p.lidars[0].topic.is_none());
    assert!(p.sensors.is_empty());
    let c = Config {
        sensor: vec![
            SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Lidar) },
            SensorConfig { topic: Some("/wheels".into()), ..SensorConfig::new(SensorKind::WheelOdometry) },
        ],
        ..Default::default()
    };
    let p = c.validate().unwrap();
    assert!(p.lidars.is_empty());
    assert_eq!(p.sensors.len(), 1);
    assert_eq!(p.sensors[0].topic.as_deref(), Some("/wheels"));
    assert_eq!(p.sensors[0].name, "wheel_odometry");
    assert!(auto_sensor(SensorKind::Imu).is_some_and(|s| !s.explicit));
    assert!(auto_sensor(SensorKind::Lidar).is_none());
}

#[test]
fn defaults_are_the_documents() {
    let p = Config::default().validate().unwrap();
    assert_eq!(p.geometry.resolution(), 0.05);
    assert_eq!(p.occupancy.prior, 0.5);
    let (name, m) = (&p.lidars[0].name, &p.lidars[0].model);
    assert_eq!(name, "laser");
    assert_eq!(m.params().p_occ, 0.9);
    assert_eq!(m.params().p_free, 0.4);
    assert_eq!(m.params().min_range, 0.1);
    assert_eq!(m.params().max_range, 10.0);
}

fn field_of(c: Config) -> String {
    c.validate().unwrap_err().field
}

#[test]
fn each_rule_names_its_field() {
    let mut c = Config::default();
    c.map.resolution = 0.0;
    assert_eq!(field_of(c), "map.resolution");
    let mut c = Config::default();
    c.map.prior = 1.0;
    assert_eq!(field_of(c), "map.prior");
    let mut c = Config::default();
    c.sensor.push(SensorConfig { p_occ: Some(0.45), ..SensorConfig::new(SensorKind::Lidar) });
    assert_eq!(field_of(c), "sensor[0].p_occ");
    // Two tables of one kind on one topic (a thousand GNSS sensors on `/fix`).
    let mut c = Config::default();
    let fix = SensorConfig { topic: Some("/fix".into()), ..SensorConfig::new(SensorKind::Gnss) };
    c.sensor.extend([
        fix.clone(),
        SensorConfig { topic: Some("/odom".into()), ..SensorConfig::new(SensorKind::WheelOdometry) },
        fix.clone(),
    ]);
    assert_eq!(field_of(c.clone()), "sensor[2].topic");
    c.sensor[0].enabled = false;
    assert!(c.validate().is_ok(), "a disabled table reads nothing");
    let lidar = |f: fn(&mut SensorConfig)| {
        let mut c = Config::default();
        let mut s = SensorConfig::new(SensorKind::Lidar);
        f(&mut s);
        c.sensor.push(s);
        field_of(c)
    };
    assert_eq!(lidar(|s| s.p_free = Some(0.5)), "sensor[0].p_free");
    let far = Mount3 { x: 1e300, ..Default::default() };
    assert_eq!(
        lidar(|s| s.base_from_sensor = Some(Mount3 { x: 1e300, ..Default::default() })),
        "sensor[0].base_from_sensor.x"
    );
    let mut c = Config::default();
    c.sensor.push(SensorConfig { base_from_sensor: Some(far), ..SensorConfig::new(SensorKind::Imu) });
    assert_eq!(field_of(c), "sensor[0].base_from_sensor.x");
    assert_eq!(lidar(|s| s.max_range = Some(0.05)), "sensor[0].max_range");
    assert_eq!(lidar(|s| s.min_range = Some(f64::NAN)), "sensor[0].min_range");
    assert_eq!(
        lidar(|s| s.base_from_sensor = Some(Mount3 { pitch: 0.5, ..Default::default() })),
        "sensor[0].base_from_sensor"
    );
    assert_eq!(lidar(|s| s.gyro_noise_rad_s = Some(0.1)), "sensor[0].gyro_noise_rad_s");
    assert_eq!(lidar(|s| s.time_offset_s = f64::INFINITY), "sensor[0].time_offset_s");
    let mut c = Config::default();
    c.map.clamp_max = 0.4;
    assert_eq!(field_of(c), "map");
    let mut c = Config::default();
    c.map.free_threshold = 0.7;
    assert_eq!(field_of(c), "map.free_threshold");
    let mut c = Config {
        sensor: vec![SensorConfig::new(SensorKind::Lidar), SensorConfig::new(SensorKind::Lidar)],
        ..Default::default()
    };
    c.sensor[1].name = Some("laser".into());
    assert_eq!(field_of(c), "sensor[1].name");
    let c = Config {
        sensor: vec![SensorConfig { datum: Some([91.0, 0.0, 0.0]), ..SensorConfig::new(SensorKind::Gnss) }],
        ..Default::default()
    };
    assert_eq!(field_of(c), "sensor[0].datum");
    let mut c = Config::default();
    c.log.max_pose_gap_s = 0.0;
    assert_eq!(field_of(c), "log.max_pose_gap_s");
    let mut c = Config::default();
    c.log.base_frame = " ".into();
    assert_eq!(field_of(c), "log.base_frame");
    let mut c = Config::default();
    c.estimator.gate_probability = 1.5;
    assert_eq!(field_of(c), "estimator.gate_probability");
    let mut c = Config::default();
    c.log.gap_bridge_motion_m = -1.0;
    assert_eq!(field_of(c), "log.gap_bridge_motion_m");
    let map = |f: fn(&mut PassThroughParams)| {
        let mut c = Config::default();
        f(&mut c.map.pass_through);
        field_of(c)
    };
    assert_eq!(map(|p| p.weight = 1.5), "map.pass_through.weight");
    assert_eq!(map(|p| p.threshold = 0.3), "map.pass_through.threshold");
    assert_eq!(map(|p| p.threshold = f64::NAN), "map.pass_through.threshold");
    assert_eq!(map(|p| p.margin_cells = 1_000_000), "map.pass_through.margin_cells");
    let filters = |f: fn(&mut crate::sensor::ScanFilters)| {
        let mut filters = crate::sensor::ScanFilters::default();
        f(&mut filters);
        let mut c = Config::default();
        c.sensor.push(SensorConfig { filters: Some(filters), ..SensorConfig::new(SensorKind::Lidar) });
        field_of(c)
    };
    assert_eq!(filters(|f| f.speckle.window = 0), "sensor[0].filters.speckle.window");
    assert_eq!(filters(|f| f.self_box.max = [-1.0, 0.0]), "sensor[0].filters.box");
    let c = Config {
        sensor: vec![SensorConfig {
            filters: Some(crate::sensor::ScanFilters::default()),
            ..SensorConfig::new(SensorKind::Imu)
        }],
        ..Default::default()
    };
    assert_eq!(field_of(c), "sensor[0].filters");
}

#[test]
fn a_configured_map_handles_pass_throughs_and_the_core_default_does_not() {
    let plan = Config::default().validate().unwrap();
    assert_eq!(plan.occupancy.pass_through, PassThroughParams::default());
    assert!(!plan.occupancy.pass_through.is_off());
    assert!(OccupancyParams::default().pass_through.is_off());
    // Filters are off by default everywhere (lossless on the corrected CARMEN logs).
    assert!(!plan.lidars[0].model.params().filters.any());
}
