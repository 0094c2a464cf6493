//! The correlated-evidence rule end to end: a lidar scan and a camera frame of one
//! instant, seeing the same wall, inflate confidence when summed as independent and do not
//! when merged (design document §2.4).

use super::*;
use crate::geometry::{PlanarMount, Point2, Pose2};
use crate::grid::{CellIndex, DynamicParams, FusionGrid, GridGeometry, MergeRule, OccupancyParams};
use crate::measurement::{Evidence, ObservationId, RangeData, Ray, SensorId, SensorKind};
use crate::sensor::{LaserScan, LidarModel, LidarParams};
use crate::time::Stamp;

const MS: i64 = 1_000_000;

fn engine(correlated: bool) -> (Engine, SensorId, SensorId) {
    let grid = FusionGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
    let mut e = Engine::new(grid);
    let lidar = e.add_lidar("laser", LidarModel::new(LidarParams::default(), PlanarMount::default()));
    let camera = e.add_sensor("camera", SensorModel::External(SensorKind::Camera));
    if correlated {
        e.set_correlation(Correlation { groups: vec![vec![lidar, camera]], window_ns: 50 * MS, rule: MergeRule::Max });
    }
    (e, lidar, camera)
}

/// One beam straight ahead onto a wall 2 m away.
fn scan(t: i64) -> LaserScan {
    LaserScan { stamp: Stamp(t), angle_min: 0.0, angle_increment: 0.1, ranges: vec![2.0] }
}

/// The camera's view of the same wall a few milliseconds later, with its own (weaker)
/// evidence.
fn frame(camera: SensorId, t: i64) -> RangeData {
    let rays = vec![Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(2.0, 0.0), hit: true }];
    RangeData { stamp: Stamp(t), sensor: camera, rays, evidence: Evidence { p_hit: 0.7, p_miss: 0.45 } }
}

fn run(correlated: bool, frames: i64) -> Engine {
    let (mut e, lidar, camera) = engine(correlated);
    for k in 0..frames {
        let t = k * 100 * MS;
        e.insert_scan_observed(lidar, ObservationId(k as u64), &scan(t), f32::NAN, f32::NAN, |_| Pose2::IDENTITY)
            .unwrap();
        e.insert_range_data_observed(ObservationId(k as u64), &frame(camera, t + 10 * MS)).unwrap();
    }
    e
}

#[test]
fn correlated_evidence_is_counted_once() {
    let wall = CellIndex::new(20, 0);
    let free = CellIndex::new(10, 0);
    let lidar_alone = {
        let (mut e, lidar, _) = engine(false);
        e.insert_scan(lidar, &scan(0), Pose2::IDENTITY).unwrap();
        e
    };
    let summed = run(false, 1);
    let merged = run(true, 1);
    let l = |e: &Engine, c| e.grid().log_odds(c).unwrap();
    // Summed as independent, one look at the wall is more confident than the lidar's own
    // evidence; merged, it is exactly the lidar's (the stronger member).
    assert!(l(&summed, wall) > l(&lidar_alone, wall) + 0.5);
    assert_eq!(l(&merged, wall), l(&lidar_alone, wall));
    assert!(l(&summed, free) < l(&lidar_alone, free) - 0.1);
    assert_eq!(l(&merged, free), l(&lidar_alone, free));
    assert_eq!(merged.stats().correlated_merged, 1);
    assert_eq!(summed.stats().correlated_merged, 0);
    // Over several instants each one counts once: the merged map's free cell is the lidar's
    // evidence times the number of instants.
    let merged = run(true, 3);
    let t = *merged.grid().table();
    let expect = (0..3).fold(t.prior, |v, _| t.update(v, t.increment(0.4)));
    assert!((l(&merged, free) - expect).abs() < 1e-6);
    // Beyond the window the camera frame is an observation of its own.
    let (mut e, lidar, camera) = engine(true);
    e.insert_scan(lidar, &scan(0), Pose2::IDENTITY).unwrap();
    e.insert_range_data(&frame(camera, 80 * MS)).unwrap();
    assert!(l(&e, wall) > l(&lidar_alone, wall) + 0.5);
}

#[test]
fn lidar_hits_on_a_cell_holding_a_dynamic_object_go_to_the_dynamic_layer() {
    let (mut e, lidar, _) = engine(false);
    e.set_dynamic(DynamicParams::default(), true);
    // Nothing dynamic yet: the hit is static.
    e.insert_scan(lidar, &scan(0), Pose2::IDENTITY).unwrap();
    let wall = CellIndex::new(20, 0);
    let before = e.grid().log_odds(wall).unwrap();
    // Mark the cell dynamic through the layer's own update, then hit it again.
    let t = Stamp(100 * MS);
    {
        let obs = e.maps.primary_mut().grid_mut().begin_observation();
        let (tile, offset, _) = e.maps.primary_mut().grid_mut().cell_mut(wall, obs).unwrap();
        let u = crate::grid::DynamicUpdate::new(&DynamicParams::default(), t);
        u.apply(&mut tile.layers_mut().dynamic, offset, u.d_hit());
    }
    e.insert_scan(lidar, &scan(t.0), Pose2::IDENTITY).unwrap();
    assert_eq!(e.grid().log_odds(wall).unwrap(), before, "the static layer did not take the hit");
    let (tile, offset) = e.grid().tile_of(wall).unwrap();
    let dynamic = tile.layers().dynamic().unwrap().log_odds_at(offset, t, 2.0).unwrap();
    assert!(dynamic > 1.0);
}
