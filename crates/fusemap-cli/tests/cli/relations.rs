//! `fusemap relations`: a trajectory scored against the SLAM benchmark's relations.

use crate::util::{assert_success, one_line_error, run, stdout, temp_dir, write_file};

/// The core's hand-computed case (metrics::relations tests): poses (0, 0, 0°),
/// (1, 0, 90°), (1, 1, 90°) at 1, 2, 3 s; relations whose errors are 0, 0.1 and 0.5 m
/// (mean 0.2 m, population std 0.216025 m) and 10°, 0, 0 (mean 3.333333°, std
/// 4.714045°), plus one relation to a stamp (4 s) the trajectory does not have.
const TUM: &str = "# t x y z qx qy qz qw\n\
    1.0 0 0 0 0 0 0 1\n\
    2.0 1 0 0 0 0 0.707106781186548 0.707106781186548\n\
    3.0 1 1 0 0 0 0.707106781186548 0.707106781186548\n";
const RELATIONS: &str = "1.0 2.0 1.0 0.0 0 0 0 1.3962634015954636\n\
    2.0 3.0 1.0 0.1 0 0 0 0\n\
    1.0 3.0 1.3 1.4 0 0 0 1.5707963267948966\n\
    3.0 4.0 1.0 0.0 0 0 0 0\n";

#[test]
fn relations_prints_the_mean_errors() {
    let dir = temp_dir("relations-ok");
    let tum = write_file(&dir, "track.tum", TUM);
    let rel = write_file(&dir, "case.relations", RELATIONS);
    let args = ["relations", "--relations", rel.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()];
    let o = run(&args);
    assert_success(&o);
    let out = stdout(&o);
    assert!(out.contains("relations        4\n") && out.contains("scored           3\n"), "{out}");
    assert!(out.contains("unmatched        1 "), "{out}");
    assert!(out.contains("translation (m)  0.200000 ± 0.216025  (max 0.500000)"), "{out}");
    assert!(out.contains("rotation (deg)   3.333333 ± 4.714045  (max 10.000000)"), "{out}");

    let o = run(&[&args[..], &["--json"]].concat());
    assert_success(&o);
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    assert_eq!((v["relations"].as_u64(), v["scored"].as_u64(), v["unmatched"].as_u64()), (Some(4), Some(3), Some(1)));
    assert!((v["translation_mean_m"].as_f64().unwrap() - 0.2).abs() < 1e-6, "{v}");
    assert!((v["rotation_sq_mean_deg2"].as_f64().unwrap() - 100.0 / 3.0).abs() < 1e-4, "{v}");
}

#[test]
fn relations_bad_input_names_the_file_and_line() {
    let dir = temp_dir("relations-bad");
    let tum = write_file(&dir, "track.tum", TUM);
    let rel = write_file(&dir, "bad.relations", "1.0 2.0 1.0 0.0 0 0 0 0\n2.0 3.0 1.0 0.1 0 0.2 0 0\n");
    let o = run(&["relations", "--relations", rel.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()]);
    let e = one_line_error(&o);
    assert!(e.contains(&format!("{}:2: roll is 0.2 rad", rel.display())), "{e}");

    // Nothing matches: an error, not a table of NaN.
    let far = write_file(&dir, "far.relations", "100.0 200.0 1.0 0.0 0 0 0 0\n");
    let o = run(&["relations", "--relations", far.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()]);
    let e = one_line_error(&o);
    assert!(e.contains("far.relations: none of its 1 relations") && e.contains("3 poses"), "{e}");

    let args = ["relations", "--relations", rel.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()];
    for bad in ["--tolerance-ms=-1", "--tolerance-ms=NaN"] {
        let e = one_line_error(&run(&[&args[..], &[bad]].concat()));
        assert!(e.contains("--tolerance-ms must be a finite number"), "{bad}: {e}");
    }
}

#[test]
fn relations_interpolate_across_short_gaps_and_score_the_sensor_when_asked() {
    let dir = temp_dir("relations-sensor");
    let tum = write_file(&dir, "track.tum", TUM);
    // Between the samples (1 s apart): the poses at 1.5 s and 2.5 s are (0.5, 0, 45°) and
    // (1, 0.5, 90°), so the motion is (√½, 0, 45°).
    let mid = write_file(&dir, "mid.relations", "1.5 2.5 0.7071067811865476 0 0 0 0 0.7853981633974483\n");
    let args = ["relations", "--relations", mid.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()];
    let e = one_line_error(&run(&args));
    assert!(e.contains("at most 500 ms apart"), "the default gap is shorter than 1 s: {e}");
    let o = run(&[&args[..], &["--max-gap-ms", "1000"]].concat());
    assert_success(&o);
    assert!(stdout(&o).contains("translation (m)  0.000000 ± 0.000000"), "{}", stdout(&o));

    // A sensor 0.5 m ahead of the base: from (0.5, 0, 0°) to (1, 0.5, 90°), the motion
    // (0.5, 0.5, 90°); the base's own motion (1, 0, 90°) is √½ m off it.
    let ahead = write_file(&dir, "ahead.relations", "1.0 2.0 0.5 0.5 0 0 0 1.5707963267948966\n");
    let args = ["relations", "--relations", ahead.to_str().unwrap(), "--trajectory", tum.to_str().unwrap()];
    let o = run(&args);
    assert!(stdout(&o).contains("translation (m)  0.707107"), "{}", stdout(&o));
    let o = run(&[&args[..], &["--sensor-in-base", "0.5,0,0"]].concat());
    assert!(stdout(&o).contains("translation (m)  0.000000"), "{}", stdout(&o));
    let e = one_line_error(&run(&[&args[..], &["--sensor-in-base", "0.5,0"]].concat()));
    assert!(e.contains("--sensor-in-base: `0.5,0` is not three"), "{e}");
}
