//! The TF pose source through the frame tree: with a localiser's `map → odom` above the
//! odometry's `odom → base_link`, the track is their composition at each scan's stamp.

use fusemap_core::config::{Config, PoseSource};
use fusemap_io::log::ros2::msgs::geometry_msgs::{Transform, TransformStamped};
use fusemap_io::log::ros2::msgs::std_msgs::Header;
use fusemap_io::log::ros2::writer::{OutMessage, Rosbag2Writer, Rosbag2WriterOptions};
use fusemap_io::testdata::TestPath;
use fusemap_pipeline::map_log;
use fusemap_sim::bag::to_out_message;
use fusemap_sim::{simulate, Scenario, SimMessage};

fn tf(stamp: fusemap_core::time::Stamp, parent: &str, child: &str, x: f64, y: f64, yaw: f64) -> OutMessage {
    OutMessage::Tf {
        is_static: false,
        transforms: vec![TransformStamped {
            header: Header { stamp, frame_id: parent.into() },
            child_frame_id: child.into(),
            transform: Transform {
                translation: [x, y, 0.0].into(),
                rotation: [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()].into(),
            },
        }],
    }
}

/// Writes the 20 s production line with its odometry as TF only: `odom → BASE` from each
/// odometry message, plus `map → odom` (10 m east, turned 90°) at 10 Hz when `localiser`,
/// plus a static `base_footprint → base_link` when BASE is `/base_footprint`.
fn bag_with_tf(tag: &str, base: &str, localiser: bool) -> TestPath {
    bag_with_tf_glitch(tag, base, localiser, None)
}

/// [`bag_with_tf`], with the `odom → BASE` sample number `glitch` a kilometre off.
fn bag_with_tf_glitch(tag: &str, base: &str, localiser: bool, glitch: Option<usize>) -> TestPath {
    let mut s = Scenario::default();
    s.robot.duration_s = 20.0;
    let rec = simulate(&s).unwrap();
    let bag = fusemap_io::testdata::temp_dir(tag).into_child("bag");
    let mut w =
        Rosbag2Writer::create_with(&bag, Rosbag2WriterOptions { overwrite: true, ..Default::default() }).unwrap();
    let mut n_odom = 0;
    for m in &rec.messages {
        match m {
            SimMessage::Scan(_) | SimMessage::StaticTransform(_) => {
                w.write(m.stamp(), m.topic(), &to_out_message(m)).unwrap()
            }
            SimMessage::Odometry(o) => {
                // odom → base_link from the odometry, and a localiser's map → odom at 10 Hz:
                // 10 m east, turned 90°.
                let yaw = fusemap_core::geometry::quaternion_yaw(o.pose.pose.orientation.to_array());
                let off = if glitch == Some(n_odom) { 1000.0 } else { 0.0 };
                let p = o.pose.pose.position;
                let odom_tf = tf(o.header.stamp, "odom", base, p.x + off, p.y, yaw);
                w.write(o.header.stamp, "/tf", &odom_tf).unwrap();
                if n_odom == 0 && base != "base_link" {
                    let mut t = tf(o.header.stamp, base, "base_link", 0.0, 0.0, 0.0);
                    if let OutMessage::Tf { is_static, .. } = &mut t {
                        *is_static = true;
                    }
                    w.write(o.header.stamp, "/tf_static", &t).unwrap();
                }
                if localiser && n_odom % 5 == 0 {
                    w.write(
                        o.header.stamp,
                        "/tf",
                        &tf(o.header.stamp, "map", "odom", 10.0, 0.0, std::f64::consts::FRAC_PI_2),
                    )
                    .unwrap();
                }
                n_odom += 1;
            }
            _ => {}
        }
    }
    w.finish().unwrap();
    bag
}

#[test]
fn map_odom_and_base_compose_at_each_stamp() {
    let bag = bag_with_tf("tf-chain", "base_link", true);
    let mut cfg = Config::default();
    cfg.log.pose_source = PoseSource::Tf;
    let run = map_log(&cfg.validate().unwrap(), &bag, &mut |_| {}).unwrap();
    assert!(run.report.pose_source.contains("map → … → base_link"), "{}", run.report.pose_source);
    assert!(run.report.scans_used > 190, "{}", run.report.scans_used);
    // The first pose: odometry starts at the origin, so map_from_base = map_from_odom.
    let (_, p) = run.trajectory[0];
    assert!((p.x - 10.0).abs() < 1e-6 && p.y.abs() < 1e-6, "{p:?}");
    assert!((p.theta - std::f64::consts::FRAC_PI_2).abs() < 1e-6, "{p:?}");
    // Later, the odometry's forward motion (east in odom) shows as north in map.
    let (_, q) = run.trajectory[run.trajectory.len() / 2];
    assert!(q.y > 3.0 && (q.x - 10.0).abs() < 1.0, "{q:?}");
}

/// `odom → /base_footprint` on /tf (a ROS 1 leading slash) and a static `base_footprint →
/// base_link`, no odometry topic: `auto` finds the chain and maps with it.
#[test]
fn a_static_edge_under_the_dynamic_one_and_a_leading_slash_are_followed() {
    let bag = bag_with_tf("tf-footprint", "/base_footprint", false);
    let run = map_log(&Config::default().validate().unwrap(), &bag, &mut |_| {}).unwrap();
    // TF under `odom` is odometry: SLAM corrects it by default.
    assert!(run.report.pose_source.contains("over TF `odom → … → base_link`"), "{}", run.report.pose_source);
    assert!(run.report.scans_used > 190, "{}", run.report.scans_used);
    assert!(run.trajectory.len() > 900, "{}", run.trajectory.len());
}

/// One `odom → base_link` sample a kilometre off under a localiser's `map → odom`: the
/// glitch is left out of the chain and counted, and the track is the one without it.
#[test]
fn a_glitch_on_one_edge_of_a_chain_is_left_out() {
    let mut cfg = Config::default();
    cfg.log.pose_source = PoseSource::Tf;
    cfg.slam.mode = fusemap_core::config::SlamMode::Off;
    let plan = cfg.validate().unwrap();
    let clean = map_log(&plan, &bag_with_tf("tf-chain-clean", "base_link", true), &mut |_| {}).unwrap();
    let glitched =
        map_log(&plan, &bag_with_tf_glitch("tf-chain-glitch", "base_link", true, Some(300)), &mut |_| {}).unwrap();
    assert_eq!(glitched.report.pose_track.glitches, 1, "{:?}", glitched.report.pose_track);
    assert_eq!(clean.report.pose_track.glitches, 0);
    assert!(glitched.notes.iter().any(|n| n.contains("1 pose sample(s) rejected as glitches")), "{:?}", glitched.notes);
    assert_eq!(glitched.report.scans_used, clean.report.scans_used);
    // Where the glitch was, the chain interpolates its neighbours (50 Hz odometry): the
    // track stays within a centimetre of the clean one everywhere.
    assert_eq!(glitched.trajectory.len(), clean.trajectory.len());
    let worst = clean
        .trajectory
        .iter()
        .zip(&glitched.trajectory)
        .map(|((ta, a), (tb, b))| {
            assert_eq!(ta, tb);
            (a.x - b.x).hypot(a.y - b.y)
        })
        .fold(0.0, f64::max);
    assert!(worst < 0.01, "the track moved by {worst} m");
}

/// map.mcap's `/tf_static` gives `map → odom` only where the log does not: with a
/// localiser's `map → odom` on the log's /tf above the wheel odometry's `odom` frame, a
/// second parent would break the tree a player of both files builds, so there is none, and
/// a note says why. (The log without it gets one: `validation.rs`.)
#[test]
fn a_log_whose_tf_already_parents_the_odometry_frame_gets_no_second_parent() {
    let mut s = Scenario::default();
    s.robot.duration_s = 20.0;
    let rec = simulate(&s).unwrap();
    let bag = fusemap_io::testdata::temp_dir("tf-localised-odometry").into_child("bag");
    let mut w =
        Rosbag2Writer::create_with(&bag, Rosbag2WriterOptions { overwrite: true, ..Default::default() }).unwrap();
    // Scans and wheel odometry only: the pose source is the odometry, in its `odom` frame.
    let kept = rec
        .messages
        .iter()
        .filter(|m| matches!(m, SimMessage::Scan(_) | SimMessage::Odometry(_) | SimMessage::StaticTransform(_)));
    for (k, m) in kept.enumerate() {
        w.write(m.stamp(), m.topic(), &to_out_message(m)).unwrap();
        if matches!(m, SimMessage::Odometry(_)) && k % 5 == 0 {
            w.write(m.stamp(), "/tf", &tf(m.stamp(), "map", "odom", 10.0, 0.0, std::f64::consts::FRAC_PI_2)).unwrap();
        }
    }
    w.finish().unwrap();
    let run = map_log(&Config::default().validate().unwrap(), &bag, &mut |_| {}).unwrap();
    assert!(run.report.pose_source.contains("over odometry"), "{}", run.report.pose_source);
    assert_eq!(run.map_from_odom, None);
    let note = "map.mcap has no /tf_static: the log's TF already gives `odom` a parent";
    assert!(run.notes.iter().any(|n| n.contains(note)), "{:?}", run.notes);
}
