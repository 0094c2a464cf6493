//! The output directory holds one complete set: a run that dies half-way through writing
//! (here: killed by a file-size limit, as a full disk would stop it) leaves the previous
//! set whole, the next run cleans up after it, and `summary.json` lists every file of its
//! set with its size and SHA-256; `[output]` chooses the optional formats and what the
//! point clouds hold.

use crate::util::{assert_success, corridor_log, file_names, read_json, repo_file, run, temp_dir, write_file};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

#[test]
fn a_run_killed_while_writing_leaves_the_old_set_and_is_cleaned_up() {
    let dir = temp_dir("output-set");
    let out = dir.join("out");
    let world = repo_file("worlds/corridor.toml");
    assert_success(&run(&["map", "--world", s(&world), "--out", s(&out)]));
    let before: Vec<(String, Vec<u8>)> = file_names(&out)
        .into_iter()
        .filter(|n| !n.starts_with('.'))
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect();
    assert!(before.iter().any(|(n, _)| n == "map.pgm") && before.iter().any(|(n, _)| n == "summary.json"));

    // The summary lists the other files of its set, and they match.
    let summary = read_json(&out.join("summary.json"));
    let listed = summary["files"].as_array().unwrap();
    assert_eq!(listed.len(), before.len() - 1, "{listed:?}");
    for f in listed {
        let name = f["name"].as_str().unwrap();
        let (bytes, sha) = fusemap_io::output_set::digest(&out.join(name)).unwrap();
        assert_eq!(f["bytes"].as_u64(), Some(bytes), "{name}");
        assert_eq!(f["sha256"].as_str(), Some(sha.as_str()), "{name}");
    }

    // A second run of another map into the same directory, stopped by a 16-block file-size
    // limit while it writes its map (SIGXFSZ or EFBIG, as a full disk would stop it).
    let finer = dir.join("finer.toml");
    std::fs::write(&finer, "[map]\nresolution = 0.02\n").unwrap();
    let script = format!(
        "ulimit -f 16; exec '{}' map --config '{}' --world '{}' --out '{}'",
        env!("CARGO_BIN_EXE_fusemap"),
        s(&finer),
        s(&world),
        s(&out)
    );
    let o = std::process::Command::new("sh").args(["-c", &script]).output().unwrap();
    assert!(!o.status.success(), "the limited run succeeded");
    for (name, bytes) in &before {
        assert!(std::fs::read(out.join(name)).unwrap() == *bytes, "{name} changed by the failed run");
    }
    assert!(!file_names(&out).iter().any(|n| !n.starts_with('.') && !before.iter().any(|(b, _)| b == n)));

    // The next run goes ahead (the dead run's lock died with it) and leaves no staging.
    assert_success(&run(&["map", "--config", s(&finer), "--world", s(&world), "--out", s(&out)]));
    let names = file_names(&out);
    assert!(!names.iter().any(|n| n.starts_with(".fusemap-staging")), "{names:?}");
    assert!(std::fs::read(out.join("map.pgm")).unwrap() != before.iter().find(|(n, _)| n == "map.pgm").unwrap().1);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[output]` turns the optional formats off one by one; a second run into the same
/// directory removes the files the first wrote and it does not.
#[test]
fn the_output_table_chooses_the_optional_formats() {
    let dir = temp_dir("output-table");
    let out = dir.join("out");
    assert_success(&run(&["demo", "--corridor", "--out", s(&out)]));
    assert!(["map.mcap", "map.pcd", "map.ply"].iter().all(|f| out.join(f).is_file()));
    let config = write_file(&dir, "c.toml", "[output]\nmcap = false\npcd = false\n");
    assert_success(&run(&["demo", "--corridor", "--config", s(&config), "--out", s(&out)]));
    let names = file_names(&out);
    assert!(names.contains(&"map.ply".to_string()), "{names:?}");
    assert!(!names.contains(&"map.mcap".to_string()) && !names.contains(&"map.pcd".to_string()), "{names:?}");
    let listed: Vec<String> = read_json(&out.join("summary.json"))["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap().to_string())
        .collect();
    assert!(listed.contains(&"map.ply".to_string()) && !listed.contains(&"map.mcap".to_string()), "{listed:?}");
    let config = write_file(&dir, "bad.toml", "[output]\nmcap = \"yes\"\n");
    let line = crate::util::one_line_error(&run(&["demo", "--corridor", "--config", s(&config), "--out", s(&out)]));
    assert!(line.contains("bad.toml:2") && line.contains("expected a boolean"), "{line}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[output] points = "endpoints"`: the point clouds hold every return of a log run as
/// placed, one a cell a scan, each on a wall; a world run keeps the occupied cells and
/// says why.
#[test]
fn endpoint_clouds_hold_the_returns_of_a_log() {
    let dir = temp_dir("endpoint-clouds");
    // A robot driving 5 cm a line along a corridor with walls at y = ±1 m (beams at ±90°
    // see the walls, the rest go to 1/|sin|, capped at 20 m).
    let log = write_file(&dir, "corridor.log", corridor_log(60, 180, 20.0, 3, |i| 0.05 * i as f64));
    let config = write_file(&dir, "c.toml", "[output]\npoints = \"endpoints\"\n");
    let (cells, ends) = (dir.join("cells"), dir.join("ends"));
    assert_success(&run(&["map", "--out", s(&cells), s(&log)]));
    assert_success(&run(&["map", "--config", s(&config), "--out", s(&ends), s(&log)]));
    let count = |p: &Path| {
        let bytes = std::fs::read(p).unwrap();
        let head = String::from_utf8_lossy(&bytes[..200.min(bytes.len())]).to_string();
        let n: usize = head.lines().find_map(|l| l.strip_prefix("element vertex ")).unwrap().parse().unwrap();
        let at = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        let f = |c: &[u8], i: usize| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap());
        let xy: Vec<(f32, f32)> = bytes[at..].chunks_exact(16).map(|c| (f(c, 0), f(c, 1))).collect();
        (n, xy)
    };
    let (n_cells, _) = count(&cells.join("map.ply"));
    let (n_ends, xy) = count(&ends.join("map.ply"));
    assert!(n_ends > 2 * n_cells, "{n_ends} returns kept, {n_cells} occupied cells");
    // Each return is on a wall, or one of the 20 m returns along the corridor's axis.
    let stray: Vec<_> = xy.iter().filter(|(x, y)| (y.abs() - 1.0).abs() > 0.05 && *x < 15.0).collect();
    assert!(
        stray.is_empty(),
        "{} of {} returns off the walls: {:?}",
        stray.len(),
        xy.len(),
        &stray[..5.min(stray.len())]
    );
    let summary = read_json(&ends.join("summary.json"));
    assert!(
        summary["notes"].as_array().unwrap().iter().all(|n| !n.as_str().unwrap().contains("endpoints")),
        "{summary}"
    );
    let world = dir.join("world");
    assert_success(&run(&["demo", "--corridor", "--config", s(&config), "--out", s(&world)]));
    let summary = read_json(&world.join("summary.json"));
    assert!(
        summary["notes"].to_string().contains("points = \\\"endpoints\\\" applies to `fusemap map` on a log"),
        "{summary}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
