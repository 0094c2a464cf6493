//! The design document's scenario end to end: the production line mapped lidar-only,
//! camera-only and fused in one pass (§5.2's M1, M2, M3), and each map scored against the
//! simulator's ground truth.
//!
//! The scores are the ones the document's opening picture asks about: does the map hold
//! the walls (F1 of occupied cells, 1-cell tolerance), does it know what they are
//! (semantic accuracy per class), is the glass fence there, did a backlit shadow become a
//! wall, did the lidar's own artefacts carve the pillars and machines open, and did the
//! walking person stay out of the static map.

use crate::{PipelineError, Stage};
use fusemap_core::config::Plan;
use fusemap_core::fusion::rasters::{semantic_cells, shown_classes};
use fusemap_core::fusion::{MapSet, SensorSelection};
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellBox, CellIndex, FusionGrid, Ternary};
use fusemap_core::measurement::SensorKind;
use fusemap_core::metrics::{SemanticAccuracy, TolerantScore};
use fusemap_core::sensor::camera::ClassTable;
use fusemap_core::time::Stamp;
use fusemap_sim::{TruthRaster, TruthSemantic};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

/// The mapping configuration of the production line (`configs/production_line.toml`, a
/// link to this crate's own copy so the crate builds from its own files).
pub const PRODUCTION_LINE_CONFIG: &str = include_str!("../configs/production_line.toml");

/// The plan of [`PRODUCTION_LINE_CONFIG`].
pub fn production_line_plan() -> Result<Plan, PipelineError> {
    let cfg =
        fusemap_io::config_file::parse_config_str(PRODUCTION_LINE_CONFIG, Path::new("configs/production_line.toml"))?;
    cfg.validate()
        .map_err(|e| PipelineError::refused(Stage::Configuration, format!("configs/production_line.toml: {e}")))
}

/// The three maps of one pass: fused (every sensor, the primary map), lidar-only and
/// camera-only.
pub fn three_maps(plan: &Plan) -> MapSet {
    let grid = || FusionGrid::new(plan.geometry, plan.occupancy);
    MapSet::new("fused", SensorSelection::All, grid())
        .with("lidar", SensorSelection::Kinds(vec![SensorKind::Lidar]), grid())
        .with("camera", SensorSelection::Kinds(vec![SensorKind::Camera]), grid())
}

/// What the simulator knows that a map is scored against.
pub struct Truth<'a> {
    /// The truly occupied cells.
    pub occupancy: &'a TruthRaster,
    /// Their classes and the cells of each kind of object.
    pub semantic: &'a TruthSemantic,
    /// Where the walking person was.
    pub person: &'a [(Stamp, Point2)],
    /// The person's radius, metres.
    pub person_radius_m: f64,
}

/// One map's scores.
#[derive(Clone, Debug, Serialize)]
pub struct MapScore {
    /// The map's name.
    pub name: String,
    /// Occupied cells against the truth, 1-cell tolerance.
    pub occupied: TolerantScore,
    /// Semantic accuracy per class id, 1-cell tolerance.
    pub semantic: SemanticAccuracy,
    /// The same without tolerance: the class must be right in the true cell itself.
    pub semantic_strict: SemanticAccuracy,
    /// Every cell of the hall with semantic evidence, free ones included (their true class
    /// is the floor), no tolerance: `held` cells with evidence, `matched` whose most likely
    /// class is the true one. A misplaced label (a wall class on the floor in front of the
    /// wall) counts against it.
    pub semantic_all_cells: fusemap_core::metrics::ClassAccuracy,
    /// Share of the glass fence's cells with an occupied map cell within one cell.
    pub glass_occupied_share: f64,
    /// Cells under the backlit shadow (floor the camera mislabelled) that the map holds
    /// as occupied, away from any true obstacle.
    pub backlit_occupied_cells: usize,
    /// Share of the pillars' body cells (inside their outlines) the map holds as free.
    pub pillar_body_free_share: f64,
    /// Share of the machines' body cells the map holds as free.
    pub machine_body_free_share: f64,
    /// Cells along the person's walk the map holds as occupied, away from any true
    /// obstacle.
    pub person_static_cells: usize,
    /// Per class name, of the cells the semantic picture shows as that class
    /// ([`shown_classes`]), how many there are and the share that truly are it (within one
    /// cell for an obstacle class, in the cell itself for a floor-like one; unlabelled
    /// truth is floor). Accuracy asks whether true obstacles carry the right class;
    /// precision asks whether what the picture shows is there.
    pub class_precision: BTreeMap<String, ClassPrecision>,
}

/// One class's precision in the semantic picture.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ClassPrecision {
    /// Cells shown as the class.
    pub shown: usize,
    /// Of them, those that truly are it.
    pub correct: usize,
    /// `correct / shown`; `None` when none is shown.
    pub precision: Option<f64>,
}

impl MapScore {
    /// Semantic accuracy of the class `name` of `classes`, if the map holds any of its cells.
    pub fn semantic_of(&self, classes: &ClassTable, name: &str) -> Option<f64> {
        let idx = classes.index_by_name(name)?;
        self.semantic.classes.get(&classes.get(idx).id).and_then(|c| c.accuracy())
    }
}

/// Scores `grid` (named `name`) against `truth`; `classes` names the semantic layer's
/// classes.
pub fn score(name: &str, grid: &FusionGrid, classes: &ClassTable, truth: &Truth) -> MapScore {
    let occupied: HashSet<CellIndex> = match grid.known_box() {
        Some(b) => cells_of(b).filter(|&c| grid.ternary(c) == Ternary::Occupied).collect(),
        None => HashSet::new(),
    };
    let truth_cells: HashSet<CellIndex> = truth.occupancy.occupied_cells().collect();
    let near_truth = |c: CellIndex| neighbours(c, 1).any(|n| truth_cells.contains(&n));
    let occupied_score = TolerantScore::new(&occupied, &truth_cells, 1);

    let (predicted, all_cells) = semantic_predictions(grid, classes, truth, &occupied);
    let truth_classes: HashMap<CellIndex, u16> =
        truth_cells.iter().map(|&c| (c, truth.semantic.class_at(c) as u16)).filter(|(_, k)| *k != 0).collect();
    let semantic = SemanticAccuracy::new(&predicted, &truth_classes, 1);
    let semantic_strict = SemanticAccuracy::new(&predicted, &truth_classes, 0);

    let glass = &truth.semantic.glass_cells;
    let glass_hit = glass.iter().filter(|&&c| neighbours(c, 1).any(|n| occupied.contains(&n))).count();
    let g = grid.geometry();
    let backlit: HashSet<CellIndex> =
        truth.semantic.backlit_floor_points.iter().filter_map(|&p| g.cell_of(p)).collect();
    let backlit_occupied_cells = backlit.iter().filter(|&&c| occupied.contains(&c) && !near_truth(c)).count();
    let free_share = |cells: &[CellIndex]| {
        if cells.is_empty() {
            return 0.0;
        }
        cells.iter().filter(|&&c| grid.ternary(c) == Ternary::Free).count() as f64 / cells.len() as f64
    };
    let r_cells = (truth.person_radius_m / g.resolution()).ceil() as i64;
    let mut trail: HashSet<CellIndex> = HashSet::new();
    for &(_, p) in truth.person {
        if let Some(c) = g.cell_of(p) {
            trail.extend(neighbours(c, r_cells));
        }
    }
    let person_static_cells = trail.iter().filter(|&&c| occupied.contains(&c) && !near_truth(c)).count();
    MapScore {
        name: name.to_string(),
        occupied: occupied_score,
        semantic,
        semantic_strict,
        semantic_all_cells: all_cells,
        glass_occupied_share: if glass.is_empty() { 0.0 } else { glass_hit as f64 / glass.len() as f64 },
        backlit_occupied_cells,
        pillar_body_free_share: free_share(&truth.semantic.pillar_body_cells),
        machine_body_free_share: free_share(&truth.semantic.machine_body_cells),
        person_static_cells,
        class_precision: class_precision(grid, classes, truth),
    }
}

/// [`MapScore::class_precision`] of `grid`.
fn class_precision(grid: &FusionGrid, classes: &ClassTable, truth: &Truth) -> BTreeMap<String, ClassPrecision> {
    let mut out: BTreeMap<String, ClassPrecision> = BTreeMap::new();
    let Some(b) = grid.known_box() else { return out };
    let cells = semantic_cells(grid, b, classes);
    let shown = shown_classes(grid, &cells, classes);
    let floor = classes.index_by_name("floor").map(|i| classes.get(i).id);
    let true_id = |c: CellIndex| match truth.semantic.class_at(c) {
        0 => floor,
        k => Some(u16::from(k)),
    };
    let w = cells.best.width;
    for (i, &k) in shown.iter().enumerate().filter(|(_, &k)| k >= 0) {
        let c = CellIndex::new(cells.best.first_cell.x + (i % w) as i64, cells.best.first_cell.y + (i / w) as i64);
        let spec = classes.get(k as u8);
        let reach = if spec.p_occupied > 0.5 { 1 } else { 0 };
        let e = out.entry(spec.name.clone()).or_default();
        e.shown += 1;
        e.correct += usize::from(neighbours(c, reach).any(|n| true_id(n) == Some(spec.id)));
    }
    for e in out.values_mut() {
        e.precision = (e.shown > 0).then(|| e.correct as f64 / e.shown as f64);
    }
    out
}

/// The class each occupied cell of the map holds (what the semantic scores compare with
/// the truth), and the share of all known cells inside the truth's raster whose class is
/// right (unlabelled truth counts as floor).
fn semantic_predictions(
    grid: &FusionGrid,
    classes: &ClassTable,
    truth: &Truth,
    occupied: &HashSet<CellIndex>,
) -> (HashMap<CellIndex, u16>, fusemap_core::metrics::ClassAccuracy) {
    let mut predicted: HashMap<CellIndex, u16> = HashMap::new();
    let mut all_cells = fusemap_core::metrics::ClassAccuracy::default();
    let floor = classes.index_by_name("floor").map(|i| classes.get(i).id);
    let t = truth.occupancy;
    let inside = |c: CellIndex| {
        c.x >= t.first_cell.x
            && c.y >= t.first_cell.y
            && c.x < t.first_cell.x + t.width as i64
            && c.y < t.first_cell.y + t.height as i64
    };
    if let Some(b) = grid.known_box() {
        let s = semantic_cells(grid, b, classes);
        for (i, &best) in s.best.cells.iter().enumerate() {
            let c = CellIndex::new(
                s.best.first_cell.x + (i % s.best.width) as i64,
                s.best.first_cell.y + (i / s.best.width) as i64,
            );
            if best < 0 {
                continue;
            }
            let id = classes.get(best as u8).id;
            if occupied.contains(&c) {
                predicted.insert(c, id);
            }
            if inside(c) {
                let true_id = match truth.semantic.class_at(c) {
                    0 => floor,
                    k => Some(k as u16),
                };
                all_cells.truth += 1;
                all_cells.held += 1;
                all_cells.matched += (Some(id) == true_id) as usize;
            }
        }
    }
    (predicted, all_cells)
}

fn cells_of(b: CellBox) -> impl Iterator<Item = CellIndex> {
    (b.min.y..=b.max.y).flat_map(move |y| (b.min.x..=b.max.x).map(move |x| CellIndex::new(x, y)))
}

fn neighbours(c: CellIndex, r: i64) -> impl Iterator<Item = CellIndex> {
    (-r..=r).flat_map(move |dy| (-r..=r).map(move |dx| CellIndex::new(c.x + dx, c.y + dy)))
}
