//! `fusemap validate` and `fusemap calibrate` through the binary: a lidar-only log gets
//! the maps it can have and says which it cannot build; a log too short to hold a training
//! period out is refused with the reason; calibration names what a log without wheel
//! odometry cannot determine. (The figures against ground truth are `fusemap-pipeline`'s
//! `--test pipeline validation` and `calibration`.)

use crate::util::{assert_success, read_json, run, stdout, temp_dir, write_file};
use fusemap_io::npz::read_npz_f32;

/// FLASER line `i` of a robot driving 5 cm a line along a corridor 1 m wide on either side
/// (beams at ±90° see the walls, the rest go to 1/|sin|), each range a few millimetres of
/// noise off (a scan repeating the one before bit for bit is a frozen driver's).
fn corridor(i: usize) -> String {
    let ranges: Vec<String> = (0..180)
        .map(|k| {
            let a = (k as f64 - 89.5).to_radians();
            let noise = 0.002 * ((i * 7 + k * 13) % 5) as f64;
            format!("{:.3}", (1.0 / a.sin().abs()).min(20.0) + noise)
        })
        .collect();
    let (x, t) = (0.05 * i as f64, 1.0 + 0.1 * i as f64);
    format!("FLASER 180 {} {x:.2} 0 0 {x:.2} 0 0 {t:.3} host {t:.3}", ranges.join(" "))
}

#[test]
fn a_lidar_only_log_gets_the_maps_it_can_have() {
    let dir = temp_dir("validate-lidar-only");
    let lines: Vec<String> = (0..100).map(corridor).collect();
    let log = write_file(&dir, "corridor.log", lines.join("\n") + "\n");
    let out = dir.join("out");
    let o = run(&["validate", "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
    assert_success(&o);
    let text = stdout(&o);
    assert!(text.contains("verdict       no_gain: one kind of map evidence only"), "{text}");
    let v = read_json(&out.join("summary.json"))["validation"].clone();
    let names: Vec<&str> = v["maps"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["m1", "m3"], "{v}");
    assert!(v["not_built"][0].as_str().unwrap().starts_with("m2: no camera is mapped"), "{v}");
    // 30 of the 100 scans held out, their returns on the walls the first 70 mapped.
    assert_eq!(v["held_out"][0]["observations"], 30, "{v}");
    let m1 = &v["maps"][0]["hit_rates"][0];
    assert!(m1["rate"].as_f64().unwrap() > 0.5, "{v}");
    assert_eq!(v["verdict"], "no_gain");
    let npz = out.join("fusion_validate.npz");
    let (shape, m2) = read_npz_f32(&npz, "m2").unwrap();
    let (shape1, m1) = read_npz_f32(&npz, "m1").unwrap();
    assert_eq!(shape, shape1);
    assert!(m2.iter().all(|p| p.is_nan()) && m1.iter().any(|p| *p > 0.8));
    let (_, entropy) = fusemap_io::npz::read_npz(&npz, "entropy").map(|a| (a.shape, a.values)).unwrap();
    assert!(matches!(entropy, fusemap_io::npz::NpyValues::F64(e) if e[1].is_nan() && e[0] == e[2]));
}

#[test]
fn a_log_too_short_to_hold_out_is_refused_with_the_reason() {
    let dir = temp_dir("validate-short");
    let log = write_file(&dir, "one.log", corridor(0) + "\n");
    let out = dir.join("out");
    let o = run(&["validate", "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = crate::util::one_line_error(&o);
    assert!(e.contains("one.log") && e.contains("nothing to validate") && e.contains("shorter than"), "{e}");
}

#[test]
fn calibrate_names_what_a_log_cannot_determine() {
    let dir = temp_dir("calibrate-carmen");
    let lines: Vec<String> = (0..100).map(corridor).collect();
    let log = write_file(&dir, "corridor.log", lines.join("\n") + "\n");
    let out = dir.join("out");
    let o = run(&["calibrate", "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
    assert_success(&o);
    let text = stdout(&o);
    assert!(
        text.contains("undetermined  the lidar's mount and the odometry's scale: the log has no wheel-odometry topic"),
        "{text}"
    );
    let c = read_json(&out.join("summary.json"))["calibration"].clone();
    assert_eq!(c["sensors"].as_array().unwrap().len(), 0, "{c}");
    assert!(!out.join("calibration.toml").exists(), "nothing estimated, nothing to paste");
    assert!(out.join("map.npz").is_file());
}

/// A config kept in the output directory under a name the set owns is an input: the run
/// refuses instead of removing it at its commit.
#[test]
fn a_config_named_like_an_output_is_never_removed() {
    let dir = temp_dir("calibration-toml-input");
    let lines: Vec<String> = (0..30).map(corridor).collect();
    let log = write_file(&dir, "corridor.log", lines.join("\n") + "\n");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let config = write_file(&out, "calibration.toml", "[map]\n");
    for cmd in ["map", "validate", "calibrate"] {
        let o =
            run(&[cmd, "--config", config.to_str().unwrap(), "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
        assert!(!o.status.success(), "{cmd}");
        let e = crate::util::one_line_error(&o);
        assert!(e.contains("calibration.toml"), "{cmd}: {e}");
        assert_eq!(std::fs::read_to_string(&config).unwrap(), "[map]\n", "{cmd}");
    }
}
