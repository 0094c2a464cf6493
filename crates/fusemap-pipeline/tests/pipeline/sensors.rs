//! `[[sensor]]` tables against a real bag: every lidar listed is mapped, a listed topic the
//! log lacks is refused by name, disabled kinds are not auto-detected, and a lidar's
//! `time_offset_s` moves its scans in time.

use fusemap_core::config::{Config, PoseSource, SensorConfig, SensorKind};
use fusemap_pipeline::{map_log, PipelineError};
use fusemap_sim::{simulate, Scenario, SimMessage};
use std::path::PathBuf;
use std::sync::OnceLock;

/// A 30 s production-line bag whose scans are also published on `/scan_copy`.
fn bag() -> &'static PathBuf {
    static B: OnceLock<PathBuf> = OnceLock::new();
    B.get_or_init(|| {
        let mut s = Scenario::default();
        s.robot.duration_s = 30.0;
        let mut rec = simulate(&s).expect("simulates");
        let copies: Vec<SimMessage> = rec
            .messages
            .iter()
            .filter_map(|m| match m {
                SimMessage::Scan(s) => {
                    let mut c = s.clone();
                    c.topic = "/scan_copy".into();
                    Some(SimMessage::Scan(c))
                }
                _ => None,
            })
            .collect();
        rec.messages.extend(copies);
        rec.messages.sort_by_key(|m| m.stamp());
        let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "sensor-tables");
        let bag = dir.join("bag");
        fusemap_sim::bag::write_bag(&rec, &bag, true).expect("written");
        bag
    })
}

fn lidar(topic: &str) -> SensorConfig {
    SensorConfig {
        topic: Some(topic.into()),
        name: Some(topic.trim_start_matches('/').into()),
        ..SensorConfig::new(SensorKind::Lidar)
    }
}

/// A config with these sensors; the bag's camera is switched off (these tests are about
/// the lidars; the camera has its own in `camera_scenario` and `camera_bad_input`).
fn with(mut sensor: Vec<SensorConfig>) -> Config {
    sensor.push(SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Camera) });
    Config { sensor, ..Default::default() }
}

fn run(cfg: Config) -> Result<fusemap_pipeline::MapRun, PipelineError> {
    map_log(&cfg.validate().expect("valid"), bag(), &mut |_| {})
}

#[test]
fn every_listed_lidar_is_mapped() {
    let cfg = with(vec![lidar("/scan"), lidar("/scan_copy")]);
    let r = run(cfg).unwrap();
    assert_eq!(r.report.lidars.len(), 2);
    for l in &r.report.lidars {
        assert_eq!(l.scans_read, 300, "{}", l.topic);
        assert!(l.scans_used > 280, "{}: {}", l.topic, l.scans_used);
    }
    let per_sensor: Vec<u64> = r.engine.sensor_stats().map(|s| s.scans).collect();
    assert_eq!(per_sensor.len(), 2);
    assert_eq!(per_sensor[0], per_sensor[1]);
    assert_eq!(r.report.merge.len(), 2, "both topics go through the merge");

    // Without a lidar table the log's `/scan` is mapped and the other topic is named.
    let r = run(with(vec![])).unwrap();
    assert_eq!(r.report.lidars.len(), 1);
    assert!(r.notes.iter().any(|n| n.contains("/scan_copy")), "{:?}", r.notes);
}

#[test]
fn a_listed_topic_the_log_lacks_is_refused_by_name() {
    let cfg = with(vec![lidar("/scan"), lidar("/scan_rear")]);
    let e = run(cfg).err().expect("refused");
    // The binding of sensors to topics refused it: a caller can tell it from a budget.
    assert_eq!(e.refusal_stage(), Some(fusemap_pipeline::Stage::Sensors), "{e}");
    let e = e.to_string();
    assert!(e.contains("/scan_rear") && e.contains("/scan_copy"), "{e}");
    let cfg = with(vec![SensorConfig { topic: Some("/gps".into()), ..SensorConfig::new(SensorKind::Gnss) }]);
    let e = run(cfg).err().expect("refused");
    assert_eq!(e.refusal_stage(), Some(fusemap_pipeline::Stage::Sensors), "{e}");
    let e = e.to_string();
    assert!(e.contains("/gps") && e.contains("/gnss/fix"), "{e}");
}

#[test]
fn disabled_kinds_are_not_auto_detected() {
    let cfg = with(vec![
        lidar("/scan"),
        SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Imu) },
        SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Gnss) },
    ]);
    let r = run(cfg).unwrap();
    // Odometry alone (SLAM corrects it by default).
    let p = &r.report.pose_source;
    assert!(p.starts_with("odometry") || p.contains("over odometry"), "{p}");
    assert!(
        !r.report.sensors.values().any(|v| v.starts_with("imu") || v.starts_with("gnss")),
        "{:?}",
        r.report.sensors
    );
}

#[test]
fn a_lidar_time_offset_moves_its_scans() {
    let mut cfg = Config::default();
    cfg.log.pose_source = PoseSource::Odometry;
    // The odometry alone places the scans: SLAM would carry the late ones on past the
    // track's end by matching.
    cfg.slam.mode = fusemap_core::config::SlamMode::Off;
    cfg.sensor = vec![lidar("/scan")];
    let base = run(cfg.clone()).unwrap();
    // 10 s later: the last third of the scans fall after the end of the odometry.
    cfg.sensor[0].time_offset_s = 10.0;
    let shifted = run(cfg).unwrap();
    let (a, b) = (&base.report.lidars[0], &shifted.report.lidars[0]);
    assert_eq!(b.time_offset_s, 10.0);
    assert!(
        b.scans_skipped.after_last_pose >= 95 && a.scans_skipped.after_last_pose <= 1,
        "{:?} / {:?}",
        a.scans_skipped,
        b.scans_skipped
    );
}

#[test]
fn one_pass_feeds_several_maps_each_with_its_sensors() {
    use fusemap_core::fusion::{MapSet, SensorSelection};
    use fusemap_core::grid::FusionGrid;
    use fusemap_core::measurement::SensorId;
    use fusemap_pipeline::recording::Inventory;
    let plan = with(vec![lidar("/scan"), lidar("/scan_copy")]).validate().unwrap();
    let inv = Inventory::read(bag()).unwrap();
    let (bound, track, s) = fusemap_pipeline::run::prepare(&plan, &inv).unwrap();
    let grid = || FusionGrid::new(plan.geometry, plan.occupancy);
    let maps = MapSet::new("both", SensorSelection::All, grid()).with(
        "first only",
        SensorSelection::Sensors(vec![SensorId(0)]),
        grid(),
    );
    let run = fusemap_pipeline::map_with_track(&plan, &inv, &bound, track, s, maps.into(), &mut |_| {}).unwrap();
    // The first lidar's map from the one pass equals a run that maps only that lidar.
    let only = map_log(&with(vec![lidar("/scan")]).validate().unwrap(), bag(), &mut |_| {}).unwrap();
    let a = run.engine.maps().by_name("first only").unwrap().grid().known_raster().unwrap();
    let b = only.engine.grid().known_raster().unwrap();
    assert_eq!((a.width, a.height, a.first_cell), (b.width, b.height, b.first_cell));
    assert!(a.log_odds == b.log_odds && a.known == b.known, "one pass and a separate run differ");
    let both = run.engine.maps().by_name("both").unwrap().grid().known_raster().unwrap();
    assert!(both.log_odds != a.log_odds, "the map of both lidars has both lidars' evidence");
}
