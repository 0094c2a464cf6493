//! Tests of the occupancy layer's insertion (see `occupancy.rs`).

use super::*;
use crate::geometry::Point2;
use crate::measurement::{Evidence, Ray, SensorId};
use crate::time::Stamp;
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

/// The map without the pass-through rule: these tests pin the plain semantics, bit
/// for bit (the rule has its own tests in `pass_through`).
fn grid() -> OccupancyGrid {
    let params = OccupancyParams { pass_through: PassThroughParams::OFF, ..OccupancyParams::default() };
    OccupancyGrid::new(GridGeometry::centered(1.0).unwrap(), params)
}

fn data(rays: Vec<Ray>) -> RangeData {
    RangeData { stamp: Stamp::ZERO, sensor: SensorId(0), rays, evidence: Evidence { p_hit: 0.9, p_miss: 0.4 } }
}

fn hit(ox: f64, oy: f64, ex: f64, ey: f64) -> Ray {
    Ray { origin: Point2::new(ox, oy), end: Point2::new(ex, ey), hit: true }
}

#[test]
fn one_ray_marks_free_then_occupied() {
    let mut g = grid();
    let s = g.insert(&data(vec![hit(0.0, 0.0, 5.0, 0.0)]));
    assert_eq!(s.hit_updates, 1);
    assert_eq!(s.miss_updates, 5);
    assert_eq!(s.cell_visits, 6);
    let t = *g.table();
    assert!((g.log_odds(CellIndex::new(5, 0)).unwrap() - t.increment(0.9)).abs() < 1e-6);
    for x in 0..5 {
        assert!((g.log_odds(CellIndex::new(x, 0)).unwrap() - t.increment(0.4)).abs() < 1e-6);
    }
    assert_eq!(g.log_odds(CellIndex::new(6, 0)), None);
    assert_eq!(g.probability(CellIndex::new(6, 0)), 0.5);
    assert_eq!(g.ternary(CellIndex::new(5, 0)), Ternary::Occupied);
    assert_eq!(g.ternary(CellIndex::new(0, 3)), Ternary::Unknown);
}

#[test]
fn each_cell_updated_once_per_observation() {
    let mut g = grid();
    // Ten identical beams are one observation of those cells.
    let s = g.insert(&data(vec![hit(0.0, 0.0, 5.0, 0.0); 10]));
    assert_eq!(s.hit_updates, 1);
    assert_eq!(s.miss_updates, 5);
    assert_eq!(s.cell_visits, 60);
    let t = *g.table();
    assert!((g.log_odds(CellIndex::new(2, 0)).unwrap() - t.increment(0.4)).abs() < 1e-6);
    // The next observation updates them again.
    g.insert(&data(vec![hit(0.0, 0.0, 5.0, 0.0)]));
    assert!((g.log_odds(CellIndex::new(2, 0)).unwrap() - 2.0 * t.increment(0.4)).abs() < 1e-6);
}

#[test]
fn occupied_wins_whatever_the_ray_order() {
    for hits_first in [true, false] {
        let mut g = grid();
        // Ray A ends at (3, 0); ray B passes through (3, 0) on its way to (6, 0).
        let a = hit(0.0, 0.0, 3.0, 0.0);
        let b = hit(0.0, 0.0, 6.0, 0.0);
        let rays = if hits_first { vec![a, b] } else { vec![b, a] };
        g.insert(&data(rays));
        let t = *g.table();
        assert!((g.log_odds(CellIndex::new(3, 0)).unwrap() - t.increment(0.9)).abs() < 1e-6);
        assert!((g.log_odds(CellIndex::new(6, 0)).unwrap() - t.increment(0.9)).abs() < 1e-6);
    }
}

#[test]
fn cleared_miss_rays_have_no_hit() {
    let mut g = grid();
    let s = g.insert(&data(vec![Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(0.0, -4.0), hit: false }]));
    assert_eq!(s.hit_updates, 0);
    assert_eq!(s.miss_updates, 5);
    assert_eq!(g.ternary(CellIndex::new(0, -4)), g.table().classify(0.4));
}

#[test]
fn corrupt_rays_are_rejected_and_counted() {
    let mut g = grid();
    let s = g.insert(&data(vec![
        hit(0.0, 0.0, f64::NAN, 0.0),
        hit(0.0, 0.0, 1e30, 0.0),
        hit(0.0, 0.0, 1e8, 0.0),
        hit(f64::INFINITY, 0.0, 1.0, 0.0),
    ]));
    assert_eq!(s.rays, 0);
    assert_eq!(s.rays_rejected, 4);
    // A refused ray gives no evidence at all, not even its hit.
    assert_eq!(s.hit_updates, 0);
    assert_eq!(g.tile_count(), 0);
    assert_eq!(g.known_box(), None);
}

#[test]
fn many_observations_never_lose_updates() {
    // Bonxai's wrapping counter lost updates after 16 scans; ours must not, however many.
    let mut g = grid();
    let t = *g.table();
    for _ in 0..300 {
        g.insert(&data(vec![hit(0.0, 0.0, 2.0, 0.0)]));
    }
    assert_eq!(g.log_odds(CellIndex::new(1, 0)), Some(t.min));
    assert_eq!(g.log_odds(CellIndex::new(2, 0)), Some(t.max));
    assert_eq!(g.observations(), 300);
}

/// The reference semantics, written the slow and obvious way: per observation, hit
/// cells get the hit update once; every other cell any ray crosses gets the miss
/// update once.
fn reference(observations: &[Vec<Ray>], table: &LogOddsTable) -> HashMap<CellIndex, f32> {
    let mut cells: HashMap<CellIndex, f32> = HashMap::new();
    let g = GridGeometry::centered(1.0).unwrap();
    for rays in observations {
        let units = |p: Point2| g.to_cell_units(p);
        let hits: HashSet<CellIndex> = rays.iter().filter(|r| r.hit).map(|r| g.cell_of(r.end).unwrap()).collect();
        let mut crossed: HashSet<CellIndex> = HashSet::new();
        for r in rays {
            crossed.extend(CellRay::new(units(r.origin), units(r.end)));
        }
        for c in &hits {
            let v = cells.get(c).copied().unwrap_or(table.prior);
            cells.insert(*c, table.update(v, table.increment(0.9)));
        }
        for c in crossed.difference(&hits) {
            let v = cells.get(c).copied().unwrap_or(table.prior);
            cells.insert(*c, table.update(v, table.increment(0.4)));
        }
    }
    cells
}

fn ray_strategy() -> impl Strategy<Value = Ray> {
    (-150.0..150.0f64, -150.0..150.0f64, -150.0..150.0f64, -150.0..150.0f64, prop::bool::ANY)
        .prop_map(|(ox, oy, ex, ey, hit)| Ray { origin: Point2::new(ox, oy), end: Point2::new(ex, ey), hit })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// The tiled, bitset-marked, tile-local walk gives exactly the reference's values,
    /// for rays that cross many tiles in every direction, negative coordinates included.
    #[test]
    fn insertion_matches_the_reference(observations in prop::collection::vec(prop::collection::vec(ray_strategy(), 1..12), 1..6)) {
        let mut g = grid();
        for rays in &observations {
            g.insert(&data(rays.clone()));
        }
        let want = reference(&observations, g.table());
        let mut seen = 0;
        for (key, tile) in g.tiles() {
            let first = key.first_cell();
            for off in 0..TILE_CELLS {
                let c = CellIndex::new(first.x + (off % TILE_SIZE) as i64, first.y + (off / TILE_SIZE) as i64);
                if let Some(l) = tile.log_odds(off) {
                    seen += 1;
                    prop_assert_eq!(Some(&l), want.get(&c), "cell {:?}", c);
                }
            }
        }
        prop_assert_eq!(seen, want.len());
    }
}

#[test]
fn grows_in_every_direction() {
    let mut g = grid();
    g.insert(&data(vec![hit(0.0, 0.0, -300.0, 0.0), hit(0.0, 0.0, 0.0, 250.0), hit(0.0, 0.0, 120.0, -90.0)]));
    let b = g.known_box().unwrap();
    assert_eq!(b.min, CellIndex::new(-300, -90));
    assert_eq!(b.max, CellIndex::new(120, 250));
    assert!(g.tile_count() > 3);
    let r = g.raster(b);
    assert_eq!(r.width, 421);
    assert_eq!(r.height, 341);
    let i = |x: i64, y: i64| ((y - b.min.y) as usize) * r.width + (x - b.min.x) as usize;
    assert!(r.known[i(-300, 0)] && r.known[i(0, 250)] && r.known[i(0, 0)]);
    assert!(!r.known[i(-300, 250)]);
    assert_eq!(r.log_odds[i(-300, 250)], g.table().prior);
    assert!((r.origin.x - (-300.5)).abs() < 1e-12 && (r.origin.y - (-90.5)).abs() < 1e-12);
}
