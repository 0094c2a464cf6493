use super::*;
use crate::geometry::Point2;
use crate::grid::logodds::logit;
use crate::grid::{CellIndex, CellRay, GridGeometry, LogOddsTable, OccupancyGrid, OccupancyParams, Ternary};
use crate::grid::{TILE_CELLS, TILE_SIZE};
use crate::measurement::{Evidence, RangeData, Ray, SensorId};
use crate::time::Stamp;
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

fn grid(rule: PassThroughParams) -> OccupancyGrid {
    let params = OccupancyParams { pass_through: rule, ..OccupancyParams::default() };
    OccupancyGrid::new(GridGeometry::centered(1.0).unwrap(), params)
}

fn data(rays: Vec<Ray>) -> RangeData {
    RangeData { stamp: Stamp::ZERO, sensor: SensorId(0), rays, evidence: Evidence { p_hit: 0.9, p_miss: 0.4 } }
}

fn ray(ex: f64, hit: bool) -> Ray {
    Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(ex, 0.0), hit }
}

const PILLAR: CellIndex = CellIndex { x: 5, y: 0 };

/// Scans needed, by the module docs' bound, for a cell at the upper clamp crossed by
/// misses only to leave the occupied state.
fn clearing_bound(p: &OccupancyParams, rule: &PassThroughParams) -> usize {
    let t = LogOddsTable::new(p);
    let d = -(t.increment(0.4) as f64);
    let (l_max, l_thr, l_occ) = (t.max as f64, logit(rule.threshold), logit(p.occupied_threshold));
    ((l_max - l_thr) / (rule.weight * d)).ceil() as usize + ((l_thr - l_occ) / d).ceil() as usize
}

/// A pillar held occupied: one scan in ten hits it, the other nine carry a flying point
/// whose ray passes through it to a ghost 15 cells behind. Returns the lowest
/// probability the pillar cell had after any scan.
fn pillar_run(rule: PassThroughParams, scans: usize) -> f64 {
    let mut g = grid(rule);
    for _ in 0..3 {
        g.insert(&data(vec![ray(5.0, true)]));
    }
    let mut lowest = 1.0f64;
    for k in 0..scans {
        let r = if k % 10 == 9 { ray(5.0, true) } else { ray(20.0, true) };
        g.insert(&data(vec![r]));
        lowest = lowest.min(g.probability(PILLAR));
    }
    lowest
}

#[test]
fn a_pillar_survives_its_flying_points_only_with_the_rule() {
    let occupied = OccupancyParams::default().occupied_threshold;
    let with = pillar_run(PassThroughParams::default(), 200);
    let without = pillar_run(PassThroughParams::OFF, 200);
    assert!(with > occupied, "with the rule the pillar stays occupied (lowest p = {with})");
    assert!(without < occupied, "without it the ghosts erase the pillar (lowest p = {without})");
}

#[test]
fn a_door_that_opened_still_clears_within_the_bound() {
    for rule in [PassThroughParams::default(), PassThroughParams { weight: 0.1, ..Default::default() }] {
        let p = OccupancyParams { pass_through: rule, ..OccupancyParams::default() };
        let mut g = grid(rule);
        // The closed door, seen until it sits at the clamp.
        for _ in 0..5 {
            g.insert(&data(vec![ray(5.0, true)]));
        }
        assert_eq!(g.log_odds(PILLAR), Some(g.table().max));
        // Opened: every later ray passes through it to the room behind, none hits it.
        let bound = clearing_bound(&p, &rule);
        let mut cleared_after = None;
        for k in 1..=bound + 5 {
            g.insert(&data(vec![ray(20.0, true)]));
            if cleared_after.is_none() && g.ternary(PILLAR) != Ternary::Occupied {
                cleared_after = Some(k);
            }
        }
        let k = cleared_after.expect("the opened door leaves the occupied state");
        assert!(k <= bound, "cleared after {k} scans, bound {bound}");
        // Without the rule it takes fewer scans, with it at most twice as many here.
        let off = clearing_bound(&p, &PassThroughParams { weight: 1.0, ..rule });
        assert!(k > off && k <= 2 * off + 4, "{k} scans vs {off} without the rule");
        // And it keeps going: the door ends free.
        for _ in 0..20 {
            g.insert(&data(vec![ray(20.0, true)]));
        }
        assert_eq!(g.ternary(PILLAR), Ternary::Free);
    }
}

#[test]
fn a_ray_ending_within_the_margin_is_a_plain_miss() {
    let rule = PassThroughParams::default();
    let mut g = grid(rule);
    for _ in 0..5 {
        g.insert(&data(vec![ray(5.0, true)]));
    }
    let before = g.log_odds(PILLAR).unwrap();
    let d = g.table().increment(0.4);
    // Ends 3 cells behind (= the margin): the full miss.
    let s = g.insert(&data(vec![ray(5.0 + rule.margin_cells as f64, true)]));
    assert_eq!(g.log_odds(PILLAR), Some(g.table().update(before, d)));
    assert_eq!(s.cell_visits_attenuated, 0);
    // Ends 4 cells behind: a quarter of it on the pillar and the observed cells after it.
    let before = g.log_odds(PILLAR).unwrap();
    let near = g.log_odds(CellIndex::new(2, 0)).unwrap();
    let s = g.insert(&data(vec![ray(6.0 + rule.margin_cells as f64, true)]));
    let quarter = (rule.weight * d as f64) as f32;
    assert_eq!(g.log_odds(PILLAR), Some(g.table().update(before, quarter)));
    // Visits of cells 5 to 9 (the end cell 9, the hit, is visited but not updated).
    assert_eq!(s.cell_visits_attenuated, 5);
    assert_eq!(g.log_odds(CellIndex::new(7, 0)), Some(g.table().update(d, quarter)));
    // The cells before it got the full miss.
    assert_eq!(g.log_odds(CellIndex::new(2, 0)), Some(g.table().update(near, d)));
}

#[test]
fn a_cell_below_the_threshold_shields_nothing() {
    let mut g = grid(PassThroughParams::default());
    // One hit: p = 0.9 < 0.95.
    g.insert(&data(vec![ray(5.0, true)]));
    let s = g.insert(&data(vec![ray(20.0, true)]));
    assert_eq!(s.cell_visits_attenuated, 0);
    let t = *g.table();
    assert_eq!(g.log_odds(PILLAR), Some(t.update(t.increment(0.9), t.increment(0.4))));
}

/// The rule's semantics written the slow way: per observation, hits first; then each ray
/// in order, each of its cells in order, reading the map as it stands at that visit.
fn reference(observations: &[Vec<Ray>], table: &LogOddsTable, rule: &PassThroughParams) -> HashMap<CellIndex, f32> {
    let g = GridGeometry::centered(1.0).unwrap();
    let mut cells: HashMap<CellIndex, f32> = HashMap::new();
    let (d_hit, d_miss) = (table.increment(0.9), table.increment(0.4));
    let d_pass = (rule.weight * d_miss as f64) as f32;
    let confident = logit(rule.threshold) as f32;
    let free = logit(OccupancyParams::default().free_threshold) as f32;
    for rays in observations {
        let mut done: HashSet<CellIndex> = HashSet::new();
        // Hit cells are marked first; each ray's hit is applied at the end of its walk.
        let first: Vec<bool> = rays.iter().map(|r| r.hit && done.insert(g.cell_of(r.end).unwrap())).collect();
        for (i, r) in rays.iter().enumerate() {
            let walk: Vec<CellIndex> = CellRay::new(g.to_cell_units(r.origin), g.to_cell_units(r.end)).collect();
            let mut through = false;
            for (k, c) in walk.iter().enumerate() {
                let after = walk.len() - 1 - k;
                let v = cells.get(c).copied();
                let d = if rule.is_off() {
                    Some(d_miss)
                } else if through {
                    match v {
                        // Never observed, behind a confident cell: no evidence.
                        None => None,
                        // Out into known free space: a plain ray again.
                        Some(v) if v < free => {
                            through = false;
                            Some(d_miss)
                        }
                        Some(_) => Some(d_pass),
                    }
                } else if v.is_some_and(|v| v >= confident) && after > rule.margin_cells as usize {
                    through = true;
                    Some(d_pass)
                } else {
                    Some(d_miss)
                };
                if done.insert(*c) {
                    if let Some(d) = d {
                        let v = v.unwrap_or(table.prior);
                        cells.insert(*c, table.update(v, d));
                    }
                }
            }
            // Every echo counts, applied at the end of its ray.
            if first[i] {
                let c = *walk.last().unwrap();
                let v = cells.get(&c).copied().unwrap_or(table.prior);
                cells.insert(c, table.update(v, d_hit));
            }
        }
    }
    cells
}

fn ray_strategy() -> impl Strategy<Value = Ray> {
    // Few distinct end points, so that rays often cross cells earlier rays made occupied.
    (-3i32..3, -3i32..3, -12i32..12, -12i32..12, prop::bool::weighted(0.8)).prop_map(|(ox, oy, ex, ey, hit)| Ray {
        origin: Point2::new(ox as f64 + 0.3, oy as f64 + 0.6),
        end: Point2::new(ex as f64 + 0.5, ey as f64 + 0.2),
        hit,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// The tiled walk with the rule gives exactly the slow reference's values, and with the
    /// rule off exactly the plain map's (bit for bit).
    #[test]
    fn the_rule_matches_its_reference(
        observations in prop::collection::vec(prop::collection::vec(ray_strategy(), 1..10), 1..12),
        weight in prop::sample::select(vec![0.0, 0.25, 0.5, 1.0]),
        margin in 0u32..4,
    ) {
        let rule = PassThroughParams { threshold: 0.95, weight, margin_cells: margin };
        let mut g = grid(rule);
        for rays in &observations {
            g.insert(&data(rays.clone()));
        }
        let want = reference(&observations, g.table(), &rule);
        let mut seen = 0;
        for (key, tile) in g.tiles() {
            let first = key.first_cell();
            for off in 0..TILE_CELLS {
                let c = CellIndex::new(first.x + (off % TILE_SIZE) as i64, first.y + (off / TILE_SIZE) as i64);
                if let Some(l) = tile.log_odds(off) {
                    seen += 1;
                    prop_assert_eq!(Some(l.to_bits()), want.get(&c).map(|v| v.to_bits()), "cell {:?}", c);
                }
            }
        }
        prop_assert_eq!(seen, want.len());
        if rule.is_off() {
            let plain = reference(&observations, g.table(), &PassThroughParams { weight: 1.0, threshold: 1.0, margin_cells: 0 });
            prop_assert_eq!(&want, &plain);
        }
    }
}
