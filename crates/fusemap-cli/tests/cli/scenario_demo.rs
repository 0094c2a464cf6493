//! `fusemap demo`: the design document's scenario through the real binary — the
//! production line simulated, mapped lidar-only, camera-only and fused, scored and drawn —
//! checked on the files a user gets.

use crate::util::{assert_success, fusemap, python_with, read_json, run_python, stdout, temp_dir};

const NUMPY_SCRIPT: &str = r#"
import json, sys
import numpy as np
z = np.load(sys.argv[1])
names = [str(n) for n in z["semantic_class_names"]]
cls = z["semantic_class"]
print(json.dumps({
    "shape": list(z["occupancy"].shape),
    "class_shape": list(cls.shape),
    "class_dtype": str(cls.dtype),
    "probs_shape": list(z["semantic_probs"].shape),
    "names": names,
    "dynamic_shape": list(z["dynamic"].shape),
    "wall_cells": int((cls == names.index("wall")).sum()),
}))
"#;

#[test]
fn the_scenario_demo_writes_three_scored_maps_and_their_layers() {
    let dir = temp_dir("scenario-demo");
    let out = dir.join("out");
    // Two threads, so the three maps are updated in parallel (checked below against one).
    let o = fusemap().env("RAYON_NUM_THREADS", "2").args(["demo", "--out", out.to_str().unwrap()]).output().unwrap();
    assert_success(&o);
    for f in [
        "map.npz",
        "map.pgm",
        "map.yaml",
        "map.png",
        "semantic.png",
        "semantic.yaml",
        "dynamic.png",
        "summary.json",
        "trajectory.tum",
        "comparison.png",
        "lidar/map.png",
        "camera/map.png",
        "camera/semantic.yaml",
        "sim/truth.yaml",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(out.join("sim/bag/metadata.yaml").is_file());
    assert!(!out.join("lidar/semantic.yaml").exists(), "a lidar-only map has no semantic layer");
    let text = stdout(&o);
    assert!(text.contains("fused") && text.contains("comparison"), "{text}");
    assert!(text.contains(&out.join("lidar").display().to_string()) && !text.contains("//"), "{text}");

    let summary = read_json(&out.join("summary.json"));
    let scores = summary["log"]["scenario_scores"].as_array().unwrap();
    let f1 = |name: &str| scores.iter().find(|s| s["name"] == name).unwrap()["occupied"]["f1"].as_f64().unwrap();
    assert!(f1("fused") > f1("lidar") && f1("fused") > f1("camera"), "{scores:?}");
    let frames = summary["log"]["cameras"][0]["frames_used"].as_u64().unwrap();
    assert!(frames > 1000);
    // Scans are the lidar's, camera frames are counted apart (the bag has 1,800 scans).
    assert_eq!(summary["scans"], summary["log"]["scans_used"]);
    assert_eq!(summary["scans"], 1800);
    assert_eq!(summary["camera_frames"], frames);
    assert!(text.contains("scans         1800\n") && text.contains(&format!("camera frames {frames}\n")), "{text}");

    let yaml = std::fs::read_to_string(out.join("semantic.yaml")).unwrap();
    assert!(yaml.contains("image: semantic.png") && yaml.contains("name: wall"), "{yaml}");
    // What the semantic picture shows is there: the floor in front of the glass fence is
    // no longer shown as glass (11,078 cells before the picture was masked by occupancy
    // and confidence, for 401 true glass cells; 505 shown now, 74 % of them glass).
    let glass = &scores.iter().find(|s| s["name"] == "fused").unwrap()["class_precision"]["glass"];
    let (shown, precision) = (glass["shown"].as_u64().unwrap(), glass["precision"].as_f64().unwrap());
    assert!(shown < 1000 && precision > 0.6, "{glass}");
    assert!(text.contains("shown glass (precision)"), "{text}");

    let png = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(out.join("comparison.png")).unwrap()));
    let info = png.read_info().unwrap();
    let (w, h) = (info.info().width, info.info().height);
    assert!(w > 4 * h, "five panels side by side: {w} x {h}");

    // map.mcap, map.pcd and map.ply through third-party readers: /map's cells are
    // map.pgm's, /trajectory has trajectory.tum's poses, the points are the occupied
    // cells, and the camera's layers and classes come along.
    if let Some(c) = crate::util::check_map_outputs(&out) {
        let topics = ["/map", "/map/dynamic", "/map/semantic", "/map_points", "/slam/loop_closures", "/trajectory"];
        assert_eq!(c["topics"], serde_json::json!(topics), "{c}");
        assert_eq!(c["pcd_fields"], serde_json::json!(["x", "y", "z", "probability", "class", "rgb"]), "{c}");
        assert!(c["poses"].as_u64().unwrap() > 1000, "{c}");
    }

    if python_with(&["numpy"]) {
        let npz = out.join("map.npz");
        let js: serde_json::Value =
            serde_json::from_str(&run_python(NUMPY_SCRIPT, &[npz.as_os_str()])).expect("the script prints JSON");
        assert_eq!(js["class_shape"], js["shape"]);
        assert_eq!(js["dynamic_shape"], js["shape"]);
        assert_eq!(js["class_dtype"], "int16");
        assert_eq!(js["probs_shape"][2], 8);
        assert!(js["wall_cells"].as_u64().unwrap() > 1000, "{js}");
    }

    // On one thread (RAYON_NUM_THREADS=1: SLAM's joins and the maps of the pass one after
    // the other) the demo writes the same maps, layers and trajectory, byte for byte.
    let one = dir.join("one");
    let o1 = fusemap().env("RAYON_NUM_THREADS", "1").args(["demo", "--out", one.to_str().unwrap()]).output().unwrap();
    assert_success(&o1);
    for f in ["map.npz", "lidar/map.npz", "camera/map.npz", "trajectory.tum", "semantic.png", "sim/bag/bag_0.mcap"] {
        let (a, b) = (std::fs::read(out.join(f)).unwrap(), std::fs::read(one.join(f)).unwrap());
        assert!(a == b, "{f} differs between 2 threads and 1");
    }
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}
