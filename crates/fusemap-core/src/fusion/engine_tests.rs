//! Tests of the fusion engine: insertion paths, counters, refusals and the map budget.

use super::*;
use crate::config::LimitsConfig;
use crate::geometry::PlanarMount;
use crate::grid::{GridGeometry, OccupancyParams};
use crate::sensor::LidarParams;

fn engine() -> (Engine, SensorId, SensorId) {
    let grid = FusionGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
    let mut e = Engine::new(grid);
    let a = e.add_lidar("front", LidarModel::new(LidarParams::default(), PlanarMount::default()));
    let b = e.add_lidar("rear", LidarModel::new(LidarParams::default(), PlanarMount::default()));
    (e, a, b)
}

fn scan(t: i64) -> LaserScan {
    LaserScan { stamp: Stamp(t), angle_min: 0.0, angle_increment: 0.1, ranges: vec![1.0, f32::NAN] }
}

#[test]
fn two_sensors_interleaved_in_time() {
    let (mut e, a, b) = engine();
    e.insert_scan(a, &scan(1), Pose2::IDENTITY).unwrap();
    e.insert_scan(b, &scan(2), Pose2::IDENTITY).unwrap();
    e.insert_scan(a, &scan(2), Pose2::IDENTITY).unwrap();
    let err = e.insert_scan(b, &scan(1), Pose2::IDENTITY).unwrap_err();
    assert!(matches!(err, EngineError::OutOfOrder { .. }));
    assert_eq!(e.stats().measurements, 3);
    assert_eq!(e.stats().out_of_order, 1);
    let s: Vec<_> = e.sensor_stats().cloned().collect();
    assert_eq!(s[0].scans, 2);
    assert_eq!(s[0].returns.nan, 2);
    assert_eq!(s[1].scans, 1);
    assert_eq!(s[1].name, "rear");
    assert!(e.insert_scan(SensorId(9), &scan(5), Pose2::IDENTITY).is_err());
}

#[test]
fn an_observation_past_the_map_budget_is_an_error_naming_the_limit() {
    // 0.1 m cells: one 64 x 64 tile is 6.4 m; a 1 m beam from the origin touches the
    // four tiles around it, a 30 m one (max range 10 m: cleared to 10 m) reaches more.
    for (limits, key, text) in [
        (
            LimitsConfig { map_cells: 4 * 4096, ..Default::default() },
            BudgetKey::MapCells,
            "limits.map_cells = 16384 cells",
        ),
        (LimitsConfig { memory_mib: 1, ..Default::default() }, BudgetKey::MemoryMib, "limits.memory_mib = 1 MiB"),
    ] {
        let (mut e, a, _) = engine();
        e.set_limits(&limits);
        let short = LaserScan { stamp: Stamp(1), angle_min: 0.0, angle_increment: 0.5, ranges: vec![1.0; 13] };
        e.insert_scan(a, &short, Pose2::IDENTITY).unwrap();
        let far = Pose2::new(100.0, 0.0, 0.0);
        let mut err = e.insert_scan(a, &scan(2), far).err();
        // 1 MiB holds about 60 tiles: walk on until the budget is met.
        for k in 3..200 {
            err = err.or_else(|| e.insert_scan(a, &scan(k), Pose2::new(100.0 * k as f64, 0.0, 0.0)).err());
        }
        let err = err.expect("the budget is met");
        assert!(matches!(err, EngineError::MapBudget { key: k, .. } if k == key), "{err:?}");
        let msg = err.to_string();
        assert!(msg.contains(text) && msg.contains(&format!("raise {}", budget_key(key))), "{msg}");
        let budget = e.budget.expect("set");
        assert!(e.grid().tile_count() <= budget.tiles);
        assert!(e.grid().tile_count() * budget.bytes_per_tile <= limits.memory_bytes() as usize);
    }
}

#[test]
fn a_camera_with_many_classes_and_the_dynamic_layer_shrink_the_tiles_a_map_may_hold() {
    let (mut e, _, _) = engine();
    e.set_limits(&LimitsConfig::default());
    let lidar_only = e.budget.expect("set").tiles;
    e.set_dynamic(crate::grid::DynamicParams::default(), false);
    let dynamic = e.budget.expect("set").tiles;
    // Each tile also reserves its export (see budget.rs), the same for both.
    use crate::fusion::budget::TileLayers;
    let bytes = |l: TileLayers| l.tile_bytes() + l.export_bytes();
    let memory = LimitsConfig::default().memory_bytes() as usize;
    assert_eq!(lidar_only, memory / bytes(TileLayers::default()));
    assert_eq!(dynamic, memory / bytes(TileLayers { dynamic: true, ..Default::default() }));
    assert!(3 * dynamic < 2 * lidar_only, "{dynamic} vs {lidar_only}");
}

#[test]
fn the_memory_in_use_is_the_tiles_with_their_export_and_stays_within_the_limit() {
    let (mut e, a, _) = engine();
    assert_eq!(e.memory_use(), None, "no limits, no budget");
    let limits = LimitsConfig { memory_mib: 1, ..Default::default() };
    e.set_limits(&limits);
    assert_eq!(e.memory_use(), Some((0, 1 << 20)));
    e.insert_scan(a, &scan(1), Pose2::IDENTITY).unwrap();
    let tiles = e.grid().tile_count();
    assert!(tiles > 0);
    use crate::fusion::budget::TileLayers;
    let per_tile = (TileLayers::default().tile_bytes() + TileLayers::default().export_bytes()) as u64;
    assert_eq!(e.memory_use(), Some((tiles as u64 * per_tile, 1 << 20)));
    // Grown until the budget refuses: what is in use never passes the limit.
    let mut refused = false;
    for k in 2..200 {
        if e.insert_scan(a, &scan(k), Pose2::new(100.0 * k as f64, 0.0, 0.0)).is_err() {
            refused = true;
            break;
        }
        let (used, limit) = e.memory_use().unwrap();
        assert!(used <= limit, "{used} > {limit} after {k} scans");
    }
    assert!(refused, "1 MiB holds about 60 tiles: the budget is met");
    let (held, per_cell) = e.export_room(e.maps().primary()).unwrap();
    assert_eq!(held, (1 << 20) - e.grid().tile_count() as u64 * TileLayers::default().tile_bytes() as u64);
    assert_eq!(per_cell, 9);
}

mod observed {
    use super::*;
    use crate::geometry::{PlanarMount, Point2};
    use crate::grid::{GridGeometry, OccupancyParams};
    use crate::measurement::Ray;
    use crate::sensor::LidarParams;

    fn engine() -> (Engine, SensorId, SensorId) {
        let grid = FusionGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let mut e = Engine::new(grid);
        let lidar = e.add_lidar("laser", LidarModel::new(LidarParams::default(), PlanarMount::default()));
        let camera = e.add_sensor("camera", SensorModel::External(SensorKind::Camera));
        (e, lidar, camera)
    }

    fn scan(t: i64) -> LaserScan {
        LaserScan { stamp: Stamp(t), angle_min: 0.0, angle_increment: 0.1, ranges: vec![1.0, 2.0, f32::NAN] }
    }

    fn frame(sensor: SensorId, t: i64) -> RangeData {
        let rays = vec![Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(0.0, 1.0), hit: true }];
        RangeData { stamp: Stamp(t), sensor, rays, evidence: Evidence { p_hit: 0.7, p_miss: 0.45 } }
    }

    #[test]
    fn an_id_shared_by_two_sensors_of_one_instant_is_counted() {
        let (mut e, lidar, camera) = engine();
        let p = |_| Pose2::IDENTITY;
        e.insert_scan_observed(lidar, ObservationId(1), &scan(10), f32::NAN, f32::NAN, p).unwrap();
        e.insert_range_data_observed(ObservationId(1), &frame(camera, 10)).unwrap();
        assert_eq!(e.stats().shared_ids, 1);
        // Another id at the same instant is not shared; the same id at a later instant is
        // a new instant's observation.
        e.insert_range_data_observed(ObservationId(2), &frame(camera, 10)).unwrap();
        e.insert_scan_observed(lidar, ObservationId(1), &scan(11), f32::NAN, f32::NAN, p).unwrap();
        assert_eq!(e.stats().shared_ids, 1);
        e.insert_range_data_observed(ObservationId(1), &frame(camera, 11)).unwrap();
        // Observations without an id never count as shared.
        e.insert_scan(lidar, &scan(11), Pose2::IDENTITY).unwrap();
        e.insert_range_data(&frame(camera, 11)).unwrap();
        assert_eq!(e.stats().shared_ids, 2);
        let s: Vec<_> = e.sensor_stats().cloned().collect();
        assert_eq!((s[0].shared_ids, s[1].shared_ids), (0, 2));
        // Both were still inserted as observations of their own.
        assert_eq!(e.stats().measurements, 7);
        assert_eq!(e.grid().observations(), 7);
    }

    #[test]
    fn per_sensor_counters_on_every_insert_path() {
        let (mut e, lidar, camera) = engine();
        let p = |_| Pose2::IDENTITY;
        e.insert_scan(lidar, &scan(1), Pose2::IDENTITY).unwrap();
        e.insert_scan_with(lidar, &scan(2), p).unwrap();
        e.insert_scan_limited(lidar, &scan(3), 0.0, 1.5, p).unwrap();
        e.insert_scan_observed(lidar, ObservationId(4), &scan(4), f32::NAN, f32::NAN, p).unwrap();
        e.insert_range_data(&frame(camera, 5)).unwrap();
        e.insert_range_data_observed(ObservationId(6), &frame(camera, 6)).unwrap();
        // Refusals: out of order on both paths, and a camera has no lidar model.
        assert!(matches!(e.insert_scan(lidar, &scan(0), Pose2::IDENTITY), Err(EngineError::OutOfOrder { .. })));
        assert!(matches!(e.insert_range_data(&frame(camera, 0)), Err(EngineError::OutOfOrder { .. })));
        assert!(matches!(e.insert_scan(camera, &scan(9), Pose2::IDENTITY), Err(EngineError::WrongModel { .. })));
        assert!(matches!(e.insert_range_data(&frame(SensorId(5), 9)), Err(EngineError::UnknownSensor(_))));
        let s: Vec<_> = e.sensor_stats().cloned().collect();
        assert_eq!((s[0].scans, s[1].scans), (4, 2));
        assert_eq!((s[0].out_of_order, s[1].out_of_order), (1, 1));
        assert_eq!((s[0].maps_fed, s[1].maps_fed), (4, 2));
        // Four scans of three beams: two valid each, but range 2.0 is a no-return under
        // the stated range_max of 1.5; one NaN each.
        assert_eq!(s[0].returns.valid, 7);
        assert_eq!(s[0].returns.no_return, 1);
        assert_eq!(s[0].returns.nan, 4);
        assert_eq!(s[0].insert.rays, 7);
        assert_eq!(s[1].insert.rays, 2);
        assert_eq!(s[1].insert.hit_updates, 2);
        assert_eq!(s[1].kind, SensorKind::Camera);
        // The sensors' counters add up to the engine's.
        let mut sum = InsertStats::default();
        sum.add(&s[0].insert);
        sum.add(&s[1].insert);
        assert_eq!(sum, e.stats().insert);
        assert_eq!(e.stats().measurements, 6);
        assert_eq!(e.stats().out_of_order, 2);
        assert_eq!(e.stats().unknown_sensor, 2);
        assert_eq!(e.sensor_kind(camera), Some(SensorKind::Camera));
        assert!(e.lidar_model(camera).is_none() && e.lidar_model(lidar).is_some());
    }
}

/// The engine walks a large scan in waves of tiles when its pool has two threads or more
/// (`grid::tile_waves`): the first 12 scans of the bench's box world (1,081 beams, about
/// 800,000 cell visits each, the pass-through rule on) give the one-thread map to the bit,
/// its tiles in the same order, and the same counts, on 2 and 4 threads.
#[cfg(feature = "parallel")]
#[test]
fn scans_in_waves_give_the_serial_map() {
    use crate::sensor::LidarModel;
    let w = crate::sim::workload_prefix('c', 12).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let params =
                OccupancyParams { pass_through: crate::grid::PassThroughParams::default(), ..Default::default() };
            let mut e = Engine::new(FusionGrid::new(GridGeometry::centered(w.resolution).unwrap(), params));
            let laser = e.add_lidar("laser", LidarModel::new(w.lidar, PlanarMount::default()));
            for (scan, pose) in w.run.scans.iter().zip(&w.run.poses) {
                e.insert_scan(laser, scan, *pose).unwrap();
            }
            let cells: Vec<(crate::grid::TileKey, Vec<Option<u32>>)> = e
                .grid()
                .tiles()
                .map(|(k, t)| (k, (0..crate::grid::TILE_CELLS).map(|o| t.log_odds(o).map(f32::to_bits)).collect()))
                .collect();
            (cells, e.grid().known_box(), e.stats().insert)
        })
    };
    let one = run(1);
    assert!(
        one.2.cell_visits > 12 * crate::grid::PARALLEL_MIN_CELLS && one.2.cell_visits_attenuated > 0,
        "{:?}",
        one.2
    );
    assert!(run(2) == one, "2 threads");
    assert!(run(4) == one, "4 threads");
}
