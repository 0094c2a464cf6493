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

    /// The cells as a ROS `nav_msgs/OccupancyGrid` holds them: −1 where unknown, else the
    /// occupancy probability in percent, rounded.
    ///
    /// A reader that classifies the percentages with this map's own thresholds gets
    /// exactly [`ternary`](Self::ternary)'s answer, cell for cell: where rounding alone
    /// would carry a cell across a threshold (0.6504 → 65 is not above 0.65) it takes the
    /// nearest percentage on its own side, at most one point away for the occupied and
    /// free classes. An observed but undecided cell whose band holds no whole percentage
    /// is written −1, which every reader takes as unknown too.
    pub fn occupancy_percent(&self) -> Vec<i8> {
        let table = LogOddsTable::new(&self.params);
        let classify = |v: i32| table.classify(f64::from(v) / 100.0);
        self.log_odds
            .iter()
            .zip(&self.known)
            .map(|(&l, &k)| {
                if !k {
                    return -1;
                }
                let p = probability(l as f64);
                let want = table.classify(p);
                let first = (p * 100.0).round().clamp(0.0, 100.0) as i32;
                // Nearest percentage of the cell's own class: first itself, then one
                // away on either side, and so on.
                (0..=100)
                    .flat_map(|d| [first - d, first + d])
                    .find(|v| (0..=100).contains(v) && classify(*v) == want)
                    .map_or(-1, |v| v as i8)
            })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::logodds::logit;
    use proptest::prelude::*;

    fn raster(probs: &[f64], known: &[bool], params: OccupancyParams) -> Raster {
        Raster {
            width: probs.len(),
            height: 1,
            resolution: 0.05,
            origin: Point2::new(0.0, 0.0),
            first_cell: CellIndex::new(0, 0),
            log_odds: probs.iter().map(|&p| logit(p) as f32).collect(),
            known: known.to_vec(),
            params,
        }
    }

    #[test]
    fn percentages_round_but_never_cross_a_threshold() {
        let params = OccupancyParams::default();
        let r = raster(&[0.6504, 0.2496, 0.97, 0.12, 0.5, 0.5], &[true, true, true, true, true, false], params);
        assert_eq!(r.occupancy_percent(), vec![66, 24, 97, 12, 50, -1]);
    }

    proptest! {
        /// Whatever the thresholds and the cell, classifying the percentage with the
        /// map's thresholds gives the ternary class, and occupied and free cells stay
        /// within a point and a half of their probability.
        #[test]
        fn percentages_classify_as_the_ternary_map(
            p in 0.001f64..0.999,
            free in 0.01f64..0.5,
            band in 0.0f64..0.45,
            known in any::<bool>(),
        ) {
            let params = OccupancyParams { free_threshold: free, occupied_threshold: free + band, ..Default::default() };
            let r = raster(&[p], &[known], params);
            let v = r.occupancy_percent()[0];
            let table = LogOddsTable::new(&params);
            let class = r.ternary()[0];
            if v < 0 {
                prop_assert_eq!(class, Ternary::Unknown);
                // −1 for an observed cell only when no whole percentage is undecided.
                let undecided = (0..=100).any(|k| table.classify(f64::from(k) / 100.0) == Ternary::Unknown);
                prop_assert!(!known || !undecided, "{} written -1 though a percentage fits its band", p);
            } else {
                prop_assert_eq!(table.classify(f64::from(v) / 100.0), class);
                let p32 = probability(r.log_odds[0] as f64);
                if class != Ternary::Unknown {
                    prop_assert!((f64::from(v) - 100.0 * p32).abs() <= 1.5, "{} for {}", v, p32);
                }
            }
        }
    }
}
