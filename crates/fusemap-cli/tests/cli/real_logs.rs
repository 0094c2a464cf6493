//! Real logs end to end: every corrected CARMEN log of the shared datasets, and the raw
//! Intel bag, mapped by the CLI and measured.

use crate::util::{assert_success, read_json, run, stdout, temp_dir};
use fusemap_core::grid::{LogOddsTable, OccupancyParams, Ternary};
use fusemap_io::testdata::dataset;

/// (file under datasets/, FLASER lines per PROVENANCE.md)
const CORRECTED: [(&str, u64); 11] = [
    ("intel/intel-corrected.log.gz", 910),
    ("freiburg-079/freiburg-079-corrected.log.gz", 4791),
    ("csail/csail-corrected.log.gz", 406),
    ("aces/aces-corrected.log.gz", 440),
    ("freiburg-campus/freiburg-campus-corrected.log.gz", 2008),
    ("infinite-corridor/infinite-corridor-corrected.log.gz", 1941),
    ("seattle/seattle-corrected.log.gz", 241),
    ("freiburg-101/freiburg-101-corrected.log.gz", 292),
    ("orebro/orebro-corrected.log.gz", 237),
    ("fhw/fhw-corrected.log.gz", 488),
    ("acapulco/acapulco-corrected.log.gz", 861),
];

/// Every corrected log maps with every scan posed from its line, draws walls (a
/// building has many occupied cells, mostly with free space next to them) and leaves a
/// PNG, PGM and npz behind.
#[test]
fn every_corrected_carmen_log_maps() {
    let dir = temp_dir("corrected-logs");
    for (rel, flaser) in CORRECTED {
        let Some(log) = dataset(rel) else { return };
        let name = rel.split('/').next().unwrap();
        let out = dir.join(name);
        let o = run(&["map", "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
        assert_success(&o);
        let s = read_json(&out.join("summary.json"));
        assert_eq!(s["scans"].as_u64(), Some(flaser), "{name}: scans mapped");
        assert_eq!(s["log"]["format"].as_str(), Some("carmen"), "{name}");
        assert_eq!(s["log"]["pose_source"].as_str(), Some("pose on each scan line"), "{name}");
        assert_eq!(s["log"]["malformed_records"].as_u64(), Some(0), "{name}");
        for f in ["map.png", "map.pgm", "map.yaml", "map.npz"] {
            assert!(out.join(f).is_file(), "{name}: {f} missing");
        }

        // Walls: many occupied cells and many observed cells. (Shares of the bounding box
        // say little here: the Infinite Corridor fills 7 % of its box.)
        let occ = fusemap_io::npz::read_npz_f32(&out.join("map.npz"), "occupancy").unwrap();
        let known = match fusemap_io::npz::read_npz(&out.join("map.npz"), "known").unwrap().values {
            fusemap_io::npz::NpyValues::Bool(v) => v,
            other => panic!("known is not bool: {other:?}"),
        };
        let table = LogOddsTable::new(&OccupancyParams::default());
        let occupied =
            (0..known.len()).filter(|&i| known[i] && table.classify(occ.1[i] as f64) == Ternary::Occupied).count();
        let (h, w) = (occ.0[0], occ.0[1]);
        let e = &s["entropy"];
        let (share, entropy) = (e["known_share"].as_f64().unwrap(), e["mean_entropy_nats"].as_f64().unwrap());
        eprintln!("{name}: {w} x {h} cells, {occupied} occupied, known share {share:.3}, entropy {entropy:.3}");
        assert!(occupied > 2000, "{name}: only {occupied} occupied cells");
        let known_cells = e["known_cells"].as_u64().unwrap();
        assert!(known_cells > 50_000 && entropy < 0.69, "{name}: {known_cells} known cells, entropy {entropy}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The raw Intel bag (13,631 scans, bz2 chunks, raw odometry): decoded, posed by SLAM
/// over the odometry interpolated at each scan stamp, and mapped; the pose graph and its
/// picture written.
#[test]
fn intel_raw_bag_maps() {
    let Some(bag) = dataset("rosbag1-slam-benchmark/intel.orig.bag") else { return };
    let dir = temp_dir("intel-bag");
    let o = run(&["map", "--out", dir.to_str().unwrap(), bag.to_str().unwrap()]);
    assert_success(&o);
    let s = read_json(&dir.join("summary.json"));
    let l = &s["log"];
    assert_eq!(l["format"].as_str(), Some("ros1-bag"));
    assert_eq!(l["scans_read"].as_u64(), Some(13631));
    // 646 scans fall in odometry pauses across which the robot moved (see the doctor's
    // snapshot): odometry alone cannot place them, SLAM matches them across the pause, so
    // every scan is mapped.
    assert!(l["pose_source"].as_str().unwrap().starts_with("SLAM"), "{}", l["pose_source"]);
    assert_eq!(l["scans_used"].as_u64(), Some(13631));
    assert_eq!(l["extrinsics"]["source"].as_str(), Some("tf"));
    assert_eq!(s["returns"]["valid"].as_u64().unwrap() + s["returns"]["no_return"].as_u64().unwrap(), 13631 * 180);
    let slam = &l["slam"];
    assert!(slam["counts"]["loop_accepted"].as_u64().unwrap() > 1000, "{}", slam["counts"]);
    // Where the seconds went: every phase of a log run with SLAM, SLAM's as its report has it.
    let sec = &s["seconds"];
    for k in ["read", "estimator", "slam", "map", "outputs", "other", "total"] {
        assert!(sec[k].as_f64().is_some_and(|v| v >= 0.0), "seconds.{k}: {sec}");
    }
    assert_eq!(sec["slam"], slam["seconds"], "{sec}");
    assert_eq!(sec["map"], l["map_s"], "{sec}");
    let edges = slam["edges"].as_array().unwrap();
    assert!(edges.iter().any(|e| e["kind"] == "loop_closure") && edges.iter().any(|e| e["kind"] == "odometry"));
    for f in ["slam.png", "trajectory.tum", "map.png"] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    // The map as ROS 2 messages and point clouds, read by third-party readers, agrees with
    // map.pgm and trajectory.tum; SLAM's loop closures come as markers, and SLAM's
    // correction of the odometry as `map → odom` (the bag's odometry frame).
    if let Some(c) = crate::util::check_map_outputs(&dir) {
        let topics = serde_json::json!(["/map", "/map_points", "/slam/loop_closures", "/tf_static", "/trajectory"]);
        assert_eq!(c["topics"], topics, "{c}");
        assert_eq!(c["tf_static"]["child"], "odom", "{c}");
        assert_eq!(c["pcd_fields"], serde_json::json!(["x", "y", "z", "probability"]), "{c}");
    }
    // The README's benchmark command: every relation finds its scans' poses in
    // trajectory.tum, and the error is the one the SLAM-benchmark test asserts (within 1.5×
    // Cartographer's 0.0229 m; the same code path, so the same figure).
    let Some(relations) = dataset("slam-benchmark-relations/intel.relations") else { return };
    let traj = dir.join("trajectory.tum");
    let o = run(&[
        "relations",
        "--relations",
        relations.to_str().unwrap(),
        "--trajectory",
        traj.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&o);
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    assert_eq!((v["scored"].as_u64(), v["unmatched"].as_u64()), (Some(2984), Some(0)), "{v}");
    let mean = v["translation_mean_m"].as_f64().unwrap();
    assert!(mean <= 1.5 * 0.0229, "{mean} m");
    std::fs::remove_dir_all(&dir).unwrap();
}
