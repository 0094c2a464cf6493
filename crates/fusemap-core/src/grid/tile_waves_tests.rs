//! The waves give the serial walk's map to the bit (see `tile_waves.rs`).

use super::*;
use crate::geometry::Point2;
use crate::grid::{
    DynamicParams, DynamicUpdate, FusedUpdate, FusionGrid, Group, LayeredGrid, MergeRule, OccupancyParams,
    OccupancyUpdate, PassThroughParams,
};
use crate::measurement::{Evidence, RangeData, SensorId};
use crate::time::Stamp;

/// A small deterministic generator (SplitMix64), so the scans are the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Range to the walls of a square room of half-size 12 m centred on (0, 0), from `o`
/// along `a`.
fn to_wall(o: Point2, a: f64) -> f64 {
    let (c, s) = (a.cos(), a.sin());
    let along = |d: f64, p: f64| match d {
        d if d > 0.0 => (12.0 - p) / d,
        d if d < 0.0 => (-12.0 - p) / d,
        _ => f64::INFINITY,
    };
    along(c, o.x).min(along(s, o.y))
}

/// Scan `k` of a drive across the room: 2,000 beams from one point that crosses tile
/// borders, most ending on the walls, some passing through them (ghosts, so that the
/// pass-through rule has work), some no-returns, one corrupt. Scan 7 is de-skewed across
/// a tile border (its rays start in two tiles: the serial walk's case).
fn scan(k: usize, rng: &mut Rng) -> RangeData {
    const BEAMS: usize = 2000;
    let o = Point2::new(-8.0 + 0.81 * k as f64, 1.6 * (k as f64 * 0.7).sin());
    let mut rays = Vec::new();
    for b in 0..BEAMS {
        let a = b as f64 * std::f64::consts::TAU / BEAMS as f64 + 0.01 * k as f64;
        let origin = if k == 7 { Point2::new(3.2 * (2 * b / BEAMS) as f64 - 0.01, o.y) } else { o };
        let u = rng.next();
        let (range, hit) = if u < 0.1 {
            (to_wall(origin, a) + 3.0 * rng.next(), true)
        } else if u < 0.15 {
            (15.0, false)
        } else {
            (to_wall(origin, a) + 0.02 * rng.next(), true)
        };
        let end = Point2::new(origin.x + range * a.cos(), origin.y + range * a.sin());
        rays.push(Ray { origin, end, hit });
    }
    rays.push(Ray { origin: o, end: Point2::new(f64::NAN, 0.0), hit: true });
    RangeData { stamp: Stamp(k as i64), sensor: SensorId(0), rays, evidence: Evidence { p_hit: 0.9, p_miss: 0.4 } }
}

fn scans(n: usize) -> Vec<RangeData> {
    let mut rng = Rng(17);
    (0..n).map(|k| scan(k, &mut rng)).collect()
}

/// A map's tiles with their cells' log-odds bits, its known box, and its budget flag.
type Snapshot = (Vec<(TileKey, Vec<Option<u32>>)>, Option<CellBox>, bool);

/// Everything a map holds: its tiles in allocation order with every cell's log-odds
/// bits, its known box, and whether it ran past its budget.
fn snapshot<L: crate::grid::ExtraLayers>(g: &LayeredGrid<L>) -> Snapshot {
    let tiles = g
        .tiles()
        .map(|(k, t)| (k, (0..crate::grid::TILE_CELLS).map(|o| t.log_odds(o).map(f32::to_bits)).collect()))
        .collect();
    (tiles, g.known_box(), g.over_budget())
}

fn params(rule: bool) -> OccupancyParams {
    let pass_through = if rule { PassThroughParams::default() } else { PassThroughParams::OFF };
    OccupancyParams { pass_through, ..OccupancyParams::default() }
}

/// Inserts `data` into a fresh map, in waves (`min_cells` 0) or serially (`u64::MAX`).
fn run(data: &[RangeData], rule: bool, min_cells: u64) -> (crate::grid::OccupancyGrid, Vec<InsertStats>) {
    let mut g = LayeredGrid::new(GridGeometry::centered(0.05).unwrap(), params(rule));
    let stats = data.iter().map(|d| g.insert_in_waves(d, min_cells)).collect();
    (g, stats)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
}

#[test]
fn waves_give_the_serial_map_to_the_bit_on_one_two_and_four_threads() {
    let data = scans(12);
    for rule in [true, false] {
        let (serial, serial_stats) = run(&data, rule, u64::MAX);
        let total: InsertStats = serial_stats.iter().fold(InsertStats::default(), |mut a, s| {
            a.add(s);
            a
        });
        // The rule, the once-per-observation marks and the rejections all had work.
        assert_eq!(total.rays_rejected, 12);
        assert!(total.miss_updates + total.hit_updates < total.cell_visits * 3 / 4, "{total:?}");
        if rule {
            assert!(total.ghost_hits > 50 && total.cell_visits_attenuated > 5_000, "{total:?}");
        }
        for threads in [1, 2, 4] {
            let (waves, stats) = pool(threads).install(|| run(&data, rule, 0));
            assert_eq!(stats, serial_stats, "rule {rule}, {threads} threads");
            assert!(snapshot(&waves) == snapshot(&serial), "rule {rule}, {threads} threads: the maps differ");
        }
    }
}

#[test]
fn rays_from_several_tiles_and_small_observations_take_the_serial_walk() {
    let data = scans(8);
    let mut g = LayeredGrid::<()>::new(GridGeometry::centered(0.05).unwrap(), params(true));
    let geometry = *g.geometry();
    let mut tiles: TileMap<crate::grid::MapTile<()>> = TileMap::new();
    let mut known = None;
    let mut v = OccupancyUpdate::new(*g.table(), data[7].evidence);
    // Scan 7 starts in two tiles; scan 0 has fewer cells than asked for.
    assert!(walk_observation_waves(&mut tiles, &geometry, 1, &data[7].rays, &mut known, &mut v, 0).is_none());
    assert!(walk_observation_waves(&mut tiles, &geometry, 1, &data[0].rays, &mut known, &mut v, u64::MAX - 1).is_none());
    assert!(tiles.is_empty() && known.is_none());
    assert!(walk_observation_waves(&mut tiles, &geometry, 1, &data[0].rays, &mut known, &mut v, 0).is_some());
    assert!(!tiles.is_empty() && known.is_some());
    // What `insert` decides on one thread: the serial walk, whatever the size.
    assert_eq!(pool(1).install(crate::grid::waves_threshold), u64::MAX);
    assert_eq!(pool(2).install(crate::grid::waves_threshold), PARALLEL_MIN_CELLS);
    g.insert(&data[0]);
}

/// Near its tile budget a map is walked serially (what a map past its budget holds is the
/// serial walk's: which tiles it still gets, and the scratch tile the rest share), so the
/// refusal comes on the same observation with the same maps and counts up to it.
#[test]
fn near_the_tile_budget_the_waves_give_way_to_the_serial_walk() {
    // The room moves 6 m a scan, so the map keeps growing: the first scans are walked in
    // waves while the budget has room for their bounding box (130 tiles), the rest not.
    let mut data = scans(12);
    for (k, d) in data.iter_mut().enumerate() {
        for r in &mut d.rays {
            r.origin.x += 6.0 * k as f64;
            r.end.x += 6.0 * k as f64;
        }
    }
    for budget in [1, 20, 90, 200, 300] {
        let run = |min_cells: u64| {
            let mut g = LayeredGrid::<()>::new(GridGeometry::centered(0.05).unwrap(), params(true));
            g.set_tile_budget(budget);
            let mut stats = Vec::new();
            for d in &data {
                stats.push(g.insert_in_waves(d, min_cells));
                if g.over_budget() {
                    break;
                }
            }
            (snapshot(&g), stats)
        };
        let serial = run(u64::MAX);
        assert!(serial.0 .2, "budget {budget} is not reached");
        assert!(pool(2).install(|| run(0)) == serial, "budget {budget}");
    }
    // The rule itself: room for the tiles of the rays' bounding box, or the serial walk.
    let geometry = GridGeometry::centered(0.05).unwrap();
    let rays = &data[0].rays;
    let tile = |p: Point2| geometry.cell_of(p).unwrap().tile();
    let ends: Vec<TileKey> = rays.iter().filter(|r| r.end.x.is_finite()).map(|r| tile(r.end)).collect();
    let span = |f: fn(&TileKey) -> i64| {
        let (lo, hi) = (ends.iter().map(f).min().unwrap(), ends.iter().map(f).max().unwrap());
        (hi - lo + 1) as usize
    };
    let box_tiles = span(|t| t.x) * span(|t| t.y);
    for (budget, waves) in [(box_tiles - 1, false), (box_tiles, true)] {
        let mut tiles: TileMap<crate::grid::MapTile<()>> = TileMap::new();
        tiles.set_tile_budget(budget);
        let mut v = OccupancyUpdate::new(*LayeredGrid::<()>::new(geometry, params(true)).table(), data[0].evidence);
        let walked = walk_observation_waves(&mut tiles, &geometry, 1, rays, &mut None, &mut v, 0);
        assert_eq!(walked.is_some(), waves, "budget {budget}, box {box_tiles}");
    }
}

/// The fusion map's update (a correlation group's merge and the dynamic layer's routing
/// and clearing) in waves, against the same serially.
#[test]
fn the_fused_update_in_waves_gives_the_serial_layers() {
    let data = scans(10);
    let dyn_params = DynamicParams::default();
    let run = |min_cells: u64| {
        let mut g = FusionGrid::new(GridGeometry::centered(0.05).unwrap(), params(true));
        let mut counts = Vec::new();
        for (k, d) in data.iter().enumerate() {
            let now = Stamp(k as i64 * 100_000_000);
            let dy = DynamicUpdate::new(&dyn_params, now);
            // A moving object on part of the far wall, written as the camera would.
            let obs = g.begin_observation();
            for x in -60..60 {
                let cell = g.geometry().cell_of(Point2::new(0.05 * x as f64, 11.99)).unwrap();
                if let Some((tile, offset, _)) = g.cell_mut(cell, obs) {
                    dy.apply(&mut tile.layers_mut().dynamic, offset, dy.d_hit());
                }
            }
            // Pairs of scans are correlated members of one group.
            let group = Some(Group { id: 1 + k as u64 / 2, rule: MergeRule::Max });
            let rule = (&g.params().pass_through, g.params().free_threshold);
            let mut v = FusedUpdate::new(*g.table(), d.evidence, rule, group, Some(dy), true);
            let obs = g.begin_observation();
            let s = g.walk_forked(obs, &d.rays, &mut v, min_cells);
            v.finish();
            counts.push((s, v.routed, v.ghost_hits(), v.attenuated()));
        }
        let dynamic: Vec<Vec<Option<(u32, i64)>>> = g
            .tiles()
            .map(|(_, t)| {
                let b = t.layers().dynamic();
                (0..crate::grid::TILE_CELLS)
                    .map(|o| b.and_then(|b| Some((b.log_odds_at(o, Stamp(0), 1.0)?.to_bits(), b.last_update(o)?.0))))
                    .collect()
            })
            .collect();
        (snapshot(&g), dynamic, counts)
    };
    let serial = run(u64::MAX);
    assert!(serial.2.iter().map(|c| c.1).sum::<u64>() > 0, "no hit was routed to the dynamic layer");
    for threads in [1, 2] {
        assert!(pool(threads).install(|| run(0)) == serial, "{threads} threads");
    }
}

/// The benchmark's corridor (`a`, its 40 scans) and box world (`c`, its first 12 scans of
/// 1,081 beams) through the lidar model as `fusemap map` maps them, the pass-through rule
/// on: in waves on 1, 2 and 4 threads, the serial map to the bit (the fusion engine's own
/// test is `fusion::engine_tests::scans_in_waves_give_the_serial_map`).
#[test]
fn the_bench_workloads_in_waves_give_the_serial_maps() {
    use crate::geometry::PlanarMount;
    use crate::sensor::{LidarModel, ReturnCounts};
    for (name, scans) in [('a', 40), ('c', 12)] {
        let w = crate::sim::workload_prefix(name, scans).unwrap();
        let model = LidarModel::new(w.lidar, PlanarMount::default());
        let mut data = Vec::new();
        for (scan, pose) in w.run.scans.iter().zip(&w.run.poses) {
            let mut d = RangeData::empty(SensorId(0), model.evidence());
            model.scan_to_range_data(SensorId(0), scan, *pose, &mut d, &mut ReturnCounts::default());
            data.push(d);
        }
        let grid = |min_cells: u64| {
            let mut g = LayeredGrid::<()>::new(GridGeometry::centered(w.resolution).unwrap(), params(true));
            let stats: Vec<InsertStats> = data.iter().map(|d| g.insert_in_waves(d, min_cells)).collect();
            (snapshot(&g), stats)
        };
        let serial = grid(u64::MAX);
        assert!(serial.1.iter().any(|s| s.cell_visits_attenuated > 0), "workload {name}: the rule never acted");
        for threads in [1, 2, 4] {
            assert!(pool(threads).install(|| grid(0)) == serial, "workload {name}, {threads} threads");
        }
    }
}
