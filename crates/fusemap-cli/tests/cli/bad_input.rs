//! Bad input of every kind: config files, world files and logs. Each must end the run
//! with exactly one `error: ` line on stderr (no panic, non-zero exit) that names the
//! file and the field or line, and write no map. Malformed CARMEN records are the
//! exception by design: they are skipped, counted and reported, and the run succeeds.

use crate::util::{
    assert_success, file_names, one_line_error, python_with, read_json, repo_file, run, run_python, stdout, temp_dir,
    write_file,
};
use std::path::{Path, PathBuf};

fn path_str(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

/// Asserts `line` names each of `parts`.
fn assert_names(line: &str, parts: &[&str]) {
    for p in parts {
        assert!(line.contains(p), "the error does not name `{p}`: {line}");
    }
}

/// Asserts no map was written into `out`.
fn assert_no_map(out: &Path) {
    if out.exists() {
        let names = file_names(out);
        assert!(!names.iter().any(|n| n.starts_with("map.")), "a map was written: {names:?}");
    }
}

/// The 1-based line of `text` where `needle` starts.
fn line_of(text: &str, needle: &str) -> usize {
    let at = text.find(needle).unwrap_or_else(|| panic!("`{needle}` not in the text"));
    text[..at].matches('\n').count() + 1
}

// ---------------------------------------------------------------------------------------
// Config files (`--config`), through `fusemap demo`.

/// Writes `text` as a config file, runs `fusemap demo --config` with it and returns the
/// file's path and the error line (which must name the file).
fn config_error(name: &str, text: &str) -> (String, String) {
    let dir = temp_dir(&format!("config-{name}"));
    let config = write_file(&dir, "robot.toml", text);
    let out = dir.join("out");
    let line = one_line_error(&run(&["demo", "--corridor", "--config", path_str(&config), "--out", path_str(&out)]));
    let config = path_str(&config).to_string();
    assert!(line.contains(&config), "the error does not name the config file: {line}");
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
    (config, line)
}

#[test]
fn config_unknown_key_names_it_and_its_line() {
    let (p, line) = config_error("unknown-key", "[map]\nresolutoin = 0.05\n");
    assert_names(&line, &[&format!("{p}:2:"), "resolutoin"]);
}

#[test]
fn config_wrong_type() {
    let (p, line) = config_error("wrong-type", "[map]\nresolution = 0.05\nprior = \"half\"\n");
    assert_names(&line, &[&format!("{p}:3:"), "invalid type", "string"]);
}

#[test]
fn config_p_occ_below_the_prior() {
    let (p, line) = config_error("p-occ", "[map]\nprior = 0.5\n\n[[sensor]]\nkind = \"lidar\"\np_occ = 0.3\n");
    assert_names(&line, &[&format!("{p}:6:"), "sensor[0].p_occ", "prior"]);
}

#[test]
fn config_p_free_above_the_prior() {
    let (p, line) = config_error("p-free", "[[sensor]]\nkind = \"lidar\"\np_occ = 0.9\np_free = 0.6\n");
    assert_names(&line, &[&format!("{p}:4:"), "sensor[0].p_free", "prior"]);
}

#[test]
fn config_min_range_not_below_max_range() {
    let (p, line) = config_error("ranges", "[[sensor]]\nkind = \"lidar\"\nmin_range = 5.0\nmax_range = 5.0\n");
    assert_names(&line, &[&format!("{p}:4:"), "sensor[0].max_range", "min_range"]);
}

#[test]
fn config_resolution_zero_or_negative() {
    for (tag, v) in [("zero", "0"), ("negative", "-0.05")] {
        let (p, line) = config_error(&format!("resolution-{tag}"), &format!("[map]\nresolution = {v}\n"));
        assert_names(&line, &[&format!("{p}:2:"), "map.resolution"]);
    }
}

#[test]
fn config_nan_probability() {
    let (p, line) = config_error("nan-prior", "[map]\nprior = nan\n");
    assert_names(&line, &[&format!("{p}:2:"), "map.prior", "finite"]);
    let (p, line) = config_error("nan-p-occ", "[[sensor]]\nkind = \"lidar\"\np_occ = nan\n");
    assert_names(&line, &[&format!("{p}:3:"), "sensor[0].p_occ", "finite"]);
}

#[test]
fn config_clamp_min_not_below_the_prior() {
    // The rule spans three keys; the error names the table and spells the rule out.
    let (p, line) = config_error("clamp", "[map]\nprior = 0.5\nclamp_min = 0.6\n");
    assert_names(&line, &[&format!("{p}:1:"), "`map`", "clamp_min < prior < clamp_max", "0.6 / 0.5"]);
}

#[test]
fn config_tilted_mount() {
    let (p, line) = config_error(
        "tilt",
        "[[sensor]]\nkind = \"lidar\"\nname = \"laser\"\n\n[sensor.base_from_sensor]\npitch = 0.5\n",
    );
    assert_names(&line, &[&p, "sensor[0].base_from_sensor", "tilted"]);
}

#[test]
fn config_toml_syntax_error_names_the_line() {
    let (p, line) = config_error("syntax", "[map]\nresolution = 0.05\nprior = = 0.5\n");
    assert_names(&line, &[&format!("{p}:3:")]);
}

#[test]
fn config_missing_file_names_the_path() {
    let dir = temp_dir("config-missing");
    let config = dir.join("no-such-config.toml");
    let out = dir.join("out");
    for args in [
        vec!["demo", "--corridor", "--config", path_str(&config), "--out", path_str(&out)],
        vec!["map", "--config", path_str(&config), "--out", path_str(&out), "--world", "unused.toml"],
    ] {
        let line = one_line_error(&run(&args));
        assert_names(&line, &[path_str(&config), "No such file"]);
    }
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// World files (`fusemap map --world`).

fn corridor_text() -> String {
    std::fs::read_to_string(repo_file("worlds/corridor.toml")).unwrap()
}

/// Writes `text` as a world file, runs `fusemap map --world` and returns the file's path
/// and the error line (which must name the file).
fn world_error(name: &str, text: &str) -> (String, String) {
    let dir = temp_dir(&format!("world-{name}"));
    let world = write_file(&dir, "world.toml", text);
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--world", path_str(&world), "--out", path_str(&out)]));
    let world = path_str(&world).to_string();
    assert!(line.contains(&world), "the error does not name the world file: {line}");
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
    (world, line)
}

#[test]
fn world_syntax_error_names_the_line() {
    let text = corridor_text().replace("beams = 181", "beams = = 181");
    let (p, line) = world_error("syntax", &text);
    assert_names(&line, &[&format!("{p}:{}:", line_of(&text, "beams = = 181"))]);
}

#[test]
fn world_unknown_key() {
    let text = corridor_text().replace("rate_hz = 10.0", "rate_hz = 10.0\ncolour = \"red\"");
    let (p, line) = world_error("unknown-key", &text);
    assert_names(&line, &[&format!("{p}:{}:", line_of(&text, "colour")), "colour"]);
}

#[test]
fn world_zero_length_wall_names_it() {
    // The end wall (the third, wall[2]) from (4, 2) to (4, 2).
    let text = corridor_text().replace("from = [4.0, -2.0]\nto = [4.0, 2.0]", "from = [4.0, 2.0]\nto = [4.0, 2.0]");
    assert_ne!(text, corridor_text());
    let (p, line) = world_error("zero-wall", &text);
    assert_names(&line, &[&p, "wall[2]", "zero length"]);
}

#[test]
fn world_without_poses() {
    let corridor = corridor_text();
    let at = corridor.find("[trajectory]").unwrap();
    let text = format!("{}[trajectory]\nposes = []\n", &corridor[..at]);
    let (p, line) = world_error("no-poses", &text);
    assert_names(&line, &[&format!("{p}:{}:", line_of(&text, "poses = []")), "trajectory.poses"]);
    // No [trajectory] at all.
    let (p, line) = world_error("no-trajectory", &corridor[..at]);
    assert_names(&line, &[&p, "trajectory"]);
}

#[test]
fn world_nan_coordinate() {
    let text = corridor_text().replace("from = [4.0, -2.0]", "from = [nan, -2.0]");
    let (p, line) = world_error("nan", &text);
    assert_names(&line, &[&format!("{p}:{}:", line_of(&text, "from = [nan")), "wall[2].from", "finite"]);
}

#[test]
fn world_missing_file_names_the_path() {
    let dir = temp_dir("world-missing");
    let world = dir.join("no-such-world.toml");
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--world", path_str(&world), "--out", path_str(&out)]));
    assert_names(&line, &[path_str(&world), "No such file"]);
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// Logs (`fusemap map LOG` and `fusemap doctor LOG`).

/// Runs `fusemap map --out DIR LOG` and `fusemap doctor LOG`; both must fail with one
/// line naming the log and each of `parts`.
fn log_errors(log: &Path, parts: &[&str]) {
    let out = log.parent().unwrap().join("out");
    let existed = out.exists();
    let map = one_line_error(&run(&["map", "--out", path_str(&out), path_str(log)]));
    let doctor = one_line_error(&run(&["doctor", path_str(log)]));
    for line in [&map, &doctor] {
        assert_eq!(line.matches(path_str(log)).count(), 1, "the error should name the log once: {line}");
        assert_names(line, parts);
    }
    assert_no_map(&out);
    // A run that fails on its input leaves no output directory it made (not even its lock).
    assert!(existed || !out.exists(), "{} was left behind", out.display());
}

#[test]
fn log_empty_file() {
    let dir = temp_dir("log-empty");
    let log = write_file(&dir, "empty.log", b"");
    log_errors(&log, &["empty"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_garbage_bytes() {
    let dir = temp_dir("log-garbage");
    // 4 KiB of xorshift noise: no format's magic, not text.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 56) as u8
        })
        .collect();
    let log = write_file(&dir, "noise.bin", bytes);
    log_errors(&log, &["not a log fusemap reads"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_missing_file() {
    let dir = temp_dir("log-missing");
    log_errors(&dir.join("no-such.log"), &["No such file"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The first `n` bytes of a shared dataset, copied into `dir` as `name`; `None` (after
/// the skip notice) when the datasets are absent.
fn dataset_head(relative: &str, n: usize, dir: &Path, name: &str) -> Option<PathBuf> {
    let Some(src) = fusemap_io::testdata::dataset(relative) else {
        let _ = std::fs::remove_dir_all(dir);
        return None;
    };
    let bytes = std::fs::read(&src).unwrap();
    assert!(bytes.len() > n, "{relative} is shorter than {n} bytes");
    Some(write_file(dir, name, &bytes[..n]))
}

#[test]
fn log_truncated_ros1_bag() {
    let dir = temp_dir("log-bag-cut");
    let Some(log) = dataset_head("rosbag1-slam-benchmark/mit-csail.orig.bag", 100_000, &dir, "cut.bag") else {
        return;
    };
    log_errors(&log, &["truncated"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A gzipped CARMEN log cut short maps the lines before the cut, and says where it ends.
#[test]
fn log_truncated_gzip_carmen_maps_the_lines_before_the_cut() {
    let dir = temp_dir("log-gz-cut");
    let Some(log) = dataset_head("intel/intel-corrected.log.gz", 50_000, &dir, "cut.log.gz") else {
        return;
    };
    let out = dir.join("out");
    let o = run(&["map", "--out", path_str(&out), path_str(&log)]);
    assert_success(&o);
    let s = read_json(&out.join("summary.json"));
    assert!(s["scans"].as_u64().unwrap() > 10, "{}", s["scans"]);
    let notes = s["notes"].to_string();
    assert!(notes.contains("cut short") && notes.contains("gzip stream ends early after line"), "{notes}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_directory_that_is_not_a_rosbag2() {
    let dir = temp_dir("log-dir");
    let bag = dir.join("not-a-bag");
    std::fs::create_dir(&bag).unwrap();
    write_file(&bag, "something.mcap", b"not really");
    log_errors(&bag, &["not a rosbag2", "metadata.yaml"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// FLASER line `i` of a robot driving along a 4 m corridor at 5 cm a line, 10 Hz, every
/// beam at 2 m; its pose `dx` metres off in x (a glitch), its raw odometry `odom_y` off in y
/// (0: a raw log, the pose on the line its odometry).
fn corridor_line(i: usize, dx: f64, odom_y: f64) -> String {
    let ranges = vec!["2.0"; 180].join(" ");
    let (x, t) = (0.05 * i as f64, 1.0 + 0.1 * i as f64);
    format!("FLASER 180 {ranges} {:.2} 0 0 {x:.2} {odom_y} 0 {t:.3} host {t:.3}", x + dx)
}

/// A CARMEN log of 20 good FLASER lines (a robot driving along a 4 m corridor, every
/// beam at 2 m) with one line of too few fields (line 6) and one with a NaN pose (line
/// 11): both are skipped and counted, the rest is mapped.
#[test]
fn log_malformed_carmen_lines_are_skipped_and_counted() {
    let dir = temp_dir("log-carmen-malformed");
    let ranges = vec!["2.0"; 180].join(" ");
    let mut lines: Vec<String> = (0..20).map(|i| corridor_line(i, 0.0, 0.0)).collect();
    lines.insert(5, "FLASER 180 1 2 3 0 0 0 0 0 0 1 h 1".into());
    lines.insert(10, format!("FLASER 180 {ranges} nan 0 0 0 0 0 2.05 host 2.05"));
    let log = write_file(&dir, "corridor.log", lines.join("\n") + "\n");
    let p = path_str(&log);

    let out = dir.join("out");
    let o = run(&["map", "--out", path_str(&out), p]);
    assert_success(&o);
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["source_kind"], "carmen");
    assert_eq!(s["scans"], 20, "every good line is mapped");
    assert_eq!(s["log"]["malformed_records"], 2, "{}", s["log"]);
    let notes = s["notes"].as_array().unwrap();
    let note = notes
        .iter()
        .filter_map(|n| n.as_str())
        .find(|n| n.contains("malformed"))
        .unwrap_or_else(|| panic!("no note on malformed records: {notes:?}"));
    assert_names(note, &["2 malformed records skipped", &format!("{p}:6:"), &format!("{p}:11:"), "nan"]);
    assert!(stdout(&o).contains("2 malformed records skipped"), "{}", stdout(&o));
    assert!(out.join("map.npz").exists());

    // The doctor reads the same log and reports the skipped records too.
    let o = run(&["doctor", p]);
    assert_success(&o);
    assert!(stdout(&o).contains("2 malformed records skipped"), "{}", stdout(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A corrected CARMEN log (pose and odometry differ) whose line 13 carries a pose a
/// kilometre off: the line is rejected as a pose glitch and counted, and the map is the
/// map of the log without that line, byte for byte, not one stretched over a kilometre.
#[test]
fn log_carmen_pose_glitch_is_rejected_and_the_map_is_not_stretched() {
    let dir = temp_dir("log-carmen-glitch");
    let line = |i: usize, dx: f64| corridor_line(i, dx, 0.5);
    let glitched: Vec<String> = (0..40).map(|i| line(i, if i == 12 { 1000.0 } else { 0.0 })).collect();
    let without: Vec<String> = (0..40).filter(|&i| i != 12).map(|i| line(i, 0.0)).collect();
    let mut maps = Vec::new();
    for (name, lines) in [("glitched", &glitched), ("without", &without)] {
        let log = write_file(&dir, &format!("{name}.log"), lines.join("\n") + "\n");
        let out = dir.join(name);
        let o = run(&["map", "--out", path_str(&out), path_str(&log)]);
        assert_success(&o);
        let s = read_json(&out.join("summary.json"));
        let glitches = &s["log"]["pose_track"]["glitches"];
        let skipped = &s["log"]["lidars"][0]["scans_skipped"]["pose_glitch"];
        if name == "glitched" {
            assert_eq!(glitches, 1, "{}", s["log"]["pose_track"]);
            assert_eq!(skipped, 1, "{}", s["log"]["lidars"][0]["scans_skipped"]);
            assert_eq!(s["scans"], 39);
            assert!(stdout(&o).contains("rejected as glitches"), "{}", stdout(&o));
        } else {
            assert_eq!(glitches, 0);
        }
        maps.push((
            std::fs::read(out.join("map.pgm")).unwrap(),
            std::fs::read_to_string(out.join("map.yaml")).unwrap(),
        ));
    }
    assert_eq!(maps[0].1, maps[1].1, "the same origin and size");
    assert!(maps[0].0 == maps[1].0, "the same cells");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Writes a bare MCAP (with the third-party `mcap` writer) holding one
/// `sensor_msgs/msg/LaserScan` on `/scan` whose CDR encapsulation header is 00 00
/// (big-endian).
const BIG_ENDIAN_MCAP: &str = r#"
import sys
from mcap.writer import Writer
with open(sys.argv[1], "wb") as f:
    w = Writer(f)
    w.start(profile="ros2", library="fusemap cli test")
    schema = w.register_schema(name="sensor_msgs/msg/LaserScan", encoding="ros2msg", data=b"")
    channel = w.register_channel(topic="/scan", message_encoding="cdr", schema_id=schema)
    # Encapsulation 00 00 (big-endian CDR), options 00 00, then a body.
    payload = bytes([0x00, 0x00, 0x00, 0x00]) + bytes(64)
    w.add_message(channel_id=channel, log_time=1_000_000_000, publish_time=1_000_000_000, data=payload)
    w.finish()
"#;

/// The ROS 2 reader refuses a big-endian payload with an error at the message; the log
/// pipeline skips and counts such messages, and a log left with no scan fails with one
/// line naming the first undecodable message. The doctor reports it as a finding.
#[test]
fn log_mcap_with_big_endian_cdr() {
    if !python_with(&["mcap"]) {
        return;
    }
    let dir = temp_dir("log-mcap-big-endian");
    let log = dir.join("big-endian.mcap");
    run_python(BIG_ENDIAN_MCAP, &[log.as_os_str()]);
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--out", path_str(&out), path_str(&log)]));
    assert_names(&line, &["no usable laser scans", "message 1 on `/scan`", "sensor_msgs/msg/LaserScan", "big-endian"]);
    assert_no_map(&out);
    // The doctor prints its whole report, and fails as `map` does.
    let o = run(&["doctor", path_str(&log)]);
    assert!(!o.status.success());
    assert_names(&stdout(&o), &["1 malformed records skipped", "big-endian"]);
    assert_names(&crate::util::stderr(&o), &["cannot be mapped", "no usable laser scans"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// What to map.

#[test]
fn map_needs_a_log_or_a_world() {
    let dir = temp_dir("map-nothing");
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--out", path_str(&out)]));
    assert_names(&line, &["nothing to map", "LOG", "--world"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn map_refuses_a_log_and_a_world() {
    let dir = temp_dir("map-both");
    let out = dir.join("out");
    let world = repo_file("worlds/corridor.toml");
    let log = write_file(&dir, "run.log", b"FLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 1.0 host 1.0\n");
    let line = one_line_error(&run(&["map", "--world", path_str(&world), "--out", path_str(&out), path_str(&log)]));
    assert_names(&line, &["either --world", "not both"]);
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `bench --max-scans` with a count whose beams overflow: one clear error, no panic.
#[test]
fn bench_max_scans_overflow_is_an_error() {
    let dir = temp_dir("bench-overflow");
    // A SCAN2D01 file: 2 scans of 3 beams.
    let f = dir.join("a.scan");
    std::fs::write(&f, fusemap_io::testdata::tiny_scanfile_bytes()).unwrap();
    let ok = run(&["bench", "--scanfile", path_str(&f), "--max-scans", "1"]);
    assert_success(&ok);
    let o = run(&["bench", "--scanfile", path_str(&f), "--max-scans", &i64::MAX.to_string()]);
    let line = one_line_error(&o);
    assert_names(&line, &["--max-scans", "overflow"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A FIFO given as the log or the config is refused at once (reading it would block).
#[cfg(unix)]
#[test]
fn a_fifo_as_log_or_config_is_refused() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("pipe");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--out", path_str(&out), path_str(&fifo)]));
    assert_names(&line, &["pipe", "FIFO"]);
    let line = one_line_error(&run(&["demo", "--config", path_str(&fifo), "--out", path_str(&out)]));
    assert_names(&line, &["pipe", "FIFO"]);
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run that observes no cell (every return a no-return) fails with the reason, writes
/// its summary, and removes the map files an earlier run left in the same directory.
#[test]
fn a_run_with_no_map_fails_and_leaves_no_stale_map() {
    let dir = temp_dir("no-map");
    let out = dir.join("out");
    // An earlier, good run into the same directory.
    assert_success(&run(&["map", "--world", path_str(&repo_file("worlds/corridor.toml")), "--out", path_str(&out)]));
    assert!(out.join("map.png").is_file());
    // Three scans whose every beam is CARMEN's no-return (81.91 m): nothing to map.
    let mut text = String::new();
    for i in 0..3 {
        let t = 1.0 + i as f64 * 0.1;
        text.push_str(&format!("FLASER 4 81.91 81.91 81.91 81.91 0 0 0 0 0 0 {t} host {t}\n"));
    }
    let log = write_file(&dir, "empty.log", text);
    let line = one_line_error(&run(&["map", "--out", path_str(&out), path_str(&log)]));
    assert_names(&line, &["no map was written", "3 scans", "summary.json"]);
    assert!(out.join("summary.json").is_file());
    assert_no_map(&out);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Escape sequences and NUL bytes inside a log's tokens never reach the terminal as
/// themselves: the malformed line is reported with its bytes made visible, in `map`'s
/// summary, in `doctor`'s report and in an error line.
#[test]
fn log_strings_are_escaped_before_they_reach_the_terminal() {
    let dir = temp_dir("log-escapes");
    let mut lines: Vec<String> = (0..20).map(|i| corridor_line(i, 0.0, 0.0)).collect();
    // Three readings, the second a token with a terminal title, a clear-screen and a NUL.
    lines.insert(5, "FLASER 3 1.0 \u{1b}]0;pwned\u{7}\u{1b}[2J\0 2.0 0 0 0 0 0 0 1.45 host 1.45".to_string());
    let log = write_file(&dir, "escapes.log", lines.join("\n") + "\n");
    let out = dir.join("out");
    let o = run(&["map", "--out", path_str(&out), path_str(&log)]);
    assert_success(&o);
    let doctor = run(&["doctor", path_str(&log)]);
    assert!(doctor.status.success(), "{}", crate::util::stderr(&doctor));
    for (what, text) in [("map", stdout(&o)), ("doctor", stdout(&doctor))] {
        assert!(text.contains("malformed"), "{what}: {text}");
        assert!(!text.contains('\u{1b}') && !text.contains('\0') && !text.contains('\u{7}'), "{what}: {text:?}");
        assert!(text.contains("\\u{1b}"), "{what} shows the escape as text: {text}");
    }
    // An error line too: the same token in a strict read is not possible from the CLI, so
    // a file name carrying the bytes stands in for it.
    let odd = write_file(&dir, "bad\u{1b}[2Jname.log", "\0\0\0\0");
    let line = one_line_error(&run(&["map", "--out", path_str(&out), path_str(&odd)]));
    assert!(!line.contains('\u{1b}') && line.contains("bad\\u{1b}[2Jname.log"), "{line:?}");
    // And the output directory's name as `map` prints it.
    let odd_out = dir.join("out\u{1b}]0;pwned\u{7}");
    let o = run(&["map", "--out", path_str(&odd_out), path_str(&log)]);
    assert_success(&o);
    let text = stdout(&o);
    assert!(!text.contains('\u{1b}') && text.contains("out\\u{1b}]0;pwned\\u{7}"), "{text:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scan line written twice is one observation: inserted once and counted, and the map is
/// the map of the log without the repeat, byte for byte.
#[test]
fn log_repeated_scans_are_inserted_once() {
    let dir = temp_dir("log-repeats");
    let line = |i: usize| corridor_line(i, 0.0, 0.0);
    let once: Vec<String> = (0..30).map(line).collect();
    let mut twice = once.clone();
    twice.insert(11, line(10));
    twice.insert(21, line(19));
    let mut maps = Vec::new();
    for (name, lines) in [("once", &once), ("twice", &twice)] {
        let log = write_file(&dir, &format!("{name}.log"), lines.join("\n") + "\n");
        let out = dir.join(name);
        let o = run(&["map", "--out", path_str(&out), path_str(&log)]);
        assert_success(&o);
        let s = read_json(&out.join("summary.json"));
        let repeated = s["log"]["lidars"][0]["scans_skipped"]["repeated"].as_u64();
        assert_eq!(repeated, Some(if name == "twice" { 2 } else { 0 }), "{}", s["log"]["lidars"][0]);
        assert_eq!(s["scans"], 30);
        if name == "twice" {
            assert!(stdout(&o).contains("2 scans of `FLASER` repeat the scan before them"), "{}", stdout(&o));
        }
        maps.push(std::fs::read(out.join("map.pgm")).unwrap());
    }
    assert!(maps[0] == maps[1], "the repeats changed the map");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A recording cut short (a ROS 1 bag without its end and index, an MCAP without its
/// end) maps the part before the cut and says where it stopped; the doctor says so too.
#[test]
fn log_cut_short_maps_its_intact_part() {
    let Some(fixtures) = crate::formats::intel_fixtures() else { return };
    let dir = temp_dir("log-cut-short");
    for name in ["ros1.bag", "bare.mcap"] {
        let whole = std::fs::read(fixtures.join(name)).unwrap();
        let cut = write_file(&dir, &format!("cut-{name}"), &whole[..whole.len() * 3 / 5]);
        let (full_out, cut_out) = (dir.join(format!("{name}-whole")), dir.join(format!("{name}-cut")));
        assert_success(&run(&["map", "--out", path_str(&full_out), path_str(&fixtures.join(name))]));
        let o = run(&["map", "--out", path_str(&cut_out), path_str(&cut)]);
        assert_success(&o);
        let (full, part) = (read_json(&full_out.join("summary.json")), read_json(&cut_out.join("summary.json")));
        let (n_full, n_part) = (full["scans"].as_u64().unwrap(), part["scans"].as_u64().unwrap());
        assert!(n_part > n_full / 3 && n_part < n_full, "{name}: {n_part} of {n_full} scans");
        let notes = part["notes"].to_string();
        assert!(notes.contains("cut short") && notes.contains("truncated"), "{name}: {notes}");
        let doctor = run(&["doctor", path_str(&cut)]);
        assert!(doctor.status.success(), "{name}: {}", crate::util::stderr(&doctor));
        assert!(stdout(&doctor).contains("the log is cut short"), "{name}: {}", stdout(&doctor));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
