//! `fusemap calibrate` on the production line with its ground truth: the lidar's mount
//! (5 cm and 2° off in the configuration), the wheel odometry's scale (the simulator's
//! 3 % error) and wheel base (right) from the lidar's motion against the wheels', and the lidar's clock offset
//! (a bag whose lidar stamps run 40 ms late), and the camera's clock offset and mount yaw
//! against the lidar's map.

use crate::validation::{bag, config, once_per_key, recording, validate, Memo};
use fusemap_core::calibration::Interval;
use fusemap_core::metrics::Verdict;
use fusemap_pipeline::calibrate::{CalibrateJob, Calibration, CALIBRATION_TOML};
use fusemap_pipeline::validate::Validation;
use fusemap_sim::{simulate, Scenario};
use std::path::Path;
use std::sync::OnceLock;

/// Where `calibrate(name, …)` wrote its set.
fn out_dir(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("calibration-{name}")).join("out")
}

/// `calibrate` without its re-validation (two validation passes), which only
/// `the_calibrated_configuration_maps_as_well_as_the_right_one` looks at.
fn calibrate(name: &str, log: &Path, cfg: &str) -> Calibration {
    calibrate_with(name, log, cfg, false)
}

/// `fusemap calibrate` of `log` with `cfg`, once per (log, configuration, re-validation)
/// in this test binary: the on-time bag's calibration serves both clock tests, the wrong
/// lidar mount's both the mount test and the re-validation test. The first caller's `name`
/// names the directory ([`out_dir`]).
fn calibrate_with(name: &str, log: &Path, cfg: &str, revalidate: bool) -> Calibration {
    static MEMO: Memo<Calibration> = OnceLock::new();
    let key = format!("{}\n{revalidate}\n{cfg}", log.display());
    once_per_key(&MEMO, &key, || calibrate_now(name, log, cfg, revalidate))
}

fn calibrate_now(name: &str, log: &Path, cfg: &str, revalidate: bool) -> Calibration {
    let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), &format!("calibration-{name}"));
    let path = dir.join("config.toml");
    std::fs::write(&path, cfg).unwrap();
    let out = dir.join("out");
    let mut job = CalibrateJob::plan(Some(&path), log, &out).unwrap_or_else(|e| panic!("{e}"));
    job.revalidate = revalidate;
    let c = job.run(&mut |_| {}).unwrap_or_else(|e| panic!("{e}")).calibration;
    eprintln!("{name}: {}", serde_json::to_string(&c).unwrap());
    // calibration.toml is a configuration fusemap reads: its lidar table as estimated, but
    // a value whose interval holds the configured one left as configured.
    let toml = out.join(CALIBRATION_TOML);
    let pasted = fusemap_io::config_file::load_config(&toml).unwrap_or_else(|e| panic!("{e}"));
    let m = pasted.sensor[0].base_from_sensor.expect("the corrected mount");
    let yaw = c.sensors[0].yaw.unwrap();
    let configured = fusemap_io::config_file::load_config(&path).unwrap().sensor[0].base_from_sensor.unwrap().yaw;
    assert!(
        m.yaw == yaw.value && !yaw.contains(configured) || m.yaw == configured && yaw.contains(configured),
        "{m:?} {yaw:?}"
    );
    c
}

fn get(
    c: &Calibration,
    kind: &str,
    what: impl Fn(&fusemap_pipeline::calibrate::SensorCalibration) -> Option<Interval>,
) -> Interval {
    let s = c.sensors.iter().find(|s| serde_json::to_value(s.kind).unwrap() == kind).unwrap();
    what(s).unwrap_or_else(|| panic!("no estimate in {}", serde_json::to_string(s).unwrap()))
}

/// The directory name of [`wrong_mount_calibration`].
const WRONG_MOUNT: &str = "lidar-mount";

/// The lidar configured 5 cm and 2° off, calibrated with its re-validation.
fn wrong_mount_calibration() -> Calibration {
    calibrate_with(WRONG_MOUNT, bag(), &config((0.30, 2.0), 0.0), true)
}

#[test]
fn finds_the_lidar_mount_and_the_odometry_scale() {
    let c = wrong_mount_calibration();
    let (x, y, yaw) = (get(&c, "lidar", |s| s.x), get(&c, "lidar", |s| s.y), get(&c, "lidar", |s| s.yaw));
    // The simulator's mount: (0.25, 0, 0°).
    assert!((x.value - 0.25).abs() < 0.01 && y.value.abs() < 0.01, "{x:?} {y:?}");
    assert!(yaw.value.to_degrees().abs() < 0.2, "{yaw:?}");
    let scale = get(&c, "wheel_odometry", |s| s.scale);
    let truth = Scenario::default().odometry.scale_error;
    assert!((scale.value / truth - 1.0).abs() < 0.003, "{scale:?} against {truth}");
    assert!(scale.contains(truth), "{scale:?} against {truth}");
    // The simulator's wheels are where the odometry assumes them.
    let base = get(&c, "wheel_odometry", |s| s.wheel_base);
    assert!(base.contains(1.0) && (base.value - 1.0).abs() < 0.005, "{base:?}");
    // Nothing was left late: the lidar's clock agrees with the odometry's.
    let clock = get(&c, "lidar", |s| s.time_offset_s);
    assert!(clock.contains(0.0), "{clock:?}");
    let lidar = &c.sensors[0];
    assert!(lidar.cost_after < lidar.cost_before);
}

#[test]
fn finds_a_lidar_clock_running_late() {
    let mut scenario = Scenario::default();
    scenario.lidar.time_offset_s = 0.04;
    let rec = simulate(&scenario).expect("the scenario simulates");
    let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "calibration-late-bag");
    let late = dir.join("bag");
    fusemap_sim::bag::write_bag(&rec, &late, true).expect("the bag is written");
    let c = calibrate("lidar-late", &late, &config((0.25, 0.0), 0.0));
    let on_time = calibrate("on-time", bag(), &config((0.25, 0.0), 0.0));
    // Its stamps are 40 ms late: −0.04 s corrects them. The two bags share every noise
    // draw, so the difference of the estimates shows the search's response alone.
    let (late, on_time) = (get(&c, "lidar", |s| s.time_offset_s), get(&on_time, "lidar", |s| s.time_offset_s));
    assert!(late.contains(-0.04) && on_time.contains(0.0), "{late:?} {on_time:?}");
    assert!((late.value - on_time.value + 0.04).abs() < 0.005, "{late:?} {on_time:?}");
}

/// A bag whose camera stamps run 40 ms late, simulated once per test binary.
fn late_camera_bag() -> &'static Path {
    static BAG: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    BAG.get_or_init(|| {
        let mut scenario = Scenario::default();
        scenario.camera.time_offset_s = 0.04;
        let rec = simulate(&scenario).expect("the scenario simulates");
        let dir = fusemap_io::testdata::fixture_dir(env!("CARGO_TARGET_TMPDIR"), "calibration-late-camera-bag");
        let late = dir.join("bag");
        fusemap_sim::bag::write_bag(&rec, &late, true).expect("the bag is written");
        late
    })
}

#[test]
fn finds_a_camera_clock_running_late() {
    let late = calibrate("camera-late", late_camera_bag(), &config((0.25, 0.0), 0.0));
    let on_time = calibrate("on-time", bag(), &config((0.25, 0.0), 0.0));
    let (late, on_time) = (get(&late, "camera", |s| s.time_offset_s), get(&on_time, "camera", |s| s.time_offset_s));
    // The figure: −0.040 s ± 0.005 s for the late one, and the on-time one within
    // as much of 0. The two bags share every noise draw: their difference is the search's
    // response alone.
    assert!((late.value + 0.04).abs() < 0.005, "{late:?}");
    assert!(on_time.value.abs() < 0.005, "{on_time:?}");
    assert!((late.value - on_time.value + 0.04).abs() < 0.005, "{late:?} {on_time:?}");
}

#[test]
fn finds_a_turned_camera_mount() {
    let c = calibrate("camera-yaw", bag(), &config((0.25, 0.0), 5.0));
    let yaw = get(&c, "camera", |s| s.yaw);
    let truth = (-90f64).to_radians();
    assert!((yaw.value - truth).abs() < 0.2f64.to_radians(), "{yaw:?}");
    let camera = c.sensors.iter().find(|s| s.name == "camera").unwrap();
    assert!(camera.cost_after < 0.5 * camera.cost_before, "{camera:?}");
    assert!(!camera.clock_curve.is_empty() && !camera.yaw_curve.is_empty());
}

/// The production line's configuration with the camera 5 cm too high, pitched down 22°
/// instead of 25° and rolled 1.5° about its optical axis.
fn tilted_camera_config() -> String {
    let right = config((0.25, 0.0), 0.0);
    let level = format!("z = 1.0\nroll = {}\npitch = 0.0\n", -(115f64).to_radians());
    let tilted = format!("z = 1.05\nroll = {}\npitch = {}\n", -(112f64).to_radians(), 1.5f64.to_radians());
    assert!(right.contains(&level), "the camera's mount as `config` writes it");
    right.replace(&level, &tilted)
}

/// The camera's height and tilt, configured wrong ([`tilted_camera_config`]), come back
/// from the floor its depth pixels see. (Measured 2026-12-08: z 0.9997 m, roll 0.006° and
/// pitch 0.003° from the truth.)
#[test]
fn finds_the_camera_height_and_tilt_from_the_floor() {
    let c = calibrate("camera-tilt", bag(), &tilted_camera_config());
    let (z, roll, pitch) = (get(&c, "camera", |s| s.z), get(&c, "camera", |s| s.roll), get(&c, "camera", |s| s.pitch));
    assert!((z.value - 1.0).abs() < 0.01, "{z:?}");
    assert!((roll.value + 115f64.to_radians()).abs() < 0.2f64.to_radians(), "{roll:?}");
    assert!(pitch.value.abs() < 0.2f64.to_radians(), "{pitch:?}");
    // The clock and yaw were fitted through the wrong tilt: the run says to fit again.
    let again = |c: &Calibration| c.undetermined.iter().any(|u| u.contains("calibrate again"));
    assert!(again(&c), "{:?}", c.undetermined);
    assert!(!again(&calibrate("on-time", bag(), &config((0.25, 0.0), 0.0))));
    // calibration.toml writes them (the configured values lie outside their intervals).
    let pasted = fusemap_io::config_file::load_config(&out_dir("camera-tilt").join(CALIBRATION_TOML)).unwrap();
    let camera = pasted.sensor.iter().find(|s| s.name.as_deref() == Some("camera")).unwrap();
    let m = camera.base_from_sensor.unwrap();
    assert_eq!((m.z, m.roll, m.pitch), (z.value, roll.value, pitch.value));
}

/// The other figure for the camera's height and tilt, not met: each interval holds
/// the truth. The 95 % intervals (about ±0.1 mm and ±0.004°, a jackknife over runs of
/// frames) hold the frames' random error; the estimates sit 0.3 mm and 0.006° from the
/// truth with the right mount and with the wrong one alike, so the intervals miss by
/// 0.2 mm and 0.002°: an offset the simulated depth or the plane fit carries, not followed.
#[test]
#[ignore = "not met: the camera's floor intervals miss the truth by 0.2 mm and 0.002° (see the doc comment)"]
fn the_camera_floor_intervals_hold_the_truth() {
    for (name, cfg) in [("right", config((0.25, 0.0), 0.0)), ("tilted", tilted_camera_config())] {
        let c = calibrate(&format!("camera-floor-{name}"), bag(), &cfg);
        assert!(get(&c, "camera", |s| s.z).contains(1.0), "{name}");
        assert!(get(&c, "camera", |s| s.roll).contains(-(115f64).to_radians()), "{name}");
        assert!(get(&c, "camera", |s| s.pitch).contains(0.0), "{name}");
    }
}

/// The fused map's F1 of occupied cells against the simulator's truth, mapped with `cfg`.
fn fused_f1(cfg: &fusemap_core::config::Config, truth: &fusemap_sim::SimRecording) -> f64 {
    use fusemap_pipeline::scenario::{score, three_maps, Truth};
    let plan = cfg.clone().validate().unwrap();
    let inv = fusemap_pipeline::recording::Inventory::read(bag()).unwrap();
    let (bound, chosen, track_s) = fusemap_pipeline::run::prepare(&plan, &inv).unwrap();
    let run =
        fusemap_pipeline::map_with_track(&plan, &inv, &bound, chosen, track_s, three_maps(&plan).into(), &mut |_| {})
            .unwrap();
    let (occupancy, semantic) =
        (truth.truth_occupancy(plan.geometry).unwrap(), truth.truth_semantic(plan.geometry).unwrap());
    let t = Truth {
        occupancy: &occupancy,
        semantic: &semantic,
        person: &truth.person_track,
        person_radius_m: truth.person_radius_m,
    };
    score("fused", run.engine.maps().by_name("fused").unwrap().grid(), &plan.classes, &t).occupied.f1
}

/// The acceptance: after calibration the fused F1 is back within 0.01 of the
/// right configuration's, and `validate` with the calibrated configuration is no worse.
/// The lidar is configured 5 cm and 2° off; `calibration.toml`'s tables are pasted over
/// the configuration's (mount and clock of each sensor it names).
///
/// On this bench the wrong mount does not lower the fused F1 (measured 2026-12-06: right
/// 0.5031, wrong 0.5384, calibrated 0.5001; SLAM follows the lidar, so its map stays
/// consistent and only the base's track moves), so the F1 half shows the calibrated
/// configuration is no worse, not that it recovers; the validation half shows it: the
/// wrong mount is named, the calibrated one is not. (This test found the cameras' yaw
/// fitted to a base the wrong lidar mount had turned: pasted beside the corrected lidar,
/// it had turned the camera by the lidar's 2°, and its hit rate on the lidars' map fell
/// from 0.38 to 0.33; turned back with the lidar's correction it is 0.79.)
#[test]
fn the_calibrated_configuration_maps_as_well_as_the_right_one() {
    let parse = |text: &str| fusemap_io::config_file::parse_config_str(text, Path::new("config.toml")).unwrap();
    let (right, wrong) = (parse(&config((0.25, 0.0), 0.0)), parse(&config((0.30, 2.0), 0.0)));
    let c = wrong_mount_calibration();
    // calibrate's own re-validation: named before, not after, and not worse.
    let r = c.revalidation.as_ref().expect("re-validated: the configuration's mounts count");
    assert!(
        r.before.suspect.as_deref() == Some("laser") && r.after.verdict != Verdict::CheckSyncAndExtrinsics && !r.worse,
        "{r:?}"
    );
    let pasted = fusemap_io::config_file::load_config(&out_dir(WRONG_MOUNT).join(CALIBRATION_TOML)).unwrap();
    let mut calibrated = wrong.clone();
    for table in &pasted.sensor {
        let s = calibrated.sensor.iter_mut().find(|s| s.name == table.name && s.kind == table.kind).unwrap();
        s.base_from_sensor = table.base_from_sensor;
        s.time_offset_s = table.time_offset_s;
    }
    let truth = recording();
    let (f_right, f_wrong, f_calibrated) =
        (fused_f1(&right, truth), fused_f1(&wrong, truth), fused_f1(&calibrated, truth));
    eprintln!("fused F1: right {f_right:.4}, wrong {f_wrong:.4}, calibrated {f_calibrated:.4}");
    assert!(f_calibrated > f_right - 0.01, "right {f_right}, wrong {f_wrong}, calibrated {f_calibrated}");
    let text = toml::to_string(&calibrated).unwrap();
    let (before, after) = (validate("before-calibration", &config((0.30, 2.0), 0.0)), validate("calibrated", &text));
    assert_eq!(before.judgement.suspect.as_deref(), Some("laser"), "{}", before.judgement.sentence);
    assert_ne!(after.judgement.verdict, Verdict::CheckSyncAndExtrinsics, "{}", after.judgement.sentence);
    let turn = |v: &Validation| v.lidar_motion[0].agreement.median_deg.abs();
    assert!(turn(&after) < 0.5 && turn(&after) < turn(&before), "{} {}", turn(&after), turn(&before));
}

/// The other figure for the camera, not met: each interval holds the truth.
/// Measured (2026-12-08): 40 ms late, −0.0362 s (−0.0378 .. −0.0346); on time, +0.0038 s
/// (0.0022 .. 0.0054). Both are within the 5 ms `finds_a_camera_clock_running_late` asks,
/// but 4 ms late on both bags, and the intervals are ±1.6 ms.
///
/// Until 2026-12-08 the level was 11 ms late: every point within 0.3 m of a wall pulled the
/// fine searches, which now truncate at 0.1 m (`CameraSearch::fine_reach_m`). What is
/// left is the lidar's map (experiments, not kept, truncated at 0.05 m, which gives the
/// same +0.0036 s as 0.1 m): scored with the simulator's true poses, the 4 ms stays
/// (+0.0049 s); scored on the simulator's true map as well, it goes (−0.0016 s,
/// −0.0040 .. 0.0008). It is not the faces'
/// surface points (the cells' centres give the same +0.004 s, and so do the returns of a
/// face's free neighbours added to its mean), nor glass (+0.0047 s without it); the
/// walls alone give +0.0039 s, the machines +0.0025 s (−0.0057 .. 0.0108). The hall's
/// south and west walls and the two machines' faces are where the simulator puts them in
/// the lidar-only map, to the cell; the pillars (round, 0.4 m across) are where a one-step
/// estimate of the shift along the heading differs most between the two maps (+10 mm on
/// the lidar's, −8 mm on the true one), not followed further. Earlier
/// findings: the camera model's pixel centres were half a pixel off the `CameraInfo`
/// convention (fixed); the camera's obstacle points lie −1 mm from the walls on average
/// with true poses; SLAM off and a track within 1 ms of the truth change nothing. The
/// mount yaw comes out 0.068° off with it (0.099° before): laps turn one way, so a clock
/// error turns the points as a yaw error would.
#[test]
#[ignore = "not met: the camera's clock comes out 4 ms late on both bags, outside its ±1.6 ms intervals (see the doc comment)"]
fn the_camera_clock_interval_holds_the_truth() {
    let late = calibrate("camera-late-abs", late_camera_bag(), &config((0.25, 0.0), 0.0));
    let on_time = calibrate("camera-on-time-abs", bag(), &config((0.25, 0.0), 0.0));
    let (late, on_time) = (get(&late, "camera", |s| s.time_offset_s), get(&on_time, "camera", |s| s.time_offset_s));
    assert!(late.contains(-0.04), "{late:?}");
    assert!(on_time.contains(0.0), "{on_time:?}");
}

/// The figure, not met: every interval contains the truth. Measured (2026-12-06):
/// with the right mount, x 0.2429 m (0.2393 .. 0.2473) misses 0.25 by 0.3 mm and yaw
/// −0.048° (−0.086 .. −0.006) misses 0° by 0.006°; with the wrong one, y −0.0057 m
/// (−0.0099 .. −0.0021) misses 0 by 2 mm and yaw 0.043° (0.007 .. 0.089) misses 0° by
/// 0.007°. The estimates are within 1 cm and 0.2°; the intervals are too narrow by a bias
/// of a few millimetres the fit does not model.
#[test]
#[ignore = "not met: some intervals miss the truth by millimetres (see the doc comment)"]
fn every_interval_contains_the_true_mount() {
    for (name, lidar) in [("right", (0.25, 0.0)), ("wrong", (0.30, 2.0))] {
        let c = calibrate(&format!("coverage-{name}"), bag(), &config(lidar, 0.0));
        assert!(get(&c, "lidar", |s| s.x).contains(0.25), "{name}");
        assert!(get(&c, "lidar", |s| s.y).contains(0.0), "{name}");
        assert!(get(&c, "lidar", |s| s.yaw).contains(0.0), "{name}");
    }
}
