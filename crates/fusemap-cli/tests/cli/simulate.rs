//! `fusemap simulate` and the multi-sensor log run through the CLI: the production line
//! written as a rosbag2 bag, read back by a third-party reader (rosbags), mapped with the
//! estimator, and the same messages rewritten by rosbags' own writer giving the same map
//! and trajectory byte for byte.

use crate::util::{python, python_with, repo_root, run, stderr, stdout, temp_dir};
use std::path::Path;

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).expect("summary.json")).expect("JSON")
}

#[test]
fn a_simulated_bag_maps_with_the_estimator_and_a_third_party_copy_maps_the_same() {
    let d = temp_dir("simulate");
    let o = run(&["simulate", "--out", d.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for t in [
        "/scan",
        "/odom",
        "/imu/data",
        "/gnss/fix",
        "/tf_static",
        "sensor_msgs/msg/NavSatFix",
        "/camera/labels",
        "/camera/depth",
        "sensor_msgs/msg/CameraInfo",
    ] {
        assert!(text.contains(t), "{t} missing from:\n{text}");
    }
    for f in ["bag/metadata.yaml", "truth.yaml", "truth.pgm", "truth_semantic.yaml", "truth_semantic.png", "truth.tum"]
    {
        assert!(d.join(f).exists(), "{f} missing");
    }
    // Refuses to write over the bag without --overwrite.
    let again = run(&["simulate", "--out", d.to_str().unwrap()]);
    assert!(!again.status.success());

    // The simulator's map frame: ENU at its datum.
    let config = d.join("datum.toml");
    std::fs::write(&config, "[[sensor]]\nkind = \"gnss\"\ndatum = [48.137154, 11.576124, 520.0]\n").unwrap();
    let out = d.join("map");
    let o = run(&[
        "map",
        d.join("bag").to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    let l = &s["log"];
    // The estimator's track, corrected by SLAM (on by default over the estimator).
    assert!(l["pose_source"].as_str().unwrap().contains("over estimator ("), "{}", l["pose_source"]);
    assert_eq!(l["scans_read"], 1800);
    assert_eq!(l["estimator"]["gnss_input"][0]["datum_source"], "config");
    assert!(l["estimator"]["estimator"]["fixes"]["used"].as_u64().unwrap() > 600);
    let tum = std::fs::read_to_string(out.join("trajectory.tum")).expect("trajectory.tum");
    assert!(tum.lines().filter(|l| !l.starts_with('#')).count() > 8000, "one pose per odometry step");

    // A third-party reader: rosbags reads every topic with its type, count and ordered
    // log times; its writer copies the bag.
    if !python_with(&["rosbags.rosbag2"]) {
        return;
    }
    let copy = d.join("rosbags_copy");
    let o = python()
        .arg(repo_root().join("tests/fixtures/rewrite_rosbag2.py"))
        .arg(d.join("bag"))
        .arg(&copy)
        .output()
        .expect("cannot start python");
    assert!(o.status.success(), "rewrite_rosbag2.py failed:\n{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the script's JSON");
    let topics = &r["topics"];
    for (topic, ty, n) in [
        ("/scan", "sensor_msgs/msg/LaserScan", 1800),
        ("/odom", "nav_msgs/msg/Odometry", 9001),
        ("/imu/data", "sensor_msgs/msg/Imu", 18001),
        ("/gnss/fix", "sensor_msgs/msg/NavSatFix", 751),
        ("/tf_static", "tf2_msgs/msg/TFMessage", 1),
        ("/camera/labels", "sensor_msgs/msg/Image", 1801),
        ("/camera/depth", "sensor_msgs/msg/Image", 1801),
        ("/camera/camera_info", "sensor_msgs/msg/CameraInfo", 1801),
    ] {
        assert_eq!(topics[topic]["type"], ty, "{topics}");
        assert_eq!(topics[topic]["count"], n, "{topic}");
        assert_eq!(topics[topic]["ordered"], true, "{topic}");
    }
    // 180 s of scans at 10 Hz, from the scenario's start time.
    assert_eq!(topics["/scan"]["first"], 1_767_225_600_000_000_000u64);
    assert_eq!(topics["/scan"]["last"], 1_767_225_779_900_000_000u64);

    let out2 = d.join("map_copy");
    let o =
        run(&["map", copy.to_str().unwrap(), "--config", config.to_str().unwrap(), "--out", out2.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["map.npz", "trajectory.tum", "map.pgm"] {
        assert_eq!(std::fs::read(out.join(f)).unwrap(), std::fs::read(out2.join(f)).unwrap(), "{f} differs");
    }
}
