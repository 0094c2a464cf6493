//! Mean binary entropy of a map (design document §5.1).
//!
//! `H = mean over cells of -(p ln p + (1-p) ln(1-p))`, p clipped to [1e-6, 1-1e-6], in
//! nats. Lower means more certain; a fused map must have clearly lower entropy than the
//! single-sensor maps. The mean depends on the region: here it is the known bounding box
//! (unknown cells inside it count at the prior), so a map that merely grows does not look
//! more certain. Compare maps only at equal resolution: finer cells mean more edge cells.

use crate::grid::{logodds::probability, Raster, SparseTiles};
use serde::{Deserialize, Serialize};

/// The binary entropy of `p` in nats, with the document's clipping.
pub fn binary_entropy(p: f64) -> f64 {
    let p = p.clamp(1e-6, 1.0 - 1e-6);
    -(p * p.ln() + (1.0 - p) * (1.0 - p).ln())
}

/// Entropy figures of a region.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EntropyReport {
    /// Cells in the region.
    pub cells: u64,
    /// Cells ever observed.
    pub known_cells: u64,
    /// `known_cells / cells`.
    pub known_share: f64,
    /// Mean binary entropy over the region, nats.
    pub mean_entropy_nats: f64,
}

/// Entropy of every cell of `raster` (unknown cells at the prior).
pub fn map_entropy(raster: &Raster) -> EntropyReport {
    let cells = raster.log_odds.len() as u64;
    let known_cells = raster.known_count() as u64;
    let sum: f64 = raster.log_odds.iter().map(|&l| binary_entropy(probability(l as f64))).sum();
    EntropyReport {
        cells,
        known_cells,
        known_share: if cells > 0 { known_cells as f64 / cells as f64 } else { 0.0 },
        mean_entropy_nats: if cells > 0 { sum / cells as f64 } else { 0.0 },
    }
}

/// [`map_entropy`] of a map held as tiles, over a region of `cells` cells that holds every
/// observed cell of `tiles`; its cells outside the tiles, and the tiles' unobserved cells,
/// count at the prior's log-odds `prior`. Equal to `map_entropy` of the dense raster of
/// the region up to the order of the sum.
pub fn sparse_entropy(tiles: &SparseTiles, cells: u64, prior: f32) -> EntropyReport {
    let h_prior = binary_entropy(probability(prior as f64));
    let mut known_cells = 0u64;
    let mut sum = 0.0;
    for &l in tiles.log_odds.iter().filter(|l| !l.is_nan()) {
        known_cells += 1;
        sum += binary_entropy(probability(l as f64));
    }
    sum += cells.saturating_sub(known_cells) as f64 * h_prior;
    EntropyReport {
        cells,
        known_cells,
        known_share: if cells > 0 { known_cells as f64 / cells as f64 } else { 0.0 },
        mean_entropy_nats: if cells > 0 { sum / cells as f64 } else { 0.0 },
    }
}

/// Mean binary entropy of `raster`'s cells where `mask` holds (unknown cells at the
/// prior), and how many there are: maps compared over the same cells, as §5.1 asks.
/// `None` when the mask does not match the raster or selects nothing.
pub fn entropy_where(raster: &Raster, mask: &[bool]) -> Option<(f64, u64)> {
    if mask.len() != raster.log_odds.len() {
        return None;
    }
    let (mut sum, mut n) = (0.0, 0u64);
    for (&l, _) in raster.log_odds.iter().zip(mask).filter(|(_, &m)| m) {
        sum += binary_entropy(probability(l as f64));
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64, n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::{CellIndex, OccupancyParams};

    #[test]
    fn entropy_values() {
        assert!((binary_entropy(0.5) - std::f64::consts::LN_2).abs() < 1e-12);
        assert!(binary_entropy(0.0) < 2e-5);
        assert!(binary_entropy(1.0) < 2e-5);
        assert!((binary_entropy(0.9) - binary_entropy(0.1)).abs() < 1e-12);
    }

    #[test]
    fn unknown_cells_count_at_the_prior() {
        let r = Raster {
            width: 2,
            height: 1,
            resolution: 0.1,
            origin: Point2::default(),
            first_cell: CellIndex::default(),
            log_odds: vec![0.0, 50.0],
            known: vec![false, true],
            params: OccupancyParams::default(),
        };
        let e = map_entropy(&r);
        assert_eq!(e.cells, 2);
        assert_eq!(e.known_cells, 1);
        assert!((e.known_share - 0.5).abs() < 1e-12);
        assert!((e.mean_entropy_nats - (std::f64::consts::LN_2 + binary_entropy(1.0)) / 2.0).abs() < 1e-9);
        // Over a mask: the selected cells only, unknown ones at the prior.
        assert_eq!(entropy_where(&r, &[true, false]), Some((binary_entropy(0.5), 1)));
        assert_eq!(entropy_where(&r, &[false, true]).map(|e| e.1), Some(1));
        assert_eq!(entropy_where(&r, &[false, false]), None);
        assert_eq!(entropy_where(&r, &[true]), None);
    }

    #[test]
    fn sparse_entropy_is_the_dense_one() {
        use crate::grid::{GridGeometry, OccupancyGrid};
        use crate::measurement::{Evidence, RangeData, Ray, SensorId};
        let mut g = OccupancyGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let mut d = RangeData::empty(SensorId(0), Evidence { p_hit: 0.7, p_miss: 0.4 });
        for k in 0..20 {
            let a = k as f64 * 0.3;
            d.rays.push(Ray {
                origin: Point2::default(),
                end: Point2::new(9.0 * a.cos(), 9.0 * a.sin()),
                hit: k % 3 > 0,
            });
        }
        g.insert(&d);
        let dense = map_entropy(&g.known_raster().unwrap());
        let area = g.known_box().unwrap();
        let sparse = sparse_entropy(&g.sparse_tiles(), area.len() as u64, g.table().prior);
        assert_eq!((sparse.cells, sparse.known_cells), (dense.cells, dense.known_cells));
        assert!((sparse.mean_entropy_nats - dense.mean_entropy_nats).abs() < 1e-12);
    }
}
