//! A camera frame through the engine: what each layer receives.

use super::camera::cell_semantics;
use super::*;
use crate::geometry::{Point2, Pose2};
use crate::grid::{CellIndex, DynamicParams, FusionGrid, GridGeometry, OccupancyParams, Ternary};
use crate::sensor::camera::{optical_mount, CameraModel, CameraParams, ClassTable, DepthImage, LabelImage, Pinhole};
use crate::time::Stamp;

const FLOOR: u16 = 1;
const WALL: u16 = 2;
const PERSON: u16 = 6;

fn model() -> CameraModel {
    let pinhole = Pinhole { width: 160, height: 120, fx: 110.0, fy: 110.0, cx: 80.0, cy: 60.0 };
    let mount = optical_mount([0.0, 0.0, 1.0], 0.0, 25f64.to_radians());
    CameraModel::new(pinhole, mount, CameraParams::default(), 0.05, ClassTable::production_default()).unwrap()
}

/// Renders the camera's view of a floor and a wall across x = `wall_x` (4 m high),
/// labelling pixels of the wall with `y` in `person` as a person instead.
fn render(m: &CameraModel, wall_x: f64, person: std::ops::Range<f64>) -> (LabelImage, DepthImage) {
    let p = *m.pinhole();
    let mount = *m.base_from_optical();
    let t = mount.translation;
    let (mut labels, mut depth) = (Vec::new(), Vec::new());
    for v in 0..p.height {
        for u in 0..p.width {
            let r = mount.rotate([(f64::from(u) - p.cx) / p.fx, (f64::from(v) - p.cy) / p.fy, 1.0]);
            let floor = (r[2] < 0.0).then(|| -t[2] / r[2]);
            let wall = (r[0] > 0.0).then(|| (wall_x - t[0]) / r[0]).filter(|s| t[2] + s * r[2] <= 4.0);
            let (s, label) = match (floor, wall) {
                (Some(f), Some(w)) if w < f => (w, WALL),
                (Some(f), _) => (f, FLOOR),
                (None, Some(w)) => (w, WALL),
                (None, None) => (f64::NAN, 7),
            };
            let y = t[1] + s * r[1];
            let label = if label == WALL && person.contains(&y) { PERSON } else { label };
            labels.push(label);
            depth.push(s as f32);
        }
    }
    (LabelImage::new(p.width, p.height, labels).unwrap(), DepthImage::new(p.width, p.height, depth).unwrap())
}

fn engine() -> (Engine, crate::measurement::SensorId) {
    let mut e = Engine::new(FusionGrid::new(GridGeometry::centered(0.05).unwrap(), OccupancyParams::default()));
    let id = e.add_camera("camera", model());
    (e, id)
}

#[test]
fn a_frame_writes_weak_occupancy_and_the_semantic_layer() {
    let (mut e, cam) = engine();
    let m = model();
    let (labels, depth) = render(&m, 3.0, 99.0..100.0);
    for k in 0..20 {
        e.insert_camera_frame(cam, None, Stamp(k * 100_000_000), &labels, &depth, Pose2::IDENTITY).unwrap();
    }
    let g = e.grid();
    let at = |x: f64, y: f64| g.geometry().cell_of(Point2::new(x, y)).unwrap();
    // The wall face (x just beyond 3 m) is occupied after repeated looks, the floor in
    // front of it free, and the wall's class is `wall`.
    let wall = at(3.01, 0.0);
    assert_eq!(g.ternary(wall), Ternary::Occupied, "{:?}", g.log_odds(wall));
    assert_eq!(g.ternary(at(2.5, 0.0)), Ternary::Free);
    let eligible: Vec<bool> = m.classes().iter().map(|c| !c.ignore).collect();
    let mut probs = vec![0.0; eligible.len()];
    let (tile, offset) = g.tile_of(wall).unwrap();
    let (best, p) = cell_semantics(tile, offset, &eligible, &mut probs).unwrap();
    assert_eq!(m.classes().get(best as u8).id, WALL);
    assert!(p > 0.7, "{p}");
    // Floor cells that received pixels (at the stride, not every floor cell does; the
    // others are free by the camera's rays) are `floor`.
    let mut floor_cells = 0;
    for i in 0..25 {
        let (tile, offset) = g.tile_of(at(1.5 + 0.05 * i as f64, 0.0)).unwrap();
        if let Some((best, _)) = cell_semantics(tile, offset, &eligible, &mut probs) {
            assert_eq!(m.classes().get(best as u8).id, FLOOR);
            floor_cells += 1;
        }
    }
    assert!(floor_cells >= 3, "{floor_cells}");
    // One frame is one look per cell: the wall cell moved by at most one frame's evidence
    // per frame (occupancy_weight · logit(0.7) ≤ 0.43).
    let s = e.sensor_stats().next().unwrap();
    assert_eq!(s.scans, 20);
    assert!(s.pixels.used > 0 && s.pixels.used <= s.pixels.seen);
}

#[test]
fn a_person_writes_the_dynamic_layer_never_the_static_one() {
    let (mut e, cam) = engine();
    e.set_dynamic(DynamicParams::default(), true);
    let m = model();
    let (labels, depth) = render(&m, 3.0, -0.3..0.3);
    let t = Stamp(0);
    e.insert_camera_frame(cam, None, t, &labels, &depth, Pose2::IDENTITY).unwrap();
    let g = e.grid();
    let person = g.geometry().cell_of(Point2::new(3.01, 0.0)).unwrap();
    assert_eq!(g.log_odds(person), None, "no static evidence where only the person was seen");
    let (tile, offset) = g.tile_of(person).unwrap();
    assert!(tile.layers().dynamic().unwrap().log_odds_at(offset, t, 2.0).unwrap() > 0.2);
    // The wall beside the person is static.
    let wall = g.geometry().cell_of(Point2::new(3.01, 1.0)).unwrap();
    assert!(g.log_odds(wall).unwrap() > 0.0);
}

#[test]
fn frames_that_do_not_fit_the_camera_are_refused_and_counted() {
    let (mut e, cam) = engine();
    let labels = LabelImage::new(2, 2, vec![1; 4]).unwrap();
    let depth = DepthImage::new(2, 2, vec![1.0; 4]).unwrap();
    let err = e.insert_camera_frame(cam, None, Stamp(0), &labels, &depth, Pose2::IDENTITY).unwrap_err();
    assert!(matches!(err, EngineError::Camera { .. }), "{err}");
    assert_eq!(e.sensor_stats().next().unwrap().frames_refused, 1);
    assert_eq!(e.stats().measurements, 0);
    let _ = CellIndex::new(0, 0);
}

#[test]
fn the_layers_as_rasters() {
    let (mut e, cam) = engine();
    e.set_dynamic(DynamicParams::default(), true);
    let m = model();
    let (labels, depth) = render(&m, 3.0, -0.3..0.3);
    for k in 0..5 {
        e.insert_camera_frame(cam, None, Stamp(k * 100_000_000), &labels, &depth, Pose2::IDENTITY).unwrap();
    }
    let g = e.grid();
    let area = g.known_box().unwrap();
    let s = super::rasters::semantic_cells(g, area, m.classes());
    let wall = g.geometry().cell_of(Point2::new(3.01, 1.0)).unwrap();
    let idx = |r: &crate::grid::CellRaster<_>, c: CellIndex| {
        ((c.y - r.first_cell.y) as usize) * r.width + (c.x - r.first_cell.x) as usize
    };
    let i = idx(&s.best, wall);
    assert_eq!(m.classes().get(s.best.cells[i] as u8).id, WALL);
    let sum: f32 = s.probs[i * s.classes..(i + 1) * s.classes].iter().sum();
    assert!((sum - 1.0).abs() < 1e-5 && s.prob[i] > 0.5);
    // The person's cells: dynamic now, unknown (decayed to nothing) a minute later.
    let person = g.geometry().cell_of(Point2::new(3.01, 0.0)).unwrap();
    let now = super::rasters::dynamic_cells(g, area, Stamp(400_000_000), 2.0);
    let j = ((person.y - now.first_cell.y) as usize) * now.width + (person.x - now.first_cell.x) as usize;
    assert!(now.known[j] && now.cells[j] > 0.65, "{}", now.cells[j]);
    let later = super::rasters::dynamic_cells(g, area, Stamp(60_000_000_000), 2.0);
    assert!((later.cells[j] - 0.5).abs() < 0.01);
}

/// Every stored value of a map (occupancy and semantic counts, as bits) with its tile key.
fn fingerprint(g: &FusionGrid, k: usize) -> Vec<(crate::grid::TileKey, Vec<u32>)> {
    g.tiles()
        .map(|(key, t)| {
            let mut bits = Vec::new();
            for o in 0..crate::grid::TILE_CELLS {
                bits.push(t.log_odds(o).map_or(u32::MAX, f32::to_bits));
                bits.extend(t.layers().semantic_counts(o, k).unwrap_or_default().iter().map(|v| v.to_bits()));
            }
            (key, bits)
        })
        .collect()
}

/// A pass's maps are updated on the pool's threads, one thread per map: fused, camera-only
/// and lidar-only maps, and a coarser fused map (whose camera cells are built apart), with
/// the lidar and the camera in one correlation group and the dynamic layer on, are the
/// same to the bit on 1, 2 and 4 threads; on 2 and 4, each scan is also walked in waves of
/// tiles (see `grid::tile_waves`), the group merge and the dynamic layer with it.
#[cfg(feature = "parallel")]
#[test]
fn a_pass_maps_bit_identical_on_one_two_and_four_threads() {
    use crate::fusion::{Correlation, MapSet, SensorSelection};
    use crate::geometry::PlanarMount;
    use crate::grid::MergeRule;
    use crate::measurement::{ObservationId, SensorKind};
    use crate::sensor::{LaserScan, LidarModel, LidarParams};
    let m = model();
    let k = m.classes().len();
    let frames: Vec<_> = (0..6).map(|i| render(&m, 3.0 + 0.2 * i as f64, -0.3..0.3)).collect();
    let on = |threads: usize, map_cells: Option<u64>| {
        let fine = || FusionGrid::new(GridGeometry::centered(0.05).unwrap(), OccupancyParams::default());
        let coarse = FusionGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let maps = MapSet::new("fused", SensorSelection::All, fine())
            .with("camera", SensorSelection::Kinds(vec![SensorKind::Camera]), fine())
            .with("lidar", SensorSelection::Kinds(vec![SensorKind::Lidar]), fine())
            .with("coarse", SensorSelection::All, coarse);
        let mut e = Engine::with_maps(maps);
        let cam = e.add_camera("camera", model());
        let laser = e.add_lidar("laser", LidarModel::new(LidarParams::default(), PlanarMount::default()));
        e.set_correlation(Correlation { groups: vec![vec![cam, laser]], window_ns: 50_000_000, rule: MergeRule::Max });
        e.set_dynamic(DynamicParams::default(), true);
        if threads > 1 {
            e.set_waves_min_cells(0);
        }
        if let Some(map_cells) = map_cells {
            e.set_limits(&crate::config::LimitsConfig { map_cells, ..Default::default() });
        }
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        // The first refusal (a map past `limits.map_cells`) ends the pass, as in a run.
        let refused = pool.install(|| -> Result<(), String> {
            for (i, (labels, depth)) in frames.iter().enumerate() {
                let (t, pose) = (Stamp(i as i64 * 100_000_000), Pose2::new(0.1 * i as f64, 0.05 * i as f64, 0.02));
                let id = Some(ObservationId(i as u64));
                e.insert_camera_frame(cam, id, t, labels, depth, pose).map_err(|e| format!("frame {i}: {e}"))?;
                let ranges = (0..181).map(|b| 2.5 + 0.01 * ((b * 7 + i) % 13) as f32).collect();
                let scan = LaserScan { stamp: t, angle_min: -1.57, angle_increment: 0.01745, ranges };
                e.insert_scan_observed(laser, ObservationId(i as u64), &scan, f32::NAN, f32::NAN, |_| pose)
                    .map_err(|e| format!("scan {i}: {e}"))?;
            }
            Ok(())
        });
        (refused, e.maps().iter().map(|m| fingerprint(m.grid(), k)).collect::<Vec<_>>())
    };
    let (refused, one) = on(1, None);
    assert_eq!((refused, one.len()), (Ok(()), 4));
    assert!(one.iter().all(|m| !m.is_empty()));
    assert!(one[0] != one[1] && one[0] != one[2] && one[1] != one[2], "the maps differ from one another");
    assert!(one == on(2, None).1, "2 threads");
    assert!(one == on(4, None).1, "4 threads");
    // A budget the pass outgrows part-way: the same refusal, at the same observation, with
    // the same maps up to it.
    let tight = on(1, Some(4 * 4096));
    assert!(tight.0.as_ref().is_err_and(|e| e.contains("limits.map_cells")), "{:?}", tight.0);
    assert!(tight == on(2, Some(4 * 4096)), "2 threads, over budget");
    assert!(tight == on(4, Some(4 * 4096)), "4 threads, over budget");
}
