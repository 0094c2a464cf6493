//! What a run produces: the time-ordered messages and the ground truth to score an
//! estimator and a map against.

use crate::camera::CameraTruth;
use crate::lidar::LidarStats;
use crate::messages::SimMessage;
use crate::world::{polygon_contains, Rect, WorldObject};
use fusemap_core::geometry::{Datum, Point2, Pose2};
use fusemap_core::grid::{CellIndex, GridGeometry};
use fusemap_core::time::Stamp;

/// A simulated run.
#[derive(Clone, Debug)]
pub struct SimRecording {
    /// Every message, sorted by header stamp (ties keep the order static transforms,
    /// scans, odometry, IMU, fixes, camera images and calibration).
    pub messages: Vec<SimMessage>,
    /// `map_from_base` at 50 Hz, true clock (no sensor offset). The map frame is ENU at
    /// the GNSS datum: x east, y north.
    pub truth_trajectory: Vec<(Stamp, Pose2)>,
    /// Stamps of the fixes that carry an unreported outlier.
    pub injected_outliers: Vec<Stamp>,
    /// Intervals (receiver clock) with the antenna in a dropout zone.
    pub dropouts: Vec<(Stamp, Stamp)>,
    /// The IMU's true gyro z bias, rad/s.
    pub gyro_bias_radps: f64,
    /// The odometry's true scale error (reported / true travel off the grooves).
    pub odometry_scale: f64,
    /// 5 ms integration steps with a wheel over a groove.
    pub slipping_steps: u64,
    /// What the lidar's failure modes did.
    pub lidar_stats: LidarStats,
    /// The map frame's datum.
    pub datum: Datum,
    /// The world's objects (for truth rasters and reports).
    pub objects: Vec<WorldObject>,
    /// The world's extent.
    pub extent: Rect,
    /// Where the walking person stood, true clock, at 50 Hz while present (empty when
    /// disabled). It is never part of the truth rasters.
    pub person_track: Vec<(Stamp, Point2)>,
    /// The person's radius, metres.
    pub person_radius_m: f64,
    /// What the camera truly did (empty when disabled).
    pub camera_truth: CameraTruth,
}

/// Largest truth raster [`SimRecording::truth_occupancy`] builds: 2²⁸ cells (256 MB of
/// flags), e.g. a 800 m square at 5 cm.
pub const MAX_TRUTH_CELLS: usize = 1 << 28;

/// Bytes a cell of the truth takes while [`crate::bag::write_simulation`] rasters and
/// writes it: the occupancy flags, the map_server raster (log-odds and known flag), the
/// class ids and their picture's rows. Measured: the production line at 2 mm (124 M
/// cells) peaked 1.05 GB above the same run at 5 cm, 8.5 bytes a cell.
pub const TRUTH_BYTES_PER_CELL: u64 = 9;

/// Why a truth raster cannot be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TruthRasterError {
    /// The world's extent holds too many cells at this resolution.
    #[error("the truth raster would hold {cells} cells (limit {limit})", limit = MAX_TRUTH_CELLS)]
    TooLarge {
        /// Cells the extent needs (saturated when beyond the grid's index range).
        cells: u128,
    },
    /// An object's class is not one of the class table's object classes.
    #[error("object `{object}` has class `{class}`, not an object class of the table (wall, glass, pillar, machine)")]
    UnknownClass {
        /// The object's name.
        object: String,
        /// Its class.
        class: String,
    },
}

/// The truly occupied cells of a rectangle of a grid.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthRaster {
    /// The grid placement the cells refer to.
    pub geometry: GridGeometry,
    /// The cell at row 0, column 0.
    pub first_cell: CellIndex,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major (row 0 = lowest y), true where an object covers the cell.
    pub occupied: Vec<bool>,
}

impl TruthRaster {
    /// Whether the cell is occupied (`false` outside the raster).
    pub fn is_occupied(&self, c: CellIndex) -> bool {
        let (dx, dy) = (c.x - self.first_cell.x, c.y - self.first_cell.y);
        dx >= 0
            && dy >= 0
            && (dx as usize) < self.width
            && (dy as usize) < self.height
            && self.occupied[dy as usize * self.width + dx as usize]
    }

    /// Number of occupied cells.
    pub fn occupied_count(&self) -> usize {
        self.occupied.iter().filter(|&&o| o).count()
    }

    /// The occupied cells.
    pub fn occupied_cells(&self) -> impl Iterator<Item = CellIndex> + '_ {
        self.occupied.iter().enumerate().filter(|(_, &o)| o).map(|(i, _)| {
            CellIndex::new(self.first_cell.x + (i % self.width) as i64, self.first_cell.y + (i / self.width) as i64)
        })
    }
}

impl SimRecording {
    /// Rasterises every object into `geometry` over the world's extent: a cell is
    /// occupied when its square touches the object's solid, i.e. its centre lies inside
    /// the object's outline (a thick segment's rectangle, a polygon) or the square meets
    /// an outline edge (so an ideal, zero-thickness line marks every cell it crosses).
    /// Refuses rasters above [`MAX_TRUTH_CELLS`] cells instead of exhausting memory.
    pub fn truth_occupancy(&self, geometry: GridGeometry) -> Result<TruthRaster, TruthRasterError> {
        let mut occupied = Vec::new();
        let (first_cell, width, height) = self.raster_objects(geometry, |n, _, i, _| {
            occupied.resize(n, false);
            occupied[i] = true;
        })?;
        occupied.resize(width * height, false);
        Ok(TruthRaster { geometry, first_cell, width, height, occupied })
    }

    /// Cells of the truth rasters at `geometry` (the world's extent), refused as
    /// [`SimRecording::truth_occupancy`] refuses them.
    pub fn truth_cells(&self, geometry: GridGeometry) -> Result<u128, TruthRasterError> {
        truth_cells(&self.extent, geometry)
    }

    /// Bytes the recording's messages hold (their images and scans, and the vector of
    /// them): what a run that keeps the recording holds beside its truth and maps.
    pub fn held_bytes(&self) -> u64 {
        let payload: usize = (self.messages.iter())
            .map(|m| match m {
                SimMessage::Image(i) => i.data.len(),
                SimMessage::Scan(s) => 4 * (s.ranges.len() + s.intensities.len()),
                _ => 0,
            })
            .sum();
        (payload + self.messages.capacity() * std::mem::size_of::<SimMessage>()) as u64
    }

    /// The truth rasters' first cell, width and height at `geometry`.
    fn truth_extent(&self, geometry: GridGeometry) -> Result<(CellIndex, usize, usize), TruthRasterError> {
        truth_extent(&self.extent, geometry)
    }

    /// Walks every cell every object covers (as [`SimRecording::truth_occupancy`] defines
    /// it) over the world's extent: `visit(cells, object, index, centre_inside)` with the
    /// raster's cell count, the row-major index into it and whether the cell's centre lies
    /// inside the object's closed outline (a body cell). Returns the raster's first cell,
    /// width and height.
    pub(crate) fn raster_objects(
        &self,
        geometry: GridGeometry,
        mut visit: impl FnMut(usize, usize, usize, bool),
    ) -> Result<(CellIndex, usize, usize), TruthRasterError> {
        let (lo, width, height) = self.truth_extent(geometry)?;
        let hi = CellIndex::new(lo.x + width as i64 - 1, lo.y + height as i64 - 1);
        let res = geometry.resolution();
        for (k, o) in self.objects.iter().enumerate() {
            let edges = o.outline();
            let corners: Vec<[f64; 2]> = edges.iter().map(|(a, _)| [a.x, a.y]).collect();
            let (mut bx0, mut by0, mut bx1, mut by1) =
                (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
            for (a, b) in &edges {
                for p in [a, b] {
                    (bx0, by0, bx1, by1) = (bx0.min(p.x), by0.min(p.y), bx1.max(p.x), by1.max(p.y));
                }
            }
            let (Some(c0), Some(c1)) =
                (geometry.cell_of(Point2::new(bx0, by0)), geometry.cell_of(Point2::new(bx1, by1)))
            else {
                continue;
            };
            for y in c0.y.max(lo.y)..=c1.y.min(hi.y) {
                for x in c0.x.max(lo.x)..=c1.x.min(hi.x) {
                    let cell = CellIndex::new(x, y);
                    let corner = geometry.cell_corner(cell);
                    let far = Point2::new(corner.x + res, corner.y + res);
                    let inside = corners.len() >= 3 && polygon_contains(&corners, geometry.cell_center(cell));
                    if inside || edges.iter().any(|&(a, b)| segment_meets_box(a, b, corner, far)) {
                        visit(width * height, k, (y - lo.y) as usize * width + (x - lo.x) as usize, inside);
                    }
                }
            }
        }
        Ok((lo, width, height))
    }

    /// The true `map_from_base` at `stamp` (true clock), interpolated; `None` outside the run.
    pub fn truth_at(&self, stamp: Stamp) -> Option<Pose2> {
        let i = self.truth_trajectory.partition_point(|(s, _)| *s <= stamp);
        if i == 0 {
            return None;
        }
        let (s0, p0) = self.truth_trajectory[i - 1];
        if s0 == stamp {
            return Some(p0);
        }
        let (s1, p1) = *self.truth_trajectory.get(i)?;
        Some(p0.interpolate(p1, stamp.secs_since(s0) / s1.secs_since(s0)))
    }
}

/// Whether the segment `a`–`b` meets the closed box `lo`–`hi` (Liang & Barsky 1984
/// parametric clipping).
pub fn segment_meets_box(a: Point2, b: Point2, lo: Point2, hi: Point2) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a.x - lo.x), (dx, hi.x - a.x), (-dy, a.y - lo.y), (dy, hi.y - a.y)] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    t0 <= t1
}

/// Cells of the truth rasters over the world's `extent` at `geometry` (a scenario's, before
/// it is run), refused as [`SimRecording::truth_occupancy`] refuses them.
pub fn truth_cells(extent: &Rect, geometry: GridGeometry) -> Result<u128, TruthRasterError> {
    let (_, w, h) = truth_extent(extent, geometry)?;
    Ok(w as u128 * h as u128)
}

/// The truth rasters' first cell, width and height over the world's `extent` at `geometry`.
fn truth_extent(e: &Rect, geometry: GridGeometry) -> Result<(CellIndex, usize, usize), TruthRasterError> {
    let (Some(lo), Some(hi)) =
        (geometry.cell_of(Point2::new(e.min[0], e.min[1])), geometry.cell_of(Point2::new(e.max[0], e.max[1])))
    else {
        return Err(TruthRasterError::TooLarge { cells: u128::MAX });
    };
    let (w, h) = ((hi.x - lo.x + 1).max(1) as u128, (hi.y - lo.y + 1).max(1) as u128);
    if w * h > MAX_TRUTH_CELLS as u128 {
        return Err(TruthRasterError::TooLarge { cells: w * h });
    }
    Ok((lo, w as usize, h as usize))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{simulate, Scenario};

    #[test]
    fn segment_box_cases() {
        let (lo, hi) = (Point2::new(0.0, 0.0), Point2::new(1.0, 1.0));
        let p = Point2::new;
        assert!(segment_meets_box(p(-1.0, 0.5), p(2.0, 0.5), lo, hi));
        assert!(segment_meets_box(p(0.2, 0.2), p(0.3, 0.3), lo, hi), "inside");
        assert!(!segment_meets_box(p(-1.0, 1.5), p(2.0, 1.5), lo, hi), "above");
        assert!(!segment_meets_box(p(1.5, -1.0), p(3.0, 0.5), lo, hi), "diagonal miss");
        assert!(segment_meets_box(p(1.0, -1.0), p(1.0, 2.0), lo, hi), "along the border");
        assert!(!segment_meets_box(p(-1.0, 0.5), p(-0.1, 0.5), lo, hi), "stops short");
        assert!(segment_meets_box(p(-0.5, 0.0), p(0.0, -0.5), p(-0.3, -0.3), p(-0.2, -0.2)), "corner cut");
    }

    #[test]
    fn oversized_rasters_are_refused() {
        let mut s = Scenario::default();
        s.robot.duration_s = 1.0;
        s.world.extent = Rect::new(-5_000.0, -5_000.0, 5_000.0, 5_000.0);
        let run = simulate(&s).unwrap();
        let err = run.truth_occupancy(GridGeometry::centered(0.05).unwrap()).unwrap_err();
        assert_eq!(err, TruthRasterError::TooLarge { cells: 200_001 * 200_001 });
        assert!(run.truth_occupancy(GridGeometry::centered(10.0).unwrap()).is_ok());
    }
}
