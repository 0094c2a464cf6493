//! The invalid-return corpus: NaN, ±inf, 0, negative, tiny, exactly max_range and beyond.
//! None of it may become an obstacle; under `skip` none of it may become free space.

use fusemap_core::fusion::Engine;
use fusemap_core::geometry::{PlanarMount, Pose2};
use fusemap_core::grid::{FusionGrid, GridGeometry, OccupancyParams, Ternary};
use fusemap_core::sensor::{LaserScan, LidarModel, LidarParams, MaxRangePolicy};
use fusemap_core::time::Stamp;

const CORPUS: [f32; 8] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -1.0, 1e-9, 10.0, 25.0];

fn map(policy: MaxRangePolicy) -> Engine {
    let grid = FusionGrid::new(GridGeometry::centered(0.05).unwrap(), OccupancyParams::default());
    let mut e = Engine::new(grid);
    let params = LidarParams { max_range_policy: policy, ..Default::default() };
    let id = e.add_lidar("laser", LidarModel::new(params, PlanarMount::default()));
    // Every corpus value on every beam of 50 scans from several poses.
    for k in 0..50 {
        let ranges: Vec<f32> = (0..181).map(|i| CORPUS[(i + k) % CORPUS.len()]).collect();
        let scan = LaserScan::evenly_spaced(Stamp(k as i64), -1.5, 1.5, ranges);
        e.insert_scan(id, &scan, Pose2::new(0.1 * k as f64, 0.0, 0.3 * k as f64)).unwrap();
    }
    e
}

fn classes(e: &Engine) -> (usize, usize, usize) {
    let g = e.grid();
    let Some(r) = g.known_raster() else { return (0, 0, 0) };
    let t = r.ternary();
    let occ = t.iter().filter(|c| **c == Ternary::Occupied).count();
    let free = t.iter().filter(|c| **c == Ternary::Free).count();
    (occ, free, r.known_count())
}

#[test]
fn skip_policy_leaves_no_evidence_at_all() {
    let e = map(MaxRangePolicy::Skip);
    assert_eq!(classes(&e), (0, 0, 0));
    assert_eq!(e.grid().tile_count(), 0);
    let s = e.sensor_stats().next().unwrap();
    let r = s.returns;
    assert_eq!(r.valid, 0);
    assert_eq!(r.total(), 50 * 181);
    assert!(r.nan > 0 && r.infinite > 0 && r.zero > 0 && r.negative > 0 && r.below_min > 0 && r.no_return > 0);
}

#[test]
fn clear_policy_frees_but_never_occupies() {
    let e = map(MaxRangePolicy::Clear);
    let (occ, free, known) = classes(&e);
    assert_eq!(occ, 0);
    assert!(free > 0 && known > 0);
    assert_eq!(e.stats().insert.hit_updates, 0);
}
