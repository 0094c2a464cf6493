//! Time synchronisation and de-skew, measured (design document §4.1: "30 ms off thickens
//! walls"; a scan sweeping 50 ms while the robot turns is distorted).
//!
//! A robot turns in a 12 m square room with obstacles. Ground truth is a continuous pose
//! function; odometry samples it exactly. Walls are drawn from scans posed three ways and
//! their thickness is measured as the mean distance of occupied cells from the true walls.

use fusemap_core::geometry::{PlanarMount, Pose2};
use fusemap_core::grid::{CellIndex, FusionGrid, GridGeometry, OccupancyParams, Ternary};
use fusemap_core::sensor::{LaserScan, LidarModel, LidarParams};
use fusemap_core::sim::{box_world, simulate_moving_scan, simulate_scan, BoxWorld, ScannerSpec};
use fusemap_core::time::{PoseBuffer, Stamp, SyncMode};
use fusemap_core::{fusion::Engine, measurement::SensorId};

/// Turning on the spot while drifting slowly: ω = 1.2 rad/s.
fn truth(t: f64) -> Pose2 {
    Pose2::new(0.4 * (0.3 * t).sin(), 0.3 * (0.2 * t).cos() - 0.3, 1.2 * t)
}

fn world() -> BoxWorld {
    box_world(6.0, 3, 7)
}

fn spec() -> ScannerSpec {
    let h = std::f64::consts::FRAC_PI_2;
    ScannerSpec { beams: 361, angle_min: -h, angle_max: h, range_max: 20.0, rate_hz: 10.0 }
}

/// Mean distance (in cells) of occupied cells from the nearest true wall, and their count.
fn wall_spread(g: &FusionGrid, w: &BoxWorld) -> (f64, usize) {
    let b = g.known_box().unwrap();
    let res = g.geometry().resolution();
    let (mut sum, mut n) = (0.0, 0usize);
    for y in b.min.y..=b.max.y {
        for x in b.min.x..=b.max.x {
            let c = CellIndex::new(x, y);
            if g.ternary(c) == Ternary::Occupied {
                let p = g.geometry().cell_center(c);
                sum += w.world.distance_to_walls(p) / res;
                n += 1;
            }
        }
    }
    (sum / n as f64, n)
}

fn engine() -> (Engine, SensorId) {
    let grid = FusionGrid::new(GridGeometry::centered(0.05).unwrap(), OccupancyParams::default());
    let mut e = Engine::new(grid);
    let id = e.add_lidar(
        "laser",
        LidarModel::new(LidarParams { max_range: 20.0, ..Default::default() }, PlanarMount::default()),
    );
    (e, id)
}

fn stamp(t: f64) -> Stamp {
    Stamp::from_secs_f64(t).unwrap()
}

#[test]
fn nearest_neighbour_thickens_walls_interpolation_does_not() {
    // Odometry at 10 Hz on t = 0.1 k; scans stamped 30 ms later (taken at one instant,
    // no sweep, so only synchronisation differs).
    let w = world();
    let mut odom = PoseBuffer::new(0.5);
    for k in 0..=100 {
        odom.push(stamp(0.1 * k as f64), truth(0.1 * k as f64));
    }
    let scans: Vec<(f64, LaserScan)> = (0..95)
        .map(|j| {
            let t = 0.1 * j as f64 + 0.03;
            (t, simulate_scan(&w.world, &spec(), &PlanarMount::default(), truth(t), stamp(t)))
        })
        .collect();
    let map = |mode: SyncMode| {
        let (mut e, id) = engine();
        for (t, scan) in &scans {
            let pose = odom.pose_at(stamp(*t), mode).expect("every scan has a pose");
            e.insert_scan(id, scan, pose).unwrap();
        }
        wall_spread(e.grid(), &w)
    };
    let (interp, n_i) = map(SyncMode::Interpolate);
    let (nearest, n_n) = map(SyncMode::Nearest { tolerance_s: 0.05 });
    eprintln!("wall spread: interpolate {interp:.3} cells over {n_i} occupied; nearest {nearest:.3} cells over {n_n}");
    assert!(interp < 0.6, "interpolated walls spread {interp} cells");
    assert!(nearest > 2.0 * interp, "nearest {nearest} vs interpolate {interp}");
    assert!(n_n > n_i, "nearest should draw more (thicker) wall cells: {n_n} vs {n_i}");
}

#[test]
fn de_skew_thins_walls_of_scans_swept_while_turning() {
    // Each scan sweeps 50 ms (time_increment = 50 ms / 360) while the robot turns at
    // 1.2 rad/s: the last beam is fired 0.06 rad later than the first.
    let w = world();
    let ti = 0.05 / 360.0;
    let mut odom = PoseBuffer::new(0.5);
    for k in 0..=500 {
        odom.push(stamp(0.02 * k as f64), truth(0.02 * k as f64));
    }
    let scans: Vec<(f64, LaserScan)> = (0..95)
        .map(|j| {
            let t = 0.1 * j as f64;
            (t, simulate_moving_scan(&w.world, &spec(), &PlanarMount::default(), truth, t, ti))
        })
        .collect();
    let map = |deskew: bool| {
        let (mut e, id) = engine();
        for (t, scan) in &scans {
            let pose = odom.interpolate(stamp(*t)).unwrap();
            if deskew {
                e.insert_scan_with(id, scan, |i| odom.interpolate(stamp(t + i as f64 * ti)).unwrap()).unwrap();
            } else {
                e.insert_scan(id, scan, pose).unwrap();
            }
        }
        wall_spread(e.grid(), &w)
    };
    let (sharp, n_s) = map(true);
    let (skewed, n_k) = map(false);
    eprintln!("wall spread: de-skewed {sharp:.3} cells over {n_s} occupied; one pose per scan {skewed:.3} over {n_k}");
    assert!(sharp < 0.6, "de-skewed walls spread {sharp} cells");
    assert!(skewed > 1.5 * sharp, "skewed {skewed} vs de-skewed {sharp}");
}
