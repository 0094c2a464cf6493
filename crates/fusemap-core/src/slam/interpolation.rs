//! A smooth probability map for scan-matching refinement: cubic convolution (Keys 1981,
//! "Cubic convolution interpolation for digital image processing", a = −½) over the cell
//! centres of a [`ProbabilityGrid`].
//!
//! Gauss–Newton needs a map whose gradient is continuous; nearest-cell lookups have none
//! and bilinear interpolation has a gradient that jumps at every cell border, which makes
//! the refinement chatter between cells. Hess et al. 2016 (§IV) interpolate bicubically
//! for the same reason; Hector SLAM (Kohlbrecher et al. 2011) makes do with bilinear.

use super::grid::{floor_i64, value_to_probability, ProbabilityGrid};

/// Keys' kernel weights and their derivatives for fractional offset `t ∈ [0, 1)` from the
/// second of four samples.
#[inline]
fn keys(t: f64) -> ([f64; 4], [f64; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    let w = [-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0, -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2];
    let d = [-1.5 * t2 + 2.0 * t - 0.5, 4.5 * t2 - 5.0 * t, -4.5 * t2 + 4.0 * t + 0.5, 1.5 * t2 - t];
    (w, d)
}

/// The interpolated probability at continuous cell coordinates `(u, v)` (cell `(i, j)`
/// spans `[i, i+1) × [j, j+1)`, its value sits at its centre), with its gradient
/// `(∂/∂u, ∂/∂v)` per cell.
#[inline]
pub fn probability_and_gradient(grid: &ProbabilityGrid, u: f64, v: f64) -> (f64, f64, f64) {
    let (fu, fv) = (u - 0.5, v - 0.5);
    let (i0, j0) = (floor_i64(fu), floor_i64(fv));
    let (wu, du) = keys(fu - i0 as f64);
    let (wv, dv) = keys(fv - j0 as f64);
    // Saturating: a point 10¹⁸ cells out reads cells outside the grid, never wraps.
    let (i0, j0) = (i0.saturating_sub(1), j0.saturating_sub(1));
    // The 4 × 4 samples; inside the grid (nearly always) straight from its rows.
    let mut samples = [[0f64; 4]; 4];
    let width = grid.limits().width;
    match (grid.probabilities(), grid.block_start(i0, j0, 4, 4)) {
        (Some(probabilities), Some(start)) => {
            for (b, row) in samples.iter_mut().enumerate() {
                for (s, &p) in row.iter_mut().zip(&probabilities[start + b * width..][..4]) {
                    *s = p as f64;
                }
            }
        }
        (None, Some(start)) => {
            for (b, row) in samples.iter_mut().enumerate() {
                for (s, &v) in row.iter_mut().zip(&grid.values()[start + b * width..][..4]) {
                    *s = value_to_probability(v) as f64;
                }
            }
        }
        (_, None) => {
            for (b, row) in samples.iter_mut().enumerate() {
                for (a, s) in row.iter_mut().enumerate() {
                    *s = grid.probability(i0.saturating_add(a as i64), j0.saturating_add(b as i64)) as f64;
                }
            }
        }
    }
    let (mut p, mut gu, mut gv) = (0.0, 0.0, 0.0);
    for ((&wvb, &dvb), row) in wv.iter().zip(&dv).zip(&samples) {
        let (mut row_w, mut row_d) = (0.0, 0.0);
        for ((&wua, &dua), &s) in wu.iter().zip(&du).zip(row) {
            row_w += wua * s;
            row_d += dua * s;
        }
        p += wvb * row_w;
        gu += wvb * row_d;
        gv += dvb * row_w;
    }
    (p, gu, gv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::slam::grid::UpdateTable;

    fn wall_grid() -> ProbabilityGrid {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
        let mut g = ProbabilityGrid::new(0.1);
        let hits: Vec<Point2> = (-20..=20).map(|k| Point2::new(2.05, k as f64 * 0.1)).collect();
        for _ in 0..40 {
            g.insert(Point2::new(0.0, 0.0), &hits, &[], &hit, &miss);
        }
        g
    }

    #[test]
    fn interpolation_passes_through_cell_centres() {
        let g = wall_grid();
        for (i, j) in [(20, 0), (15, 3), (5, -2)] {
            let (p, _, _) = probability_and_gradient(&g, i as f64 + 0.5, j as f64 + 0.5);
            assert!((p - g.probability(i, j) as f64).abs() < 1e-5, "{i},{j}");
        }
    }

    #[test]
    fn the_gradient_matches_finite_differences_and_points_at_the_wall() {
        let g = wall_grid();
        for (u, v) in [(19.3, 0.7), (18.9, 2.2), (20.2, -1.4)] {
            let (_, gu, gv) = probability_and_gradient(&g, u, v);
            let h = 1e-5;
            let nu = (probability_and_gradient(&g, u + h, v).0 - probability_and_gradient(&g, u - h, v).0) / (2.0 * h);
            let nv = (probability_and_gradient(&g, u, v + h).0 - probability_and_gradient(&g, u, v - h).0) / (2.0 * h);
            assert!((gu - nu).abs() < 1e-4 && (gv - nv).abs() < 1e-4, "({u},{v}): {gu} vs {nu}, {gv} vs {nv}");
        }
        // Left of the wall cell the probability rises towards it.
        assert!(probability_and_gradient(&g, 19.6, 0.5).1 > 0.0);
    }
}
