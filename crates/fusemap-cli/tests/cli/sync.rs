//! Time synchronisation through the whole pipeline: a simulated CARMEN log of a turning
//! robot whose scans are stamped 30 ms after its 10 Hz odometry, mapped by the CLI with
//! `log.sync = "interpolate"` and `"nearest"`. Nearest-neighbour matching places each
//! scan with a pose 30 ms old and must draw measurably thicker walls (design document
//! §4.1: "30 ms off thickens walls").

use crate::util::{assert_success, read_json, run, temp_dir, write_file};
use fusemap_core::geometry::{PlanarMount, Point2, Pose2};
use fusemap_core::sim::{box_world, simulate_scan, BoxWorld, ScannerSpec};
use fusemap_core::time::Stamp;
use std::fmt::Write as _;
use std::path::Path;

/// Turning at 1.2 rad/s while drifting slowly.
fn truth(t: f64) -> Pose2 {
    Pose2::new(0.4 * (0.3 * t).sin(), 0.3 * (0.2 * t).cos() - 0.3, 1.2 * t)
}

/// The log: ODOM at t = 0.1 k, FLASER (181 beams over 180°) at t = 0.1 j + 0.03, in time
/// order. The pose on each FLASER line is left at zero: the run must take its poses from
/// the odometry.
fn carmen_log(w: &BoxWorld) -> String {
    let h = std::f64::consts::FRAC_PI_2;
    let spec = ScannerSpec { beams: 181, angle_min: -h, angle_max: h, range_max: 20.0, rate_hz: 10.0 };
    let mut out = String::from("# simulated: a robot turning in a 12 m room\n");
    for k in 0..=100 {
        let t = 0.1 * k as f64;
        let p = truth(t);
        writeln!(out, "ODOM {:.9} {:.9} {:.9} 0 0 0 {t:.6} sim {t:.6}", p.x, p.y, p.theta).unwrap();
        if k < 95 {
            let ts = t + 0.03;
            let scan = simulate_scan(&w.world, &spec, &PlanarMount::default(), truth(ts), Stamp::ZERO);
            let ranges: Vec<String> = scan.ranges.iter().map(|r| format!("{r:.4}")).collect();
            writeln!(out, "FLASER 181 {} 0 0 0 0 0 0 {ts:.6} sim {ts:.6}", ranges.join(" ")).unwrap();
        }
    }
    out
}

/// Mean distance, in cells, of the map's occupied cells from the nearest true wall.
fn wall_spread(out: &Path, w: &BoxWorld) -> (f64, usize) {
    let npz = out.join("map.npz");
    let (shape, occ) = fusemap_io::npz::read_npz_f32(&npz, "occupancy").unwrap();
    let origin = match fusemap_io::npz::read_npz(&npz, "origin").unwrap().values {
        fusemap_io::npz::NpyValues::F64(v) => v,
        other => panic!("origin: {other:?}"),
    };
    let res = match fusemap_io::npz::read_npz(&npz, "resolution").unwrap().values {
        fusemap_io::npz::NpyValues::F64(v) => v[0],
        other => panic!("resolution: {other:?}"),
    };
    let (h, wd) = (shape[0], shape[1]);
    let (mut sum, mut n) = (0.0, 0);
    for row in 0..h {
        for col in 0..wd {
            if occ[row * wd + col] > 0.65 {
                let p = Point2::new(origin[0] + (col as f64 + 0.5) * res, origin[1] + (row as f64 + 0.5) * res);
                let d = w.world.segments.iter().map(|s| distance(p, s.a, s.b)).fold(f64::INFINITY, f64::min);
                sum += d / res;
                n += 1;
            }
        }
    }
    (sum / n as f64, n)
}

fn distance(p: Point2, a: Point2, b: Point2) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    p.distance(Point2::new(a.x + t * dx, a.y + t * dy))
}

#[test]
fn nearest_neighbour_sync_thickens_walls_through_the_cli() {
    let w = box_world(6.0, 3, 7);
    let dir = temp_dir("sync");
    let log = write_file(&dir, "turning.log", carmen_log(&w));
    let mut spread = Vec::new();
    for sync in ["interpolate", "nearest"] {
        let cfg = write_file(
            &dir,
            &format!("{sync}.toml"),
            format!(
                "[[lidar]]\nmax_range = 20.0\n\n[log]\npose_source = \"odometry\"\nsync = \"{sync}\"\nnearest_tolerance_s = 0.05\n"
            ),
        );
        let out = dir.join(sync);
        let o = run(&["map", "--config", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), log.to_str().unwrap()]);
        assert_success(&o);
        let s = read_json(&out.join("summary.json"));
        assert_eq!(s["scans"].as_u64(), Some(95), "{sync}: every scan gets a pose");
        spread.push(wall_spread(&out, &w));
    }
    let ((interp, n_i), (nearest, n_n)) = (spread[0], spread[1]);
    eprintln!("wall spread through the CLI: interpolate {interp:.3} cells ({n_i} occupied), nearest {nearest:.3} cells ({n_n})");
    assert!(interp < 0.6, "interpolated walls spread {interp} cells");
    assert!(nearest > 2.0 * interp, "nearest {nearest} vs interpolate {interp}");
    std::fs::remove_dir_all(&dir).unwrap();
}
