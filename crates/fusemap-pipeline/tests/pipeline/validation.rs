//! `fusemap validate` (the design document's §5) on the production line with its ground
//! truth: a correct configuration, the camera's mount 5° off in yaw, and the lidar's 5 cm
//! and 2° off. The simulated bag is written once; each case maps it with its own
//! configuration, whose mounts override the bag's TF (`[log] extrinsics = "config"`).

use fusemap_core::metrics::Verdict;
use fusemap_pipeline::scenario::PRODUCTION_LINE_CONFIG;
use fusemap_pipeline::validate::{ValidateJob, Validation, VALIDATE_NPZ};
use fusemap_sim::{simulate, Scenario, SimRecording};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// The production line's simulated run (its truth), simulated once per test binary.
pub(crate) fn recording() -> &'static SimRecording {
    static REC: OnceLock<SimRecording> = OnceLock::new();
    REC.get_or_init(|| simulate(&Scenario::default()).expect("the default scenario simulates"))
}

/// The production line's bag, written once.
pub(crate) fn bag() -> &'static Path {
    static BAG: OnceLock<PathBuf> = OnceLock::new();
    BAG.get_or_init(|| {
        let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "validation");
        let bag = dir.join("bag");
        fusemap_sim::bag::write_bag(recording(), &bag, true).expect("the bag is written");
        bag
    })
}

/// Results by key, each computed once ([`once_per_key`]).
pub(crate) type Memo<T> = OnceLock<Mutex<HashMap<String, Arc<OnceLock<T>>>>>;

/// Runs `compute` once per `key` in this test binary, however many tests ask for it and
/// whichever asks first (tests run in parallel: a second asker waits for the first).
/// The slow passes of the validation and calibration tests (a validation ~10 s, a
/// calibration ~20 s in the test profile) are shared this way where tests need the same one.
pub(crate) fn once_per_key<T: Clone + Send + Sync + 'static>(
    memo: &'static Memo<T>,
    key: &str,
    compute: impl FnOnce() -> T,
) -> T {
    let cell = Arc::clone(memo.get_or_init(Default::default).lock().unwrap().entry(key.to_owned()).or_default());
    cell.get_or_init(compute).clone()
}

/// The production line's configuration with the lidar mounted at `lidar` (x, yaw) and
/// the camera's yaw turned by `camera_yaw_deg` from the simulator's mounts. Every mount
/// is written out: `extrinsics = "config"` takes none from the bag's TF (the GNSS
/// antenna's lever arm included).
pub(crate) fn config(lidar: (f64, f64), camera_yaw_deg: f64) -> String {
    let lidar = format!(
        "[sensor.base_from_sensor]\nx = {}\ny = 0.0\nz = 0.3\nroll = 0.0\npitch = 0.0\nyaw = {}\n\n",
        lidar.0,
        lidar.1.to_radians()
    );
    // The simulator's optical frame: 25 cm ahead, 1 m up, looking ahead and 25° down.
    let camera = format!(
        "\n[sensor.base_from_sensor]\nx = 0.25\ny = 0.0\nz = 1.0\nroll = {}\npitch = 0.0\nyaw = {}\n",
        -(90f64 + 25.0).to_radians(),
        (-90.0 + camera_yaw_deg).to_radians()
    );
    let gnss = "\n[sensor.base_from_sensor]\nx = -0.1\ny = 0.0\nz = 0.8\nroll = 0.0\npitch = 0.0\nyaw = 0.0\n";
    let datum = "datum = [48.137154, 11.576124, 520.0]\n";
    assert!(PRODUCTION_LINE_CONFIG.contains(datum), "the GNSS table's last line");
    let c = PRODUCTION_LINE_CONFIG
        .replace(datum, &format!("{datum}{gnss}"))
        .replace("[sensor.filters.shadow]", &format!("{lidar}[sensor.filters.shadow]"))
        .replace("info_topic = \"/camera/camera_info\"\n", &format!("info_topic = \"/camera/camera_info\"\n{camera}"));
    format!("{c}\n[log]\nextrinsics = \"config\"\n")
}

/// `fusemap validate` of the bag with `cfg`, once per configuration text in this test
/// binary (the first caller's `name` names the directory).
pub(crate) fn validate(name: &str, cfg: &str) -> Validation {
    static MEMO: Memo<Validation> = OnceLock::new();
    once_per_key(&MEMO, cfg, || validate_now(name, cfg))
}

fn validate_now(name: &str, cfg: &str) -> Validation {
    let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), &format!("validation-{name}"));
    let path = dir.join("config.toml");
    std::fs::write(&path, cfg).unwrap();
    let out = dir.join("out");
    let job = ValidateJob::plan(Some(&path), bag(), &out).unwrap_or_else(|e| panic!("{e}"));
    let run = job.run(&mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let v = run.validation;
    eprintln!("{name}: {}", serde_json::to_string(&v).unwrap());
    assert!(out.join(VALIDATE_NPZ).is_file() && out.join("map.npz").is_file());
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["validation"]["verdict"], serde_json::to_value(v.judgement.verdict).unwrap());
    assert!(summary["files"].as_array().unwrap().iter().any(|f| f["name"] == VALIDATE_NPZ));
    v
}

fn rate(v: &Validation, map: &str, sensor: &str) -> f64 {
    let m = v.maps.iter().find(|m| m.name == map).unwrap();
    m.hit_rates.iter().find(|h| h.sensor == sensor).unwrap().hit.rate.unwrap()
}

#[test]
fn the_verdict_names_the_sensor_whose_mount_is_wrong() {
    let good = validate("good", &config((0.25, 0.0), 0.0));
    // The correct mounts: every sensor agrees with the fused map. The entropy gain is
    // under the document's 0.05 nats here (the lidar alone holds most cells at a clamp),
    // and the report says so.
    assert_ne!(good.judgement.verdict, Verdict::CheckSyncAndExtrinsics, "{}", good.judgement.sentence);
    if good.judgement.verdict == Verdict::NoGain {
        assert!(good.judgement.sentence.contains("Why:"), "{}", good.judgement.sentence);
    }
    assert!(rate(&good, "m3", "camera") >= rate(&good, "m2", "camera"));
    assert!(rate(&good, "m1", "laser") > 0.9);
    let turn = good.lidar_motion[0].agreement.median_deg;
    assert!(turn.abs() < 0.5, "{turn}");

    let camera = validate("camera-yaw", &config((0.25, 0.0), 5.0));
    assert_eq!(camera.judgement.verdict, Verdict::CheckSyncAndExtrinsics);
    assert_eq!(camera.judgement.suspect.as_deref(), Some("camera"), "{}", camera.judgement.sentence);

    let lidar = validate("lidar-mount", &config((0.30, 2.0), 0.0));
    assert_eq!(lidar.judgement.verdict, Verdict::CheckSyncAndExtrinsics);
    assert_eq!(lidar.judgement.suspect.as_deref(), Some("laser"), "{}", lidar.judgement.sentence);
    // The lidar's direction of travel turned by about the 2° of its wrong yaw.
    let d = lidar.lidar_motion[0].agreement.median_deg - turn;
    assert!((d - 2.0).abs() < 0.5, "{d}");
}

/// `map.mcap`'s `/tf_static` on the production line mapped from its wheel odometry alone,
/// with SLAM: `map → odom` carries the odometry's last pose onto the track's pose at that
/// stamp, and it is not the identity (SLAM corrected the simulator's 3 % scale error).
#[test]
fn map_to_odom_carries_the_odometry_onto_the_slam_track() {
    let text = format!("{}pose_source = \"odometry\"\n", config((0.25, 0.0), 0.0));
    let cfg = fusemap_io::config_file::parse_config_str(&text, Path::new("config.toml")).unwrap();
    let run = fusemap_pipeline::map_log(&cfg.validate().unwrap(), bag(), &mut |_| {}).unwrap();
    assert!(run.report.slam.is_some(), "SLAM ran over the odometry");
    let (frame, m) = run.map_from_odom.clone().expect("odometry with SLAM gives map → odom");
    assert_eq!(frame, "odom");
    let inv = fusemap_pipeline::recording::Inventory::read(bag()).unwrap();
    let odometry = inv.odom.values().next().expect("the bag has odometry");
    let last = odometry.iter().rev().find(|o| run.trajectory.iter().any(|(t, _)| *t == o.stamp)).unwrap();
    let placed = run.trajectory.iter().find(|(t, _)| *t == last.stamp).unwrap().1;
    let carried = m.compose(last.pose);
    let turn = fusemap_core::geometry::normalize_angle(carried.theta - placed.theta);
    assert!(
        (carried.x - placed.x).abs() < 1e-6 && (carried.y - placed.y).abs() < 1e-6 && turn.abs() < 1e-9,
        "map → odom {m:?} carries {:?} to {carried:?}, the track has {placed:?}",
        last.pose
    );
    assert!(m.x.hypot(m.y) > 0.01, "{m:?}");
}

/// §4.3's leave-one-out maps end to end: with three sensors making the map (the lidar, a
/// twin of it on a second topic, the camera), validate builds one map without each and
/// scores every held-out sensor on it. Leaving out the camera leaves the lidars' map, the
/// same observations in the same order, so the camera scores on it exactly as on M1;
/// leaving out either lidar leaves the same map, the other's identical scans.
#[test]
fn three_mapping_sensors_get_one_map_without_each() {
    let mut s = Scenario::default();
    s.robot.duration_s = 60.0;
    let mut rec = simulate(&s).unwrap();
    let twins: Vec<_> = (rec.messages.iter())
        .filter_map(|m| match m {
            fusemap_sim::SimMessage::Scan(scan) => {
                let mut twin = scan.clone();
                twin.topic = "/scan_twin".into();
                Some(fusemap_sim::SimMessage::Scan(twin))
            }
            _ => None,
        })
        .collect();
    rec.messages.extend(twins);
    rec.messages.sort_by_key(|m| m.stamp());
    let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "validation-leave-one-out");
    fusemap_sim::bag::write_bag(&rec, &dir.join("bag"), true).unwrap();
    // The twin's table is the laser's (its range and shadow filter), under its own name.
    let (start, end) =
        (PRODUCTION_LINE_CONFIG.find("[[sensor]]").unwrap(), PRODUCTION_LINE_CONFIG.find("enabled = true\n").unwrap());
    let laser = &PRODUCTION_LINE_CONFIG[start..end + "enabled = true\n".len()];
    let twin = laser.replace("name = \"laser\"", "name = \"twin\"").replace("\"/scan\"", "\"/scan_twin\"");
    assert!(twin.contains("/scan_twin") && twin.contains("shadow"), "{twin}");
    // Correlated with the camera as the laser is, so either lidar with the camera is merged
    // alike.
    let group = "correlated = [[\"laser\", \"camera\"]]";
    assert!(PRODUCTION_LINE_CONFIG.contains(group));
    let cfg = PRODUCTION_LINE_CONFIG
        .replacen(laser, &format!("{laser}\n{twin}"), 1)
        .replace(group, "correlated = [[\"laser\", \"twin\", \"camera\"]]");
    std::fs::write(dir.join("config.toml"), &cfg).unwrap();
    let job = ValidateJob::plan(Some(&dir.join("config.toml")), &dir.join("bag"), &dir.join("out")).unwrap();
    let v = job.run(&mut |_| {}).unwrap_or_else(|e| panic!("{e}")).validation;
    let names: Vec<&str> = v.maps.iter().map(|m| m.name.as_str()).collect();
    for want in ["m1", "m2", "m3", "without twin", "without laser", "without camera"] {
        assert!(names.contains(&want), "no map `{want}`: {names:?}");
    }
    for m in v.maps.iter().filter(|m| m.name.starts_with("without ")) {
        let left_out = m.name.trim_start_matches("without ");
        assert!(!m.sensors.iter().any(|s| s == left_out), "{m:?}");
        assert_eq!(m.hit_rates.len(), 3, "every held-out sensor is scored on {}: {m:?}", m.name);
    }
    assert_eq!(rate(&v, "without camera", "camera"), rate(&v, "m1", "camera"));
    // The twin's scans are the laser's: the map without one is the map without the other,
    // and every sensor scores the same on both.
    for sensor in ["laser", "twin", "camera"] {
        assert_eq!(rate(&v, "without laser", sensor), rate(&v, "without twin", sensor), "{sensor}");
    }
    // Declared correlated, the twin adds no evidence of its own to M3 (merged, not counted
    // twice): the laser scores on M3 as on the map of one lidar and the camera. (Left out
    // of the group, the twin doubles the lidar's evidence: 0.919 on M3 against 0.893.)
    let (one, both) = (rate(&v, "without twin", "laser"), rate(&v, "m3", "laser"));
    assert!(one > 0.8 && (both - one).abs() < 0.005, "the laser on one lidar's map: {one}, on M3: {both}");
}
