//! Dense views of a fusion map's extra layers, for exporters: the semantic layer's most
//! likely class, its probability and the whole distribution per cell, and the dynamic
//! layer's probability at a given time.

use super::camera::cell_semantics;
use crate::grid::{logodds::probability, CellBox, CellIndex, CellRaster, FusionGrid, Ternary};
use crate::sensor::camera::ClassTable;
use crate::time::Stamp;

/// The semantic layer over an area.
#[derive(Clone, Debug, PartialEq)]
pub struct SemanticCells {
    /// Per cell, the index (into the class table) of the most likely class, -1 where the
    /// layer holds no evidence; `known` marks cells with evidence.
    pub best: CellRaster<i16>,
    /// Per cell, the probability of the most likely class (0 without evidence).
    pub prob: Vec<f32>,
    /// Per cell, the probability of every class: `cells × classes`, cell-major.
    pub probs: Vec<f32>,
    /// Number of classes.
    pub classes: usize,
}

/// The semantic layer of `grid` over `area` with the class table `classes`.
pub fn semantic_cells(grid: &FusionGrid, area: CellBox, classes: &ClassTable) -> SemanticCells {
    let eligible: Vec<bool> = classes.iter().map(|c| !c.ignore && !c.dynamic).collect();
    let k = eligible.len();
    // With a symmetric prior the most likely class is the eligible one with the most
    // evidence (ties: the first), so the first sweep needs no probabilities.
    let best = grid.cell_raster(area, -1i16, |tile, offset| {
        let counts = tile.layers().semantic_counts(offset, k)?;
        let mut top: Option<(usize, f32)> = None;
        for (c, (&n, &e)) in counts.iter().zip(&eligible).enumerate() {
            if e && top.is_none_or(|(_, m)| n > m) {
                top = Some((c, n));
            }
        }
        let total: f32 = counts.iter().zip(&eligible).filter(|(_, &e)| e).map(|(n, _)| n).sum();
        top.filter(|_| total > 0.0).map(|(c, _)| c as i16)
    });
    let n = best.width * best.height;
    let mut prob = vec![0.0f32; n];
    let mut probs = vec![0.0f32; n * k];
    for row in 0..best.height {
        for col in 0..best.width {
            let i = row * best.width + col;
            if !best.known[i] {
                continue;
            }
            let cell = CellIndex::new(best.first_cell.x + col as i64, best.first_cell.y + row as i64);
            if let Some((tile, offset)) = grid.tile_of(cell) {
                if let Some((_, p)) = cell_semantics(tile, offset, &eligible, &mut probs[i * k..(i + 1) * k]) {
                    prob[i] = p;
                }
            }
        }
    }
    SemanticCells { best, prob, probs, classes: k }
}

/// The least probability of its most likely class for a cell's class to be shown.
pub const MIN_SHOWN_CLASS_PROBABILITY: f32 = 0.5;

/// The most likely class of each cell of `cells` as a picture shows it (`semantic.png`),
/// -1 where it is hidden: a class is shown only where it is confident (its probability at
/// least [`MIN_SHOWN_CLASS_PROBABILITY`]) and agrees with the occupancy layer — an
/// obstacle class (`p_occupied` above one half) on a cell the occupancy does not hold
/// free, a floor-like class on one it does not hold occupied. The camera's labels land a
/// cell or two off an edge and its depth smears them along the ray; without the mask, the
/// floor in front of a glass fence showed as glass (most of 11,078 "glass" cells of the
/// production line, against 401 true ones, were free, with a median class probability of
/// 0.24).
pub fn shown_classes(grid: &FusionGrid, cells: &SemanticCells, classes: &ClassTable) -> Vec<i16> {
    let b = &cells.best;
    b.cells
        .iter()
        .enumerate()
        .map(|(i, &best)| {
            if best < 0 || cells.prob[i] < MIN_SHOWN_CLASS_PROBABILITY {
                return -1;
            }
            let cell = CellIndex::new(b.first_cell.x + (i % b.width) as i64, b.first_cell.y + (i / b.width) as i64);
            let obstacle = classes.get(best as u8).p_occupied > 0.5;
            let agrees = match grid.ternary(cell) {
                Ternary::Free => !obstacle,
                Ternary::Occupied => obstacle,
                Ternary::Unknown => true,
            };
            if agrees {
                best
            } else {
                -1
            }
        })
        .collect()
}

/// The dynamic layer's probability over `area` at `now` (its evidence decayed with
/// `half_life_s`); cells the layer never wrote are unknown (0.5, `known` false).
pub fn dynamic_cells(grid: &FusionGrid, area: CellBox, now: Stamp, half_life_s: f64) -> CellRaster<f32> {
    grid.cell_raster(area, 0.5f32, |tile, offset| {
        tile.layers().dynamic()?.log_odds_at(offset, now, half_life_s).map(|l| probability(l as f64) as f32)
    })
}
