//! `fusemap demo`: the design document's corridor (§3.1, §3.3) through the real binary,
//! checked on the files a user gets: the npz against the known walls, the same npz
//! through NumPy, the map_server pair and the PNG against the npz, `fusemap map` on the
//! corridor world against `demo`, and the CLI's behaviour around them (help, progress
//! bar, inputs never overwritten, no temp files left).

use crate::util::{
    assert_success, file_names, python_with, read_json, repo_file, run, run_python, stdout, temp_dir, write_file,
};
use fusemap_core::grid::Ternary;
use fusemap_io::npz::{read_npz, NpyValues};
use fusemap_io::testdata::TestPath;
use std::path::Path;
use std::process::Output;

/// Runs `fusemap demo --out <temp>/out` and returns the output directory and the run.
fn demo(name: &str) -> (TestPath, Output) {
    let out = temp_dir(name).into_child("out");
    let o = run(&["demo", "--corridor", "--out", path_str(&out)]);
    assert_success(&o);
    (out, o)
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

/// A map as `map.npz` holds it, read with fusemap-io's reader.
struct NpzMap {
    width: usize,
    height: usize,
    resolution: f64,
    origin: [f64; 2],
    occupancy: Vec<f32>,
    log_odds: Vec<f32>,
    known: Vec<bool>,
}

impl NpzMap {
    fn read(path: &Path) -> Self {
        let (shape, occupancy) = fusemap_io::npz::read_npz_f32(path, "occupancy").unwrap();
        let (lo_shape, log_odds) = fusemap_io::npz::read_npz_f32(path, "log_odds").unwrap();
        assert_eq!(shape.len(), 2, "occupancy is 2-D");
        assert_eq!(lo_shape, shape, "log_odds has occupancy's shape");
        let known = read_npz(path, "known").unwrap();
        assert_eq!(known.shape, shape, "known has occupancy's shape");
        let NpyValues::Bool(known) = known.values else { panic!("known is not bool") };
        let res = read_npz(path, "resolution").unwrap();
        assert!(res.shape.is_empty(), "resolution is a 0-d array, got shape {:?}", res.shape);
        let NpyValues::F64(res) = res.values else { panic!("resolution is not float64") };
        let origin = read_npz(path, "origin").unwrap();
        assert_eq!(origin.shape, [2]);
        let NpyValues::F64(origin) = origin.values else { panic!("origin is not float64") };
        Self {
            width: shape[1],
            height: shape[0],
            resolution: res[0],
            origin: [origin[0], origin[1]],
            occupancy,
            log_odds,
            known,
        }
    }

    /// Column of the cell containing world `x`.
    fn col(&self, x: f64) -> usize {
        let c = ((x - self.origin[0]) / self.resolution).floor();
        assert!(c >= 0.0 && (c as usize) < self.width, "x = {x} is outside the raster");
        c as usize
    }

    /// Row of the cell containing world `y` (row 0 = lowest y).
    fn row(&self, y: f64) -> usize {
        let r = ((y - self.origin[1]) / self.resolution).floor();
        assert!(r >= 0.0 && (r as usize) < self.height, "y = {y} is outside the raster");
        r as usize
    }

    fn index(&self, col: usize, row: usize) -> usize {
        row * self.width + col
    }

    /// Index of the cell containing world `(x, y)`.
    fn at(&self, x: f64, y: f64) -> usize {
        self.index(self.col(x), self.row(y))
    }

    /// World centre of cell `(col, row)`.
    fn center(&self, col: usize, row: usize) -> (f64, f64) {
        (self.origin[0] + (col as f64 + 0.5) * self.resolution, self.origin[1] + (row as f64 + 0.5) * self.resolution)
    }

    /// Occupied / free / unknown as the exporters classify (map_server's 0.65, the
    /// config's free threshold 0.25, unknown where never observed).
    fn ternary(&self, i: usize) -> Ternary {
        let p = self.occupancy[i];
        if !self.known[i] {
            Ternary::Unknown
        } else if p > 0.65 {
            Ternary::Occupied
        } else if p < 0.25 {
            Ternary::Free
        } else {
            Ternary::Unknown
        }
    }
}

/// A world point (x, y), metres.
type Point = (f64, f64);

/// Points on the corridor's walls within the scanned field, one per cell step: the side
/// walls y = ±2 for x ∈ [0.5, 4] and the end wall x = 4 for |y| < 2 (as
/// crates/fusemap-core/tests/core/corridor.rs takes them). Returns (side, end).
fn wall_points(res: f64) -> (Vec<Point>, Vec<Point>) {
    let mut side = Vec::new();
    let n = (3.5 / res).round() as i64;
    for i in 0..=n {
        let x = 0.5 + i as f64 * res;
        side.push((x, 2.0));
        side.push((x, -2.0));
    }
    let m = (4.0 / res).round() as i64;
    let end = (1..m).map(|j| (4.0, -2.0 + j as f64 * res)).collect();
    (side, end)
}

/// A binary PGM: (width, height, pixels, top row first).
fn read_pgm(path: &Path) -> (usize, usize, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    // Header: magic, width, height, maxval, each separated by whitespace; `#` comments
    // run to the end of their line; one whitespace byte before the pixels.
    let mut tokens = Vec::new();
    let mut i = 0;
    while tokens.len() < 4 {
        match bytes[i] {
            b'#' => {
                while bytes[i] != b'\n' {
                    i += 1;
                }
            }
            c if c.is_ascii_whitespace() => i += 1,
            _ => {
                let start = i;
                while !bytes[i].is_ascii_whitespace() {
                    i += 1;
                }
                tokens.push(String::from_utf8(bytes[start..i].to_vec()).unwrap());
            }
        }
    }
    assert_eq!(tokens[0], "P5", "{}: not a binary PGM", path.display());
    assert_eq!(tokens[3], "255");
    let (w, h): (usize, usize) = (tokens[1].parse().unwrap(), tokens[2].parse().unwrap());
    let pixels = bytes[i + 1..].to_vec();
    assert_eq!(pixels.len(), w * h, "{}: pixel count", path.display());
    (w, h, pixels)
}

/// A grayscale 8-bit PNG: (width, height, pixels, top row first).
fn read_png(path: &Path) -> (usize, usize, Vec<u8>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// Every output written, summary.json with the run's figures, the summary on stdout,
/// nothing on stderr (off a terminal, progress is a line every 20 s), no temp file left.
#[test]
fn demo_writes_every_output_and_prints_its_summary() {
    let (out, o) = demo("demo-outputs");
    // The lock a run takes on its directory stays (empty): removing it could let two runs
    // hold two locks.
    assert_eq!(
        file_names(&out),
        [
            ".fusemap.lock",
            "map.mcap",
            "map.npz",
            "map.pcd",
            "map.pgm",
            "map.ply",
            "map.png",
            "map.yaml",
            "report.html",
            "summary.json"
        ]
    );
    // Foxglove's, ROS 2's and the point-cloud tools' readers agree with map.pgm.
    if let Some(c) = crate::util::check_map_outputs(&out) {
        assert_eq!(c["topics"], serde_json::json!(["/map", "/map_points", "/trajectory"]), "{c}");
        assert_eq!(c["poses"], 0, "a world run has no track: {c}");
        assert!(c["occupied"].as_u64().unwrap() > 100, "{c}");
    }
    for name in file_names(&out).into_iter().filter(|n| n != ".fusemap.lock") {
        assert!(!(name.starts_with('.') && name.contains(".tmp")), "temp file left: {name}");
        assert!(std::fs::metadata(out.join(&name)).unwrap().len() > 0, "{name} is empty");
    }
    // Off a terminal, progress is a plain line every 20 s: a run this short prints none.
    assert_eq!(crate::util::stderr(&o), "", "stderr must stay empty for a short run off a terminal");

    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["scans"], 40);
    assert_eq!(s["beams"], 7240);
    assert_eq!(s["source_kind"], "world");
    let r = &s["returns"];
    assert_eq!(r["valid"], 7240, "{r}");
    for k in ["no_return", "nan", "infinite", "zero", "negative", "below_min"] {
        assert_eq!(r[k], 0, "returns.{k}: {r}");
    }
    assert_eq!(s["rays_walked"], 7240);
    assert_eq!(s["rays_rejected"], 0);
    let e = &s["entropy"];
    let h = e["mean_entropy_nats"].as_f64().expect("entropy.mean_entropy_nats");
    assert!(h > 0.0 && h < std::f64::consts::LN_2, "mean entropy {h}");
    assert_eq!(e["known_share"], 1.0, "{e}");
    let t = s["wall_time_s"].as_f64().expect("wall_time_s");
    assert!(t > 0.0 && t < 60.0, "wall time {t}");
    // Where the time went: a world has a map pass and outputs, no log phases, and the
    // phases add up to the wall time.
    let sec = &s["seconds"];
    assert_eq!(sec["total"], s["wall_time_s"], "{sec}");
    assert!(sec.get("read").is_none() && sec.get("slam").is_none(), "{sec}");
    let phases: f64 = ["map", "outputs", "other"].iter().map(|k| sec[k].as_f64().expect(k)).sum();
    assert!((phases - t).abs() < 1e-6 && sec["map"].as_f64().unwrap() > 0.0, "{sec}");
    assert_eq!(s["notes"], serde_json::json!([]));
    assert!(s.get("log").is_none(), "a simulated run has no log counters");

    // summary.json describes the raster the npz holds.
    let m = NpzMap::read(&out.join("map.npz"));
    let map = &s["map"];
    assert_eq!(map["width"], m.width);
    assert_eq!(map["height"], m.height);
    assert_eq!(map["resolution"], m.resolution);
    assert_eq!(map["origin"], serde_json::json!(m.origin));

    let text = stdout(&o);
    for want in
        ["scans         40", "beams         7240 (valid 7240", "entropy       ", "wall time     ", "outputs       "]
    {
        assert!(text.contains(want), "stdout lacks `{want}`:\n{text}");
    }
    assert!(text.contains(&format!("{:.4} nats", h)), "stdout's entropy differs from summary.json:\n{text}");
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

/// The corridor's acceptance on the written npz: walls occupied, inside free, nothing
/// behind the walls, the known box no larger than the corridor.
#[test]
fn demo_npz_meets_the_corridor_acceptance() {
    let (out, _) = demo("demo-acceptance");
    let m = NpzMap::read(&out.join("map.npz"));
    assert_eq!(m.resolution, 0.05);
    let res = m.resolution;

    // Every wall cell is occupied; all but at most 4 are above 0.8, and those are
    // end-wall cells next to the corners, seen last at grazing incidence (see the comment
    // in crates/fusemap-core/tests/core/corridor.rs).
    let (side, end) = wall_points(res);
    let mut weak = Vec::new();
    for &(x, y) in side.iter().chain(&end) {
        let i = m.at(x, y);
        assert!(m.known[i], "wall cell at ({x}, {y}) never observed");
        assert!(m.occupancy[i] > 0.65, "wall cell at ({x}, {y}) has p = {}", m.occupancy[i]);
        if m.occupancy[i] <= 0.8 {
            weak.push((x, y, m.occupancy[i]));
        }
    }
    assert!(weak.len() <= 4, "{} wall cells at or below 0.8: {weak:?}", weak.len());
    for &(x, y, p) in &weak {
        assert!(x == 4.0 && y.abs() > 1.5, "wall cell at ({x}, {y}) is weak (p = {p}) away from the corners");
    }

    // Strictly inside the corridor, every observed cell is free.
    let mut inside = 0;
    let (mut min_x, mut max_x, mut max_abs_y) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for row in 0..m.height {
        for col in 0..m.width {
            let i = m.index(col, row);
            let (cx, cy) = m.center(col, row);
            if (0.5..4.0 - res).contains(&cx) && cy.abs() < 2.0 - res && m.known[i] {
                inside += 1;
                assert!(m.occupancy[i] < 0.2, "inside cell ({cx:.3}, {cy:.3}) has p = {}", m.occupancy[i]);
            }
            let behind = cy.abs() > 2.0 + res / 2.0 || cx > 4.0 + res / 2.0;
            if behind {
                assert_eq!(m.occupancy[i], 0.5, "cell ({cx:.3}, {cy:.3}) behind a wall");
                assert_eq!(m.log_odds[i], 0.0, "cell ({cx:.3}, {cy:.3}) behind a wall");
                assert!(!m.known[i], "cell ({cx:.3}, {cy:.3}) behind a wall is known");
            }
            if m.known[i] {
                min_x = min_x.min(cx - res / 2.0);
                max_x = max_x.max(cx + res / 2.0);
                max_abs_y = max_abs_y.max(cy.abs() + res / 2.0);
            }
        }
    }
    assert!(inside > 2500, "only {inside} inside cells were observed");
    let eps = 1e-9;
    assert!(min_x >= -0.05 - eps && max_x <= 4.05 + eps, "known box x ∈ [{min_x}, {max_x}]");
    assert!(max_abs_y <= 2.05 + eps, "known box reaches |y| = {max_abs_y}");
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

/// The script a user would run: `np.load`, then what each array is. Prints JSON.
const NUMPY_SCRIPT: &str = r#"
import json, sys
import numpy as np
with np.load(sys.argv[1]) as z:
    out = {"files": sorted(z.files), "arrays": {}}
    for k in z.files:
        a = z[k]
        out["arrays"][k] = {"dtype": a.dtype.name, "shape": list(a.shape)}
    lo, occ, known = z["log_odds"], z["occupancy"], z["known"]
    out["resolution"] = float(z["resolution"])
    out["origin"] = [float(v) for v in z["origin"]]
    out["log_odds_sum"] = float(lo.sum(dtype=np.float64))
    out["known_count"] = int(known.sum())
    out["log_odds_hex"] = lo.astype("<f4").tobytes().hex()
    out["occupancy_hex"] = occ.astype("<f4").tobytes().hex()
    out["known_hex"] = known.astype(np.uint8).tobytes().hex()
    cells = [int(v) for v in sys.argv[2:]]
    out["samples"] = [[float(occ[r, c]), float(lo[r, c]), bool(known[r, c])] for r, c in zip(cells[::2], cells[1::2])]
print(json.dumps(out))
"#;

fn hex_f32(v: &[f32]) -> String {
    v.iter().flat_map(|x| x.to_le_bytes()).map(|b| format!("{b:02x}")).collect()
}

/// Loads `npz` with NumPy and checks it against fusemap-io's reader; `cells` are
/// `(row, col)` pairs sampled by 2-D indexing. Returns the parsed JSON, or `None` when
/// NumPy is unavailable (after the skip notice).
fn numpy_matches_reader(npz: &Path, cells: &[(usize, usize)]) -> Option<(NpzMap, serde_json::Value)> {
    if !python_with(&["numpy"]) {
        return None;
    }
    let mut args: Vec<std::ffi::OsString> = vec![npz.as_os_str().to_owned()];
    for (r, c) in cells {
        args.push(r.to_string().into());
        args.push(c.to_string().into());
    }
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let js: serde_json::Value = serde_json::from_str(&run_python(NUMPY_SCRIPT, &args)).expect("the script prints JSON");
    let m = NpzMap::read(npz);

    assert_eq!(js["files"], serde_json::json!(["known", "log_odds", "occupancy", "origin", "resolution"]));
    let a = &js["arrays"];
    let shape = serde_json::json!([m.height, m.width]);
    for (k, dtype, shape) in [
        ("occupancy", "float32", &shape),
        ("log_odds", "float32", &shape),
        ("known", "bool", &shape),
        ("resolution", "float64", &serde_json::json!([])),
        ("origin", "float64", &serde_json::json!([2])),
    ] {
        assert_eq!(a[k]["dtype"], dtype, "{k}: {}", a[k]);
        assert_eq!(&a[k]["shape"], shape, "{k}: {}", a[k]);
    }
    assert_eq!(js["resolution"].as_f64(), Some(m.resolution));
    assert_eq!(js["origin"], serde_json::json!(m.origin));
    // Bit for bit the same values in the same (C, row-major) order.
    assert_eq!(js["log_odds_hex"].as_str(), Some(hex_f32(&m.log_odds).as_str()), "log_odds differ");
    assert_eq!(js["occupancy_hex"].as_str(), Some(hex_f32(&m.occupancy).as_str()), "occupancy differs");
    let known_hex: String = m.known.iter().map(|&k| format!("{:02x}", u8::from(k))).collect();
    assert_eq!(js["known_hex"].as_str(), Some(known_hex.as_str()), "known differs");
    assert_eq!(js["known_count"], m.known.iter().filter(|&&k| k).count());
    let sum: f64 = m.log_odds.iter().map(|&l| l as f64).sum();
    let np_sum = js["log_odds_sum"].as_f64().unwrap();
    assert!((np_sum - sum).abs() <= 1e-9 * sum.abs().max(1.0), "sum of log_odds: numpy {np_sum}, fusemap {sum}");
    for (k, &(r, c)) in cells.iter().enumerate() {
        let i = m.index(c, r);
        let s = &js["samples"][k];
        assert_eq!(s[0].as_f64().map(|v| v as f32), Some(m.occupancy[i]), "occupancy[{r}, {c}]");
        assert_eq!(s[1].as_f64().map(|v| v as f32), Some(m.log_odds[i]), "log_odds[{r}, {c}]");
        assert_eq!(s[2].as_bool(), Some(m.known[i]), "known[{r}, {c}]");
    }
    Some((m, js))
}

/// map.npz loads in NumPy exactly as fusemap-io reads it, with the dtypes and shape the
/// map_server pair and summary.json state.
#[test]
fn demo_npz_loads_in_numpy_as_fusemap_reads_it() {
    let (out, _) = demo("demo-numpy");
    let npz = out.join("map.npz");
    let m = NpzMap::read(&npz);
    let cells = [(m.row(2.0), m.col(2.0)), (m.row(0.0), m.col(2.0)), (m.row(-2.0), m.col(4.0)), (0, 0)];
    let Some((m, js)) = numpy_matches_reader(&npz, &cells) else {
        std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
        return;
    };
    assert_eq!(js["resolution"], 0.05);
    let ms = fusemap_io::map_server::read_map_server(&out.join("map.yaml")).unwrap();
    assert_eq!(js["arrays"]["occupancy"]["shape"], serde_json::json!([ms.height, ms.width]));
    let (w, h, _) = read_pgm(&out.join("map.pgm"));
    assert_eq!((w, h), (m.width, m.height));
    // The samples: side wall occupied, corridor centre free.
    assert!(js["samples"][0][0].as_f64().unwrap() > 0.65);
    assert!(js["samples"][1][0].as_f64().unwrap() < 0.2);
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

/// The map_server pair reads back to the npz's ternary map; its YAML has exactly
/// map_server's keys; the PGM is P5 with the lowest y at the bottom.
#[test]
fn demo_map_server_pair_matches_the_npz() {
    let (out, _) = demo("demo-map-server");
    let m = NpzMap::read(&out.join("map.npz"));
    let yaml_path = out.join("map.yaml");
    let ms = fusemap_io::map_server::read_map_server(&yaml_path).unwrap();
    assert_eq!((ms.width, ms.height), (m.width, m.height));
    assert_eq!(ms.resolution, m.resolution);
    assert_eq!([ms.origin.x, ms.origin.y], m.origin);
    assert_eq!(ms.origin_yaw, 0.0);
    let mut mismatches = Vec::new();
    for (i, t) in ms.cells.iter().enumerate() {
        let want = m.ternary(i);
        // A float32 occupancy a hair from a threshold may classify differently from the
        // float64 probability the writer used; nothing else may.
        let near_threshold = [0.65f32, 0.25].iter().any(|t| (m.occupancy[i] - t).abs() < 1e-6);
        if *t != want && !near_threshold {
            mismatches.push((i % m.width, i / m.width, *t, want, m.occupancy[i]));
        }
    }
    assert!(mismatches.is_empty(), "PGM vs npz (col, row, pgm, npz, p): {mismatches:?}");

    let yaml = std::fs::read_to_string(&yaml_path).unwrap();
    let keys: Vec<&str> = yaml
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|l| l.split_once(':').expect("key: value").0.trim())
        .collect();
    assert_eq!(keys, ["image", "mode", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"]);
    assert!(yaml.contains("image: map.pgm\n"), "{yaml}");
    assert!(yaml.contains("mode: trinary\n"), "{yaml}");

    let (w, h, px) = read_pgm(&out.join("map.pgm"));
    assert_eq!((w, h), (m.width, m.height));
    // The bottom image row is raster row 0, the lowest y: it holds the y = -2 wall.
    assert_eq!(m.row(-2.0), 0, "the raster starts at the right wall");
    let bottom = &px[(h - 1) * w..];
    let top = &px[..w];
    for x in [0.5, 1.0, 2.0, 3.0, 3.9] {
        let c = m.col(x);
        assert_eq!(bottom[c], 0, "bottom row at x = {x}: the y = -2 wall is black");
        assert_eq!(top[c], 0, "top row at x = {x}: the y = +2 wall is black");
        let centre = &px[(h - 1 - m.row(0.0)) * w..][..w];
        assert_eq!(centre[c], 254, "corridor centre at x = {x} is white");
    }
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

/// The PNG shows three straight walls: every black pixel lies on the row of y = 2, the
/// row of y = -2 or the column of x = 4, and those lines are (nearly) all black.
#[test]
fn demo_png_shows_three_straight_walls() {
    let (out, _) = demo("demo-png");
    let m = NpzMap::read(&out.join("map.npz"));
    let (pw, ph, px) = read_png(&out.join("map.png"));
    let f = pw / m.width;
    assert_eq!(f, fusemap_io::picture::scale_factor(m.width, m.height));
    assert_eq!((pw, ph), (m.width * f, m.height * f), "image size is the raster's × {f}");
    let res = m.resolution;
    let (top, bottom, end) = (m.row(2.0), m.row(-2.0), m.col(4.0));

    let mut dark = std::collections::BTreeSet::new();
    for (k, &v) in px.iter().enumerate() {
        if v < 64 {
            let (x, y) = (k % pw, k / pw);
            // Top image row = highest y.
            dark.insert((x / f, m.height - 1 - y / f));
        }
    }
    assert!(!dark.is_empty(), "no dark pixel at all");
    for &(col, row) in &dark {
        let (cx, cy) = m.center(col, row);
        let near_side = ((cy - 2.0).abs() <= res || (cy + 2.0).abs() <= res) && cx <= 4.0 + res;
        let near_end = (cx - 4.0).abs() <= res && cy.abs() <= 2.0 + res;
        assert!(near_side || near_end, "dark cell ({cx:.3}, {cy:.3}) is more than a cell from every wall");
        // Straight: one row per side wall, one column for the end wall.
        let on_line = row == top || row == bottom || col == end;
        assert!(on_line, "dark cell ({cx:.3}, {cy:.3}) off the lines y = 2, y = -2 and x = 4");
    }
    // Each wall is drawn along its whole scanned length: the side walls black from
    // x = 0.5 to 4; the end wall darker than grey everywhere and black over most of it
    // (its corner cells are weaker, see the corridor acceptance test).
    let shade = |col: usize, row: usize| px[(m.height - 1 - row) * f * pw + col * f];
    let (side, end_pts) = wall_points(res);
    for (x, y) in side {
        assert!(dark.contains(&(m.col(x), m.row(y))), "side wall at ({x}, {y}) is not black");
    }
    let black = end_pts.iter().filter(|(x, y)| dark.contains(&(m.col(*x), m.row(*y)))).count();
    assert!(black * 100 >= end_pts.len() * 85, "only {black} of {} end-wall cells black", end_pts.len());
    for (x, y) in end_pts {
        assert!(shade(m.col(x), m.row(y)) < 140, "end wall at ({x}, {y}) is not dark");
    }
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

/// Reads every array of an npz as (name, shape, bytes) for bitwise comparison.
fn npz_arrays(path: &Path) -> Vec<(&'static str, Vec<usize>, Vec<u8>)> {
    ["occupancy", "log_odds", "known", "resolution", "origin"]
        .into_iter()
        .map(|name| {
            let a = read_npz(path, name).unwrap();
            let bytes = match a.values {
                NpyValues::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                NpyValues::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                NpyValues::Bool(v) => v.iter().map(|&b| u8::from(b)).collect(),
                other => panic!("{name}: unexpected dtype {other:?}"),
            };
            (name, a.shape, bytes)
        })
        .collect()
}

/// `fusemap map --world worlds/corridor.toml`, with and without configs/example.toml
/// (every key at its default), gives the demo's arrays bit for bit.
#[test]
fn map_of_the_corridor_world_equals_demo() {
    let (demo_out, _) = demo("demo-vs-map");
    let want = npz_arrays(&demo_out.join("map.npz"));
    let world = repo_file("worlds/corridor.toml");
    let config = repo_file("configs/example.toml");
    let base = temp_dir("demo-vs-map-runs");
    let plain = base.join("plain");
    let o = run(&["map", "--world", path_str(&world), "--out", path_str(&plain)]);
    assert_success(&o);
    let configured = base.join("configured");
    let o = run(&["map", "--config", path_str(&config), "--world", path_str(&world), "--out", path_str(&configured)]);
    assert_success(&o);
    for dir in [&plain, &configured] {
        let got = npz_arrays(&dir.join("map.npz"));
        for ((name, shape, bytes), (_, want_shape, want_bytes)) in got.iter().zip(&want) {
            assert_eq!(shape, want_shape, "{}: {name} shape", dir.display());
            assert!(bytes == want_bytes, "{}: {name} differs from demo's", dir.display());
        }
        let s = read_json(&dir.join("summary.json"));
        assert_eq!((s["scans"].as_u64(), s["beams"].as_u64()), (Some(40), Some(7240)));
    }
    std::fs::remove_dir_all(demo_out.parent().unwrap()).unwrap();
    std::fs::remove_dir_all(&base).unwrap();
}

/// A corridor that is neither square nor symmetric in y (walls at y = 1 and y = -1.5, a
/// short wall at y = 0.5 on the left only): every output must put it north up, with
/// npz row 0 at the lowest y.
#[test]
fn outputs_are_north_up_on_an_asymmetric_world() {
    let corridor = std::fs::read_to_string(repo_file("worlds/corridor.toml")).unwrap();
    let scanner = &corridor[corridor.find("[scanner]").unwrap()..corridor.find("[[wall]]").unwrap()];
    let world_text = format!(
        "{scanner}\
         [[wall]]\nfrom = [-20.0, 1.0]\nto = [4.0, 1.0]\n\n\
         [[wall]]\nfrom = [-20.0, -1.5]\nto = [4.0, -1.5]\n\n\
         [[wall]]\nfrom = [4.0, -1.5]\nto = [4.0, 1.0]\n\n\
         [[wall]]\nfrom = [2.0, 0.5]\nto = [2.6, 0.5]\n\n\
         [trajectory]\nstart = [0.0, 0.0, 0.0]\nstep = [0.1, 0.0, 0.0]\ncount = 40\n"
    );
    let dir = temp_dir("north-up");
    let world = write_file(&dir, "asymmetric.toml", world_text);
    let out = dir.join("out");
    assert_success(&run(&["map", "--world", path_str(&world), "--out", path_str(&out)]));

    let m = NpzMap::read(&out.join("map.npz"));
    assert!(m.height < m.width, "rows follow y (2.5 m), columns x (4 m): {} × {}", m.height, m.width);
    let (pillar, mirror) = (m.at(2.3, 0.5), m.at(2.3, -0.5));
    assert!(m.occupancy[pillar] > 0.65, "the short wall at y = 0.5: p = {}", m.occupancy[pillar]);
    assert!(m.known[mirror] && m.occupancy[mirror] < 0.25, "its mirror at y = -0.5: p = {}", m.occupancy[mirror]);
    assert_eq!(m.row(-1.5), 0, "the lowest wall is raster row 0");
    assert_eq!(m.row(1.0), m.height - 1, "the highest wall is the last raster row");

    // PGM: image row = height - 1 - raster row.
    let (w, h, pgm) = read_pgm(&out.join("map.pgm"));
    assert_eq!((w, h), (m.width, m.height));
    let pgm_at = |x: f64, y: f64| pgm[(h - 1 - m.row(y)) * w + m.col(x)];
    assert_eq!(pgm_at(2.3, 0.5), 0, "PGM: the short wall is black, north up");
    assert_eq!(pgm_at(2.3, -0.5), 254, "PGM: its mirror is white");
    assert_eq!(pgm_at(2.0, -1.5), 0, "PGM: the bottom row is the y = -1.5 wall");
    let ms = fusemap_io::map_server::read_map_server(&out.join("map.yaml")).unwrap();
    assert_eq!(ms.cells[pillar], Ternary::Occupied);
    assert_eq!(ms.cells[mirror], Ternary::Free);

    // PNG: the same, enlarged.
    let (pw, _, png) = read_png(&out.join("map.png"));
    let f = pw / m.width;
    let png_at = |x: f64, y: f64| png[((m.height - 1 - m.row(y)) * f + f / 2) * pw + m.col(x) * f + f / 2];
    assert!(png_at(2.3, 0.5) < 64, "PNG: the short wall is dark, north up");
    assert!(png_at(2.3, -0.5) > 200, "PNG: its mirror is light");

    // NumPy: `occupancy[row, col]` with row = y.
    let cells = [(m.row(0.5), m.col(2.3)), (m.row(-0.5), m.col(2.3))];
    if let Some((_, js)) = numpy_matches_reader(&out.join("map.npz"), &cells) {
        assert!(js["samples"][0][0].as_f64().unwrap() > 0.65, "numpy: occupancy[row(0.5), col(2.3)]");
        assert!(js["samples"][1][0].as_f64().unwrap() < 0.25, "numpy: occupancy[row(-0.5), col(2.3)]");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--help` on the tool and on every subcommand; no arguments is a usage error.
#[test]
fn help_and_usage() {
    for args in [&["--help"][..], &["demo", "--help"], &["map", "--help"], &["doctor", "--help"], &["bench", "--help"]]
    {
        let o = run(args);
        assert_success(&o);
        assert!(stdout(&o).contains("Usage: fusemap"), "{args:?}: {}", stdout(&o));
    }
    let o = run(&[]);
    assert!(!o.status.success(), "no arguments must fail");
    assert!(crate::util::stderr(&o).contains("Usage: fusemap"), "{}", crate::util::stderr(&o));
    assert!(stdout(&o).is_empty());
}

/// An output path that is one of the run's inputs (world, log or config) is refused
/// before anything is written, with one line naming it, and the input stays as it was.
#[test]
fn outputs_never_overwrite_inputs() {
    let dir = temp_dir("no-overwrite");
    let world_bytes = std::fs::read(repo_file("worlds/corridor.toml")).unwrap();
    let config_bytes = std::fs::read(repo_file("configs/example.toml")).unwrap();
    let log_bytes = b"FLASER 3 1.0 1.0 1.0 0 0 0 0 0 0 1.0 host 1.0\n".to_vec();

    type Case<'a> = (&'a str, &'a [u8], &'a dyn Fn(&Path, &Path) -> Vec<String>);
    let world_case = |input: &Path, out: &Path| {
        ["map", "--world", path_str(input), "--out", path_str(out)].map(String::from).to_vec()
    };
    let log_case = |input: &Path, out: &Path| {
        // The same file by another spelling.
        let spelled = out.join("sub/..").join(input.file_name().unwrap());
        std::fs::create_dir_all(out.join("sub")).unwrap();
        ["map", "--out", path_str(out), path_str(&spelled)].map(String::from).to_vec()
    };
    let config_case = |input: &Path, out: &Path| {
        ["demo", "--corridor", "--config", path_str(input), "--out", path_str(out)].map(String::from).to_vec()
    };
    let cases: [Case; 3] = [
        ("summary.json", &world_bytes, &world_case),
        ("map.png", &log_bytes, &log_case),
        ("map.yaml", &config_bytes, &config_case),
    ];
    for (name, bytes, args) in cases {
        let out = dir.join(name.replace('.', "-"));
        std::fs::create_dir_all(&out).unwrap();
        let input = write_file(&out, name, bytes);
        let args = args(&input, &out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let line = crate::util::one_line_error(&run(&args));
        assert!(line.contains(path_str(&out.join(name))), "{args:?}: {line}");
        assert!(line.contains("refusing to overwrite an input"), "{line}");
        assert_eq!(std::fs::read(&input).unwrap(), bytes, "{name} was changed");
        let left: Vec<String> = file_names(&out).into_iter().filter(|n| n != "sub").collect();
        assert_eq!(left, [name], "nothing else may be written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
