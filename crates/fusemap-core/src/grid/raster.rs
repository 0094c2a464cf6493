//! Dense copies of a rectangle of a layer, for exporters and metrics.
//!
//! Every layer gives a raster view of its cells through
//! [`LayeredGrid::cell_raster`](super::LayeredGrid::cell_raster), a [`CellRaster`] of the
//! layer's own cell type with the placement every exporter needs; [`Raster`] is the
//! occupancy layer's view, with the probability and ternary readings of log-odds cells.

use super::{logodds::probability, CellIndex, LogOddsTable, OccupancyParams, Ternary};
use crate::geometry::Point2;

/// A dense, row-major rectangle of occupancy cells. Row 0 is the lowest y (the design
/// document's `log_odds[iy, ix]`); image formats flip it when they write.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell side, metres.
    pub resolution: f64,
    /// World coordinates of the lower-left corner of cell (row 0, column 0).
    pub origin: Point2,
    /// The grid cell at row 0, column 0.
    pub first_cell: CellIndex,
    /// Log-odds per cell; the prior's log-odds where unknown.
    pub log_odds: Vec<f32>,
    /// Whether each cell was ever observed.
    pub known: Vec<bool>,
    /// The layer's parameters (prior and thresholds).
    pub params: OccupancyParams,
}

impl Raster {
    /// Occupancy probabilities as `f32`, `1 - 1/(1 + e^l)` (the prior where unknown).
    pub fn occupancy(&self) -> Vec<f32> {
        self.log_odds.iter().map(|&l| probability(l as f64) as f32).collect()
    }

    /// Free / occupied / unknown per cell; unobserved cells are unknown whatever the prior.
    pub fn ternary(&self) -> Vec<Ternary> {
        let table = LogOddsTable::new(&self.params);
        self.log_odds
            .iter()
            .zip(&self.known)
            .map(|(&l, &k)| if k { table.classify(probability(l as f64)) } else { Ternary::Unknown })
            .collect()
    }

    /// Number of observed cells.
    pub fn known_count(&self) -> usize {
        self.known.iter().filter(|&&k| k).count()
    }

    /// Row-major index of the cell at `(column, row)`.
    pub fn index(&self, column: usize, row: usize) -> usize {
        row * self.width + column
    }

    /// The raster position of a grid cell, `None` outside.
    pub fn position(&self, c: CellIndex) -> Option<(usize, usize)> {
        let (dx, dy) = (c.x - self.first_cell.x, c.y - self.first_cell.y);
        (dx >= 0 && dy >= 0 && (dx as usize) < self.width && (dy as usize) < self.height)
            .then_some((dx as usize, dy as usize))
    }
}

/// A dense, row-major rectangle of one layer's cells (row 0 = lowest y), the raster view
/// of any layer: occupancy log-odds, a class distribution, a visit count.
#[derive(Clone, Debug, PartialEq)]
pub struct CellRaster<T> {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell side, metres.
    pub resolution: f64,
    /// World coordinates of the lower-left corner of cell (row 0, column 0).
    pub origin: Point2,
    /// The grid cell at row 0, column 0.
    pub first_cell: CellIndex,
    /// The layer's value per cell; the fill value where unknown.
    pub cells: Vec<T>,
    /// Whether the layer holds a value for each cell.
    pub known: Vec<bool>,
}

impl<T> CellRaster<T> {
    /// The value at grid cell `c`, `None` outside the raster or where unknown.
    pub fn get(&self, c: CellIndex) -> Option<&T> {
        let (dx, dy) = (c.x - self.first_cell.x, c.y - self.first_cell.y);
        let inside = dx >= 0 && dy >= 0 && (dx as usize) < self.width && (dy as usize) < self.height;
        let i = inside.then(|| dy as usize * self.width + dx as usize)?;
        self.known[i].then(|| &self.cells[i])
    }
}
