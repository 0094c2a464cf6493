//! `[limits]`: a configuration or a trajectory that would need an absurd amount of memory
//! is refused before the memory is taken, naming the limit, the value met and the key;
//! a map too large for one dense raster is written sparsely; `--crop` exports a region.

use crate::util::{
    assert_success, corridor_log, file_names, one_line_error, read_json, repo_file, run, temp_dir, write_file,
};
use std::path::Path;

/// Which file an error must name.
#[derive(Clone, Copy)]
enum Names {
    Config,
    World,
}

fn s(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

/// Runs the corridor world with `config` and returns the error line, which names `names`
/// (the config or the world file); no map is written.
fn corridor_error(name: &str, config: &str, names: Names) -> String {
    let dir = temp_dir(&format!("limits-{name}"));
    let cfg = write_file(&dir, "robot.toml", config);
    let out = dir.join("out");
    let world = repo_file("worlds/corridor.toml");
    let line = one_line_error(&run(&["map", "--config", s(&cfg), "--world", s(&world), "--out", s(&out)]));
    let file = match names {
        Names::Config => s(&cfg),
        Names::World => s(&world),
    };
    assert!(line.contains(file), "the error does not name {file}: {line}");
    if out.exists() {
        let names = file_names(&out);
        assert!(!names.iter().any(|n| n.starts_with("map.")), "a map was written: {names:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
    line
}

#[test]
fn a_cell_size_that_makes_rays_absurdly_long_is_refused_before_mapping() {
    // The cases: 1e-4 and 1e-5 m grew memory until the allocator aborted; 1e-9 m
    // refused every ray and exited 0 with no map.
    for (res, cells) in [("1e-4", "100000 cells"), ("1e-5", "1000000 cells"), ("1e-9", "10000000000 cells")] {
        let line = corridor_error(&format!("res-{res}"), &format!("[map]\nresolution = {res}\n"), Names::Config);
        for part in ["limits.ray_cells", "max_range = 10 m", "map.resolution", cells, "over the limit of 50000"] {
            assert!(line.contains(part), "{res}: `{part}` missing: {line}");
        }
    }
    let line = corridor_error("range", "[[sensor]]\nkind = \"lidar\"\nmax_range = 1e12\n", Names::Config);
    for part in ["limits.ray_cells", "sensor[0].max_range = 1000000000000 m", "raise limits.ray_cells"] {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    // Raising the limit is what the error says to do, and it is honoured.
    let dir = temp_dir("limits-raised");
    let cfg = write_file(&dir, "robot.toml", "[map]\nresolution = 0.005\n\n[limits]\nray_cells = 2000\n");
    let out = dir.join("out");
    let world = repo_file("worlds/corridor.toml");
    assert_success(&run(&["map", "--config", s(&cfg), "--world", s(&world), "--out", s(&out)]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_map_past_its_cell_budget_stops_the_run_naming_the_limit() {
    // The corridor at 5 cm spans 3 x 2 tiles; one tile is allowed.
    let line = corridor_error("map-cells", "[limits]\nmap_cells = 4096\n", Names::World);
    for part in ["scan 0", "limits.map_cells = 4096", "1 tile(s)", "raise limits.map_cells"] {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    let line = corridor_error("zero", "[limits]\nexport_cells = 0\n", Names::Config);
    assert!(line.contains("limits.export_cells") && line.contains("at least 1"), "{line}");
}

/// The corridor's walls at the origin and again `far` metres away in x and y, with three
/// poses at each site.
fn two_sites(far: f64) -> String {
    let mut w = String::from(
        "[scanner]\nbeams = 181\nangle_min = -1.5707963267948966\nangle_max = 1.5707963267948966\n\
         range_max = 10.0\nrate_hz = 10.0\n",
    );
    for o in [0.0, far] {
        for (a, b) in [([-2.0, 2.0], [4.0, 2.0]), ([-2.0, -2.0], [4.0, -2.0]), ([4.0, -2.0], [4.0, 2.0])] {
            w += &format!("\n[[wall]]\nfrom = [{}, {}]\nto = [{}, {}]\n", o + a[0], o + a[1], o + b[0], o + b[1]);
        }
    }
    w += &format!(
        "\n[trajectory]\nposes = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0], \
         [{far}, {far}, 0.0], [{}, {far}, 0.0], [{}, {far}, 0.0]]\n",
        far + 0.1,
        far + 0.2
    );
    w
}

#[test]
fn two_sites_kilometres_apart_are_written_sparsely_and_a_crop_is_dense() {
    let dir = temp_dir("limits-two-sites");
    // 2 km apart in x and y: the bounding box is 40,000 x 40,000 cells (1.6e9), over the
    // default export budget of 1e8, while the map holds a few dozen tiles.
    let world = write_file(&dir, "world.toml", two_sites(2000.0));
    let out = dir.join("out");
    let o = run(&["map", "--world", s(&world), "--out", s(&out)]);
    assert_success(&o);
    let names = file_names(&out);
    assert!(names.contains(&"map.npz".to_string()) && names.contains(&"map.png".to_string()), "{names:?}");
    assert!(!names.iter().any(|n| n == "map.pgm" || n == "map.yaml"), "{names:?}");
    let summary = read_json(&out.join("summary.json"));
    let notes = summary["notes"].to_string();
    assert!(notes.contains("written sparsely") && notes.contains("limits.export_cells = 100000000"), "{notes}");
    let tiles = summary["map"]["tiles"].as_u64().unwrap();
    assert!(tiles > 0 && tiles < 100, "{tiles} tiles");
    assert!(summary["map"]["width"].as_u64().unwrap() > 40_000, "{}", summary["map"]);
    let keys = fusemap_io::npz::read_npz(&out.join("map.npz"), "tile_keys").unwrap();
    assert_eq!(keys.shape, vec![tiles as usize, 2]);
    let entropy = &summary["entropy"];
    assert!(entropy["known_cells"].as_u64().unwrap() > 0, "{entropy}");

    // A dense raster of the second site, into the same directory: the map_server pair is
    // back and the npz is the dense one.
    let o = run(&["map", "--world", s(&world), "--out", s(&out), "--crop", "1997,1997,2005,2003"]);
    assert_success(&o);
    let summary = read_json(&out.join("summary.json"));
    assert_eq!((summary["map"]["width"].as_u64(), summary["map"]["height"].as_u64()), (Some(161), Some(121)));
    assert!(out.join("map.pgm").exists() && out.join("map.yaml").exists());
    let (shape, _) = fusemap_io::npz::read_npz_f32(&out.join("map.npz"), "log_odds").unwrap();
    assert_eq!(shape, vec![121, 161]);
    assert!(summary["entropy"]["known_cells"].as_u64().unwrap() > 1000);

    // A crop past the export budget is refused before the map is built; the set above stays.
    let line =
        one_line_error(&run(&["map", "--world", s(&world), "--out", s(&out), "--crop", "-1000,-1000,1000,1000"]));
    assert!(line.contains("--crop") && line.contains("limits.export_cells"), "{line}");
    assert!(out.join("map.pgm").exists());
    let o = run(&["map", "--world", s(&world), "--out", s(&out), "--crop", "1,2,3"]);
    let err = crate::util::stderr(&o);
    assert!(!o.status.success() && err.contains("x0,y0,x1,y1") && !err.contains("panicked"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_gzipped_log_of_one_endless_line_stops_at_the_decompression_limit() {
    if !crate::util::python_with(&["gzip"]) {
        return;
    }
    let dir = temp_dir("limits-gzip-line");
    let log = dir.join("bomb.log.gz");
    // One ODOM line, then 64 MiB without a newline (64 KiB compressed).
    crate::util::run_python(
        "import gzip, sys\n\
         with gzip.open(sys.argv[1], 'wb', compresslevel=1) as f:\n\
         \x20   f.write(b'ODOM 0 0 0 0 0 0 1.0 host 1.0\\n')\n\
         \x20   for _ in range(64):\n\
         \x20       f.write(b'9' * (1 << 20))\n",
        &[log.as_os_str()],
    );
    let cfg = write_file(&dir, "robot.toml", "[limits]\ndecompressed_mib = 1\n");
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--config", s(&cfg), "--out", s(&out), s(&log)]));
    for part in [s(&log), ":2:", "limit of 1048576 bytes", "limits.decompressed_mib"] {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_world_pose_1e8_m_off_is_a_counted_glitch_and_the_map_is_the_one_without_it() {
    // The corridor's 40 poses with one replaced by a pose 1e8 m away (the case:
    // it panicked on a capacity overflow), and the same run without that pose at all.
    let corridor = std::fs::read_to_string(repo_file("worlds/corridor.toml")).unwrap();
    let head = &corridor[..corridor.find("[trajectory]").unwrap()];
    let poses = |glitch: bool| {
        let list: Vec<String> = (0..40)
            .filter_map(|i| match (i, glitch) {
                (17, true) => Some("[1e8, -1e8, 0.0]".to_string()),
                (17, false) => None,
                _ => Some(format!("[{:.1}, 0.0, 0.0]", 0.1 * i as f64)),
            })
            .collect();
        format!("{head}[trajectory]\nposes = [{}]\n", list.join(", "))
    };
    let dir = temp_dir("limits-world-glitch");
    let mut maps = Vec::new();
    for glitch in [true, false] {
        let world = write_file(&dir, &format!("world-{glitch}.toml"), poses(glitch));
        let out = dir.join(format!("out-{glitch}"));
        assert_success(&run(&["map", "--world", s(&world), "--out", s(&out)]));
        let summary = read_json(&out.join("summary.json"));
        let notes = summary["notes"].to_string();
        assert_eq!(notes.contains("1 pose sample(s) rejected as glitches"), glitch, "{notes}");
        assert_eq!(summary["scans"].as_u64(), Some(39));
        maps.push(std::fs::read(out.join("map.pgm")).unwrap());
    }
    // The scans are simulated at their own index's time, so the glitch run's later scans are
    // 0.1 s later than the clean run's: the same poses, the same map.
    assert!(maps[0] == maps[1], "the glitch changed the map");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[output] points = "endpoints"` keeps every return of a log until the clouds are
/// written, which grows with the log: past `limits.memory_mib` beside the maps the run
/// stops naming the key, the scan and what to change, and writes no map; the same log
/// and budget map with the occupied cells as points.
#[test]
fn endpoint_clouds_past_the_memory_budget_stop_the_run_naming_the_limit() {
    let dir = temp_dir("limits-endpoints");
    // 3,000 scans of 360 beams along a corridor 2 m wide, driving its first 5 m over and
    // over (back to the start every 100 scans): about 200 returns kept a scan, 80 bytes
    // each (48 MB in all), over a few tiles of map.
    let log = write_file(&dir, "corridor.log", corridor_log(3000, 360, 8.0, 5, |i| 0.05 * (i % 100) as f64));
    let ends = write_file(&dir, "ends.toml", "[output]\npoints = \"endpoints\"\n\n[limits]\nmemory_mib = 16\n");
    let cells = write_file(&dir, "cells.toml", "[output]\npoints = \"cells\"\n\n[limits]\nmemory_mib = 16\n");
    let out = dir.join("out");
    let line = one_line_error(&run(&["map", "--config", s(&ends), "--out", s(&out), s(&log)]));
    for part in
        ["points = \"endpoints\"", "limits.memory_mib = 16 MiB", "at the scan stamped", "raise limits.memory_mib"]
    {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    if out.exists() {
        let names = file_names(&out);
        assert!(!names.iter().any(|n| n.starts_with("map.")), "a map was written: {names:?}");
    }
    assert_success(&run(&["map", "--config", s(&cells), "--out", s(&out), s(&log)]));
    assert!(out.join("map.ply").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
