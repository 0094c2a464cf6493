//! Pose-sensor values no receiver or gyro can produce (a latitude of 91°, a fix status
//! NavSatFix does not define, a yaw rate of 10³⁰ rad/s, a lone first fix a thousand
//! kilometres off, fixes too imprecise to ever give the heading): each is dropped and
//! counted by reason, the run maps with the rest, and the track stays where the clean
//! log's is, measured against the simulator's truth.

use fusemap_core::config::{Config, PoseSource, SensorConfig, SensorKind, SlamMode};
use fusemap_core::geometry::Pose2;
use fusemap_core::time::Stamp;
use fusemap_pipeline::{map_log, MapRun};
use fusemap_sim::{simulate, Scenario, SimMessage, SimRecording};

fn short_run() -> SimRecording {
    let mut s = Scenario::default();
    s.robot.duration_s = 40.0;
    simulate(&s).expect("a 40 s scenario simulates")
}

/// The estimator's track alone (no SLAM), so what the pose sensors did is what is scored.
fn estimator_only(datum: Option<&SimRecording>) -> Config {
    let mut cfg = Config::default();
    cfg.log.pose_source = PoseSource::Estimator;
    cfg.slam.mode = SlamMode::Off;
    if let Some(rec) = datum {
        // The simulator's map frame: ENU at its datum, so tracks compare with the truth.
        let d = &rec.datum;
        cfg.sensor.push(SensorConfig {
            datum: Some([d.latitude(), d.longitude(), d.altitude()]),
            ..SensorConfig::new(SensorKind::Gnss)
        });
    }
    cfg
}

fn map(rec: &SimRecording, tag: &str, cfg: &Config) -> MapRun {
    let dir = fusemap_io::testdata::temp_dir(tag);
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(rec, &bag, true).expect("the bag is written");
    let plan = cfg.validate().expect("valid config");
    map_log(&plan, &bag, &mut |_| {}).unwrap_or_else(|e| panic!("{tag}: the log maps: {e}"))
}

/// RMS distance of `track` from the truth at the truth's stamps inside the track.
fn ate(track: &[(Stamp, Pose2)], truth: &[(Stamp, Pose2)]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (t, p) in truth {
        let i = track.partition_point(|(s, _)| s < t);
        if i == 0 || i == track.len() {
            continue;
        }
        let ((ta, a), (tb, b)) = (track[i - 1], track[i]);
        let w = t.secs_since(ta) / tb.secs_since(ta).max(1e-9);
        let (x, y) = (a.x + w * (b.x - a.x), a.y + w * (b.y - a.y));
        sum += (x - p.x).powi(2) + (y - p.y).powi(2);
        n += 1;
    }
    assert!(n > 100, "the track covers the truth ({n} stamps)");
    (sum / n as f64).sqrt()
}

fn gnss_report(run: &MapRun) -> serde_json::Value {
    serde_json::to_value(&run.report).unwrap()["estimator"]["gnss_input"][0].clone()
}

#[test]
fn fixes_outside_the_earth_or_the_message_definition_are_dropped_and_counted() {
    let mut rec = short_run();
    let (mut fixes, mut off_earth) = (0u64, 0u64);
    for m in &mut rec.messages {
        if let SimMessage::Fix(f) = m {
            fixes += 1;
            off_earth += u64::from(fixes % 4 < 2);
            match fixes % 4 {
                0 => f.latitude = 91.0,
                1 => f.latitude = 1e308,
                2 => f.status.status = 5,
                _ => f.position_covariance_type = 9,
            }
        }
    }
    // Without a datum in the config: no fix is left to give one.
    let run = map(&rec, "implausible-fixes", &estimator_only(None));
    let g = gnss_report(&run);
    println!("{g}");
    assert_eq!(g["out_of_range"], off_earth, "{g}");
    assert_eq!(g["invalid_field"], fixes - off_earth, "{g}");
    assert_eq!(g["passed"], 0, "{g}");
    assert!(run.notes.iter().any(|n| n.contains("outside the Earth's ranges")), "{:?}", run.notes);
    assert!(run.report.scans_used > 350, "{}", run.report.scans_used);
}

#[test]
fn an_altitude_outside_the_configured_band_is_a_receiver_fault() {
    let rec = short_run();
    let mut cfg = estimator_only(None);
    cfg.sensor.push(SensorConfig { altitude_range_m: Some([-10.0, 10.0]), ..SensorConfig::new(SensorKind::Gnss) });
    let run = map(&rec, "altitude-band", &cfg);
    let g = gnss_report(&run);
    let alt = rec.datum.altitude();
    assert!(alt > 10.0, "the simulated site is above the band ({alt} m)");
    assert_eq!(g["out_of_range"], g["read"], "{g}");
    // The doctor judges the fixes by the same band: none of them is usable.
    let dir = fusemap_io::testdata::temp_dir("altitude-band-doctor");
    fusemap_sim::bag::write_bag(&rec, &dir.join("bag"), true).expect("the bag is written");
    let report = fusemap_pipeline::doctor::report(&cfg.validate().unwrap(), &dir.join("bag")).unwrap();
    assert!(report.text.contains("no usable fix at all"), "{}", report.text);
    let bad = Config {
        sensor: vec![SensorConfig { altitude_range_m: Some([5.0, -5.0]), ..SensorConfig::new(SensorKind::Gnss) }],
        ..Config::default()
    };
    let e = bad.validate().unwrap_err();
    assert!(e.to_string().contains("sensor[0].altitude_range_m"), "{e}");
}

#[test]
fn a_gyro_rate_no_gyro_can_measure_is_dropped_and_the_track_is_unchanged() {
    let clean = short_run();
    let mut bad = clean.clone();
    let mut imus = 0;
    for m in &mut bad.messages {
        if let SimMessage::Imu(i) = m {
            imus += 1;
            if imus == 500 {
                i.angular_velocity = [0.0, 0.0, 1e30].into();
            }
        }
    }
    let cfg = estimator_only(Some(&clean));
    let a = map(&clean, "gyro-clean", &cfg);
    let b = map(&bad, "gyro-1e30", &cfg);
    let e = &serde_json::to_value(&b.report).unwrap()["estimator"]["estimator"];
    assert_eq!(e["gyro"]["implausible"], 1, "{}", e["gyro"]);
    let (ate_a, ate_b) = (ate(&a.trajectory, &clean.truth_trajectory), ate(&b.trajectory, &clean.truth_trajectory));
    println!("ATE clean {ate_a:.4} m, with a 1e30 rad/s sample {ate_b:.4} m");
    assert!(ate_b < ate_a + 0.01, "clean {ate_a:.4} m, with the bad sample {ate_b:.4} m");
}

#[test]
fn a_lone_first_fix_far_away_is_neither_the_datum_nor_the_start() {
    let clean = short_run();
    let mut bad = clean.clone();
    let first = bad.messages.iter_mut().find_map(|m| if let SimMessage::Fix(f) = m { Some(f) } else { None });
    first.expect("the run has fixes").latitude += 9.0; // about 1,000 km north
    let cfg = estimator_only(None);
    let a = map(&clean, "datum-clean", &cfg);
    let b = map(&bad, "datum-far-first-fix", &cfg);
    let (ga, gb) = (gnss_report(&a), gnss_report(&b));
    println!("clean {ga}\nfar first fix {gb}");
    assert_eq!(ga["datum_source"], "first good fix");
    assert_eq!(gb["datum_source"], "first consistent fix");
    assert_eq!(gb["contradicted"], 1, "{gb}");
    let (da, db) = (ga["datum"].as_array().unwrap(), gb["datum"].as_array().unwrap());
    let north_m = (db[0].as_f64().unwrap() - da[0].as_f64().unwrap()) * 111_320.0;
    assert!(north_m.abs() < 20.0, "the datum is a good fix, {north_m:.1} m from the clean log's");
    assert!(b.notes.iter().any(|n| n.contains("disagree with the fixes after them")), "{:?}", b.notes);
    // Both tracks are in ENU frames a few metres apart: compare their shapes through the
    // first pose.
    let shift = |run: &MapRun| {
        let p0 = run.trajectory[0].1;
        run.trajectory.iter().map(|(t, p)| (*t, Pose2::new(p.x - p0.x, p.y - p0.y, p.theta))).collect::<Vec<_>>()
    };
    let (sa, sb) = (shift(&a), shift(&b));
    let d = ate(&sb, &sa);
    println!("clean and far-first-fix tracks differ by {d:.3} m RMS");
    assert!(d < 0.5, "{d:.3} m");
}

#[test]
fn fixes_that_jump_111_m_and_stay_are_not_followed() {
    // From 20 s on every fix is 0.001° (111 m) north: the fixes agree with each other, so
    // the gate's reset would take them, but no odometry drifts 111 m in 20 s.
    let clean = short_run();
    let mut bad = clean.clone();
    let start = clean.messages.iter().map(|m| m.stamp()).min().expect("the run has messages");
    for m in &mut bad.messages {
        let late = m.stamp().secs_since(start) > 20.0;
        if let (SimMessage::Fix(f), true) = (m, late) {
            f.latitude += 0.001;
        }
    }
    let cfg = estimator_only(Some(&clean));
    let a = map(&clean, "jump-clean", &cfg);
    let b = map(&bad, "jump-111m", &cfg);
    let e = &serde_json::to_value(&b.report).unwrap()["estimator"]["estimator"];
    assert_eq!(e["gate_resets_refused"], 1, "one jump, counted once: {e}");
    assert!(b.notes.iter().any(|n| n.contains("a jump of the receiver, not followed")), "{:?}", b.notes);
    let (ate_a, ate_b) = (ate(&a.trajectory, &clean.truth_trajectory), ate(&b.trajectory, &clean.truth_trajectory));
    println!("ATE clean {ate_a:.4} m, fixes 111 m off from 20 s {ate_b:.4} m");
    assert!(ate_b < ate_a + 0.1, "clean {ate_a:.4} m, with the jump {ate_b:.4} m");
}

/// The IMU's messages given an orientation: the true heading with an attitude filter's
/// jitter (±0.1 mrad; 1 mrad σ claimed) until `frozen_after_s`, then the heading of that
/// moment, repeated.
fn with_orientation(rec: &SimRecording, frozen_after_s: f64) -> SimRecording {
    let mut out = rec.clone();
    let truth = &rec.truth_trajectory;
    let start = truth[0].0;
    let yaw_at = |t: Stamp| truth[truth.partition_point(|(s, _)| *s < t).min(truth.len() - 1)].1.theta;
    let frozen = yaw_at(Stamp(start.0 + (frozen_after_s * 1e9) as i64));
    for (k, m) in out.messages.iter_mut().enumerate() {
        if let SimMessage::Imu(i) = m {
            let t = i.header.stamp;
            let jitter = 1e-4 * ((k * 7919) % 200) as f64 / 100.0 - 1e-4;
            let yaw = if t.secs_since(start) < frozen_after_s { yaw_at(t) + jitter } else { frozen };
            i.orientation = fusemap_sim::rpy_to_quaternion(0.0, 0.0, yaw).into();
            i.orientation_covariance = [1e-6, 0.0, 0.0, 0.0, 1e-6, 0.0, 0.0, 0.0, 1e-6];
        }
    }
    out
}

#[test]
fn an_imu_orientation_frozen_while_the_gyro_turns_is_left_out() {
    let clean = short_run();
    let mut cfg = estimator_only(Some(&clean));
    cfg.sensor.push(SensorConfig { use_orientation: Some(true), ..SensorConfig::new(SensorKind::Imu) });
    let good = map(&with_orientation(&clean, 1e9), "orientation-good", &cfg);
    let frozen = map(&with_orientation(&clean, 10.0), "orientation-frozen", &cfg);
    let truth = &clean.truth_trajectory;
    let (a, b) = (ate(&good.trajectory, truth), ate(&frozen.trajectory, truth));
    let note = frozen.notes.iter().find(|n| n.contains("orientation readings left out as stale"));
    println!("ATE with the true orientation {a:.4} m, frozen from 10 s {b:.4} m; {note:?}");
    assert!(!good.notes.iter().any(|n| n.contains("stale")), "{:?}", good.notes);
    // The readings claim σ = 1 mrad, below the floor: raised to it, and counted.
    let floor = good.notes.iter().find(|n| n.contains("below estimator.imu_heading_floor_sigma_rad"));
    assert!(floor.is_some_and(|n| n.contains("0.11°")), "{:?}", good.notes);
    assert!(note.is_some(), "{:?}", frozen.notes);
    assert!(b < a + 0.02, "true orientation {a:.4} m, frozen {b:.4} m");
}

/// An orientation whose covariance is all zeros ("unknown", REP 145) is used with
/// `estimator.fallback_heading_sigma_rad`, counted as a fallback, not dropped.
#[test]
fn an_imu_orientation_of_unknown_covariance_gets_the_fallback_sigma() {
    let clean = short_run();
    let mut rec = with_orientation(&clean, 1e9);
    for m in rec.messages.iter_mut() {
        if let SimMessage::Imu(i) = m {
            i.orientation_covariance = [0.0; 9];
        }
    }
    let mut cfg = estimator_only(Some(&clean));
    cfg.sensor.push(SensorConfig { use_orientation: Some(true), ..SensorConfig::new(SensorKind::Imu) });
    let run = map(&rec, "orientation-unknown-covariance", &cfg);
    let report = serde_json::to_value(&run.report).unwrap();
    let headings = &report["estimator"]["estimator"]["headings"];
    println!("{headings}");
    assert!(headings["received"].as_u64().unwrap() > 100, "{headings}");
    assert_eq!(headings["covariance_fallbacks"], headings["received"], "{headings}");
    assert!(!run.notes.iter().any(|n| n.contains("imu_heading_floor_sigma_rad")), "{:?}", run.notes);
    assert!(ate(&run.trajectory, &clean.truth_trajectory) < 0.05);
}

#[test]
fn fixes_too_imprecise_to_give_the_heading_are_dropped_with_a_note() {
    let mut rec = short_run();
    for m in &mut rec.messages {
        if let SimMessage::Fix(f) = m {
            f.position_covariance = [1e6, 0.0, 0.0, 0.0, 1e6, 0.0, 0.0, 0.0, 1e6];
            f.position_covariance_type = 2;
        }
    }
    let run = map(&rec, "imprecise-fixes", &estimator_only(None));
    assert!(run.notes.iter().any(|n| n.contains("never made the heading observable")), "{:?}", run.notes);
    assert!(run.report.scans_used > 350, "{}", run.report.scans_used);
}
