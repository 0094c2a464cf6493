//! Broken pose-sensor messages in a real bag: NavSatFix with NaN coordinates, a zero
//! covariance or `NO_FIX`, an IMU with NaN rates, odometry with a zero quaternion, a TF
//! loop, and a GNSS topic with no fix at all. Each is counted with its reason; the run
//! still maps, and never panics.

use fusemap_core::config::{Config, SensorConfig, SensorKind};
use fusemap_pipeline::map_log;
use fusemap_sim::{simulate, Scenario, SimMessage, SimRecording, SimStaticTransform};

fn short_run() -> SimRecording {
    let mut s = Scenario::default();
    s.robot.duration_s = 40.0;
    simulate(&s).expect("a 40 s scenario simulates")
}

fn map(
    rec: &SimRecording,
    tag: &str,
    cfg: &Config,
) -> Result<fusemap_pipeline::MapRun, fusemap_pipeline::PipelineError> {
    let dir = fusemap_io::testdata::temp_dir(tag);
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(rec, &bag, true).expect("the bag is written");
    let plan = cfg.validate().expect("valid config");
    map_log(&plan, &bag, &mut |_| {})
}

#[test]
fn broken_messages_are_counted_and_the_log_still_maps() {
    let mut rec = short_run();
    let (mut fixes, mut imus, mut odoms) = (0, 0, 0);
    for m in &mut rec.messages {
        match m {
            SimMessage::Fix(f) => {
                fixes += 1;
                match fixes % 10 {
                    1 => f.latitude = f64::NAN,
                    2 => f.position_covariance = [0.0; 9],
                    3 => f.status.status = -1,
                    _ => {}
                }
            }
            SimMessage::Imu(i) => {
                imus += 1;
                if imus % 50 == 0 {
                    i.angular_velocity = [f64::NAN; 3].into();
                }
            }
            SimMessage::Odometry(o) => {
                odoms += 1;
                if odoms % 100 == 0 {
                    o.pose.pose.orientation = [0.0; 4].into();
                }
            }
            _ => {}
        }
    }
    // A loop in the frame tree: laser → a → laser.
    let t = rec.messages[0].stamp();
    for (parent, child) in [("laser", "loop_a"), ("loop_a", "laser")] {
        rec.messages.insert(
            0,
            SimMessage::StaticTransform(SimStaticTransform::from_mount(
                t,
                "/tf_static",
                parent,
                child,
                &fusemap_core::geometry::Mount3 { x: 0.1, ..Default::default() },
            )),
        );
    }
    let run = map(&rec, "bad-pose-sensors", &Config::default()).expect("the log still maps");
    let l = serde_json::to_value(&run.report).unwrap();
    let g = &l["estimator"]["gnss_input"][0];
    println!("gnss input: {g}");
    assert_eq!(g["not_finite"], fixes / 10 + u64::from(fixes % 10 >= 1));
    assert_eq!(g["no_fix"], fixes / 10 + u64::from(fixes % 10 >= 3));
    assert!(g["unknown_covariance"].as_u64().unwrap() >= fixes / 10, "a zero covariance is not trusted: {g}");
    let e = &l["estimator"]["estimator"];
    println!("odometry: {}, gyro: {}", e["odometry"], e["gyro"]);
    assert!(e["odometry"]["not_finite"].as_u64().unwrap() >= odoms / 100, "{}", e["odometry"]);
    assert!(e["gyro"]["not_finite"].as_u64().unwrap() >= imus / 50, "{}", e["gyro"]);
    assert!(l["frames"]["rejected"]["loops"].as_u64().unwrap() >= 1, "{}", l["frames"]["rejected"]);
    assert!(run.notes.iter().any(|n| n.contains("refused by the frame tree")), "{:?}", run.notes);
    assert!(l["scans_used"].as_u64().unwrap() > 350, "{}", l["scans_used"]);
}

#[test]
fn a_gnss_topic_without_a_fix_says_so_and_maps_on_odometry_and_gyro() {
    let mut rec = short_run();
    for m in &mut rec.messages {
        if let SimMessage::Fix(f) = m {
            f.status.status = -1;
            f.latitude = f64::NAN;
        }
    }
    let run = map(&rec, "gnss-no-fix", &Config::default()).expect("maps without fixes");
    assert!(run.notes.iter().any(|n| n.contains("no usable fix and no datum configured")), "{:?}", run.notes);
    // The estimator (odometry and gyro here), corrected by SLAM as by default.
    assert!(run.report.pose_source.contains("over estimator"), "{}", run.report.pose_source);
    assert!(run.report.scans_used > 350);

    // With a datum configured the fixes are still all NO_FIX: counted, none used.
    let mut cfg = Config::default();
    cfg.sensor.push(SensorConfig { datum: Some([48.1, 11.5, 500.0]), ..SensorConfig::new(SensorKind::Gnss) });
    let run = map(&rec, "gnss-no-fix-datum", &cfg).expect("maps");
    let l = serde_json::to_value(&run.report).unwrap();
    assert_eq!(l["estimator"]["gnss_input"][0]["passed"], 0);
    assert!(l["estimator"]["gnss_input"][0]["no_fix"].as_u64().unwrap() > 100);
}

/// An IMU that reports its orientation (REP 145: a covariance, not −1) gives the
/// estimator absolute headings, rotated from the IMU's frame into base_link by its mount.
#[test]
fn imu_orientation_is_used_when_the_message_provides_it() {
    let mut rec = short_run();
    let truth = rec.truth_trajectory.clone();
    let at = |t: fusemap_core::time::Stamp| {
        let i = truth.partition_point(|(s, _)| *s < t).min(truth.len() - 1);
        truth[i].1.theta
    };
    for m in &mut rec.messages {
        if let SimMessage::Imu(i) = m {
            let yaw = at(i.header.stamp);
            i.orientation = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()].into();
            i.orientation_covariance = [1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-4];
        }
    }
    let run = map(&rec, "imu-orientation", &Config::default()).expect("maps");
    let l = serde_json::to_value(&run.report).unwrap();
    let e = &l["estimator"]["estimator"];
    println!("headings: {}, init: {}", e["headings"], e["heading_init"]);
    assert!(e["headings"]["used"].as_u64().unwrap() > 1000, "{}", e["headings"]);
    assert_eq!(e["heading_init"]["source"]["kind"], "imu_heading", "{}", e["heading_init"]);
}

/// One odometry sample a kilometre off (a real driver glitch) is rejected and counted, on
/// the odometry track and in the estimator's input alike: the map is the map of the same
/// log without it, not one stretched to cover a kilometre.
#[test]
fn one_odometry_glitch_maps_like_the_log_without_it() {
    use fusemap_core::config::{PoseSource, SlamMode};
    use fusemap_core::grid::CellIndex;
    use fusemap_core::metrics::Confusion;
    let clean = short_run();
    let mut glitched = clean.clone();
    let mut odoms = 0;
    for m in &mut glitched.messages {
        if let SimMessage::Odometry(o) = m {
            odoms += 1;
            if odoms == 300 {
                o.pose.pose.position.x += 1000.0;
            }
        }
    }
    for (source, slam) in [(PoseSource::Odometry, SlamMode::Off), (PoseSource::Estimator, SlamMode::Off)] {
        let mut cfg = Config::default();
        cfg.log.pose_source = source;
        cfg.slam.mode = slam;
        let a = map(&clean, "glitch-clean", &cfg).expect("the clean log maps");
        let b = map(&glitched, "glitch-one", &cfg).expect("the glitched log maps");
        assert_eq!(a.report.pose_track.glitches, 0, "{source:?}");
        assert_eq!(b.report.pose_track.glitches, 1, "{source:?}");
        assert!(b.notes.iter().any(|n| n.contains("rejected as glitches")), "{:?}", b.notes);
        let (ga, gb) = (a.engine.grid(), b.engine.grid());
        let (ba, bb) = (ga.known_box().unwrap(), gb.known_box().unwrap());
        assert!(
            (ba.min.x - bb.min.x).abs() <= 2
                && (ba.min.y - bb.min.y).abs() <= 2
                && (ba.max.x - bb.max.x).abs() <= 2
                && (ba.max.y - bb.max.y).abs() <= 2,
            "{source:?}: {ba:?} vs {bb:?}"
        );
        let occupied = |g: &fusemap_core::grid::FusionGrid, c| g.log_odds(c).is_some_and(|l| l > 0.0);
        let pairs = (ba.min.y..=ba.max.y)
            .flat_map(|y| (ba.min.x..=ba.max.x).map(move |x| CellIndex::new(x, y)))
            .map(|c| (occupied(ga, c), occupied(gb, c)));
        let f1 = Confusion::from_pairs(pairs).f1();
        println!("{source:?}: occupied cells F1 with and without the glitch {f1:.4}");
        assert!(f1 > 0.98, "{source:?}: F1 {f1}");
    }
}
