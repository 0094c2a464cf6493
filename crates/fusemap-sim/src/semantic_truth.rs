//! The semantic ground truth: the class of every truly occupied cell, the cells of each
//! kind of object a map must not carve open, and what the camera truly did.

use crate::camera::{class_id, CLASS_GLASS, CLASS_MACHINE, CLASS_PILLAR};
use crate::recording::{SimRecording, TruthRasterError};
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellIndex, GridGeometry};
use fusemap_core::time::Stamp;

/// The true class map of a run, on a rectangle of a grid (the same cells as
/// [`SimRecording::truth_occupancy`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TruthSemantic {
    /// The grid placement the cells refer to.
    pub geometry: GridGeometry,
    /// The cell at row 0, column 0.
    pub first_cell: CellIndex,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major (row 0 = lowest y): the class id of the object covering the cell (the
    /// later object in the world's list where two overlap), 0 where the cell is free.
    pub class_ids: Vec<u8>,
    /// Cells whose centre lies inside a pillar's outline.
    pub pillar_body_cells: Vec<CellIndex>,
    /// Cells whose centre lies inside a machine's outline.
    pub machine_body_cells: Vec<CellIndex>,
    /// Cells a glass object covers (a fence is thinner than a cell, so every cell it
    /// touches).
    pub glass_cells: Vec<CellIndex>,
    /// Map-frame floor points the camera's backlight labelled as an obstacle (a bounded
    /// sample, see [`crate::MAX_BACKLIT_POINTS`]).
    pub backlit_floor_points: Vec<Point2>,
    /// Per camera frame: its true time and its published stamp.
    pub camera_stamps: Vec<(Stamp, Stamp)>,
}

impl TruthSemantic {
    /// The class id at `c` (0 outside the raster or where free).
    pub fn class_at(&self, c: CellIndex) -> u8 {
        let (dx, dy) = (c.x - self.first_cell.x, c.y - self.first_cell.y);
        if dx >= 0 && dy >= 0 && (dx as usize) < self.width && (dy as usize) < self.height {
            self.class_ids[dy as usize * self.width + dx as usize]
        } else {
            0
        }
    }

    fn cell(&self, i: usize) -> CellIndex {
        CellIndex::new(self.first_cell.x + (i % self.width) as i64, self.first_cell.y + (i / self.width) as i64)
    }
}

impl SimRecording {
    /// The semantic ground truth at `geometry`: the class id of each cell
    /// [`SimRecording::truth_occupancy`] marks occupied, the pillar and machine body
    /// cells and the glass cells, the backlit floor sample and the camera's stamps. The
    /// walking person is not part of it. Refuses objects whose class is not an object
    /// class of the table, and rasters above [`crate::MAX_TRUTH_CELLS`] cells.
    pub fn truth_semantic(&self, geometry: GridGeometry) -> Result<TruthSemantic, TruthRasterError> {
        let mut classes = Vec::with_capacity(self.objects.len());
        for o in &self.objects {
            match class_id(&o.class) {
                Some(c @ 2..=5) => classes.push(c as u8),
                _ => return Err(TruthRasterError::UnknownClass { object: o.name.clone(), class: o.class.clone() }),
            }
        }
        let mut ids = Vec::new();
        let (mut pillar, mut machine, mut glass) = (Vec::new(), Vec::new(), Vec::new());
        let (first_cell, width, height) = self.raster_objects(geometry, |n, k, i, inside| {
            ids.resize(n, 0u8);
            let c = classes[k];
            ids[i] = c;
            match u16::from(c) {
                CLASS_PILLAR if inside => pillar.push(i),
                CLASS_MACHINE if inside => machine.push(i),
                CLASS_GLASS => glass.push(i),
                _ => {}
            }
        })?;
        ids.resize(width * height, 0);
        let mut t = TruthSemantic {
            geometry,
            first_cell,
            width,
            height,
            class_ids: ids,
            pillar_body_cells: Vec::new(),
            machine_body_cells: Vec::new(),
            glass_cells: Vec::new(),
            backlit_floor_points: self.camera_truth.backlit_floor_points.clone(),
            camera_stamps: self.camera_truth.stamps.clone(),
        };
        for (list, out) in [(pillar, 0), (machine, 1), (glass, 2)] {
            let mut list = list;
            list.sort_unstable();
            list.dedup();
            let cells = list.into_iter().map(|i| t.cell(i)).collect();
            match out {
                0 => t.pillar_body_cells = cells,
                1 => t.machine_body_cells = cells,
                _ => t.glass_cells = cells,
            }
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{simulate, Scenario, CLASS_WALL};
    use super::*;

    #[test]
    fn classes_match_the_occupancy_and_the_objects() {
        let mut s = Scenario::default();
        s.robot.duration_s = 2.0;
        let run = simulate(&s).unwrap();
        let g = GridGeometry::centered(0.05).unwrap();
        let occ = run.truth_occupancy(g).unwrap();
        let sem = run.truth_semantic(g).unwrap();
        assert_eq!((sem.width, sem.height, sem.first_cell), (occ.width, occ.height, occ.first_cell));
        for (o, c) in occ.occupied.iter().zip(&sem.class_ids) {
            assert_eq!(*o, *c != 0);
        }
        let at = |x: f64, y: f64| sem.class_at(g.cell_of(Point2::new(x, y)).unwrap());
        assert_eq!(u16::from(at(15.0, 0.0)), CLASS_WALL);
        assert_eq!(u16::from(at(10.0, 10.5)), CLASS_GLASS);
        assert_eq!(u16::from(at(8.0, 1.3)), CLASS_PILLAR);
        assert_eq!(u16::from(at(9.0, 7.0)), CLASS_MACHINE);
        assert_eq!(at(5.0, 3.0), 0);
        // A 0.2 m radius pillar holds about π r² / 0.05² ≈ 50 body cells; six of them.
        let per_pillar = sem.pillar_body_cells.len() as f64 / 6.0;
        assert!((per_pillar - std::f64::consts::PI * 0.04 / 0.0025).abs() < 8.0, "{per_pillar}");
        // Two 7 × 3.5 m machines.
        let expected = 2.0 * 7.0 * 3.5 / 0.0025;
        assert!((sem.machine_body_cells.len() as f64 - expected).abs() < 0.02 * expected);
        // The 20 m fence covers one or two rows of cells along its length.
        let n = sem.glass_cells.len() as f64;
        assert!((400.0..=820.0).contains(&n), "{n}");
        assert!(sem.glass_cells.iter().all(|&c| u16::from(sem.class_at(c)) == CLASS_GLASS));
        assert_eq!(sem.camera_stamps.len(), run.camera_truth.stamps.len());
        let mut bad = run.clone();
        bad.objects[0].class = "fence".into();
        assert!(matches!(bad.truth_semantic(g), Err(TruthRasterError::UnknownClass { .. })));
    }
}
