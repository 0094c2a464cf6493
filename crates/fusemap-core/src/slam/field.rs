//! The likelihood field a submap is matched against.
//!
//! A return is scored by how close it falls to a wall the submap has seen, not by the
//! probability of the one cell it lands in: the likelihood-field model of Thrun et al.,
//! *Probabilistic Robotics*, §6.4, and the blurred lookup table of Olson 2009 ("Real-time
//! correlative scan matching", §III). The field at a cell is `exp(−d² / 2σ²)`, `d` the
//! distance to the nearest occupied cell of the submap (probability above ½), `0` farther
//! than 3σ.
//!
//! Why not the probability grid itself (as Hess et al. 2016 match)? Scored cell by cell,
//! a return counts only where an earlier return fell. That works when a submap holds
//! hundreds of scans and every wall is hit many times, but a log with one scan per metre
//! of travel (corrected logs, keyframes, slow lidars) builds submaps of sparse, speckled
//! walls: a beam 1° from its neighbour is 35 cm away at 20 m, and a new scan's far returns
//! land between the old ones. Its score surface is then a bed of spikes, and the match's
//! heading wanders by as much as the search window (measured on the bench's Acapulco log:
//! 0.86° mean heading error a scan with perfect odometry; 0.32° with a blurred target). The
//! field is smooth, its value does not depend on how often a wall was hit, and its
//! gradient reaches a few cells from every wall, which the refinement needs.
//!
//! The field is stored as a [`ProbabilityGrid`] (`P_MIN` far from walls, `P_MAX` on them),
//! so the correlative search, the refinement and branch and bound read it as they read any
//! grid. It is kept up to date cell by cell: a cell that becomes occupied raises its
//! neighbourhood to the kernel; a cell that stops being occupied (cleared by later rays)
//! has its neighbourhood recomputed from the occupancy. The result is the field computed
//! from scratch, to the bit.

use super::grid::{probability_to_value, ProbabilityGrid, P_MAX, P_MIN};
use crate::grid::CellIndex;

/// A change of a cell's occupancy (probability crossing ½) in one insertion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crossing {
    /// The cell.
    pub cell: CellIndex,
    /// Now occupied (else no longer).
    pub occupied: bool,
}

/// The kernel: offsets within the radius and their stored field values.
#[derive(Clone, Debug)]
pub struct FieldKernel {
    radius: i64,
    /// `(dx, dy, value)`, value as stored (`u16`), largest first.
    offsets: Vec<(i64, i64, u16)>,
}

impl FieldKernel {
    /// The kernel of σ `sigma_m` on cells of `resolution` metres (at least one cell of
    /// radius; a σ of 0 gives the occupied cells alone).
    pub fn new(sigma_m: f64, resolution: f64) -> Self {
        let s = (sigma_m / resolution).max(0.0);
        let radius = (3.0 * s).ceil().max(0.0) as i64;
        let mut offsets = Vec::new();
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let d2 = (dx * dx + dy * dy) as f64;
                if d2 > (radius * radius) as f64 {
                    continue;
                }
                let f = if d2 == 0.0 { 1.0 } else { (-d2 / (2.0 * s * s)).exp() };
                let v = probability_to_value(P_MIN + f as f32 * (P_MAX - P_MIN));
                offsets.push((dx, dy, v));
            }
        }
        offsets.sort_by_key(|o| std::cmp::Reverse(o.2));
        Self { radius, offsets }
    }

    /// Cells of the neighbourhood on each side.
    pub fn radius(&self) -> i64 {
        self.radius
    }
}

/// Brings `field` up to date with `occupancy` after `crossings` (the cells whose occupancy
/// changed in the last insertion; `occupied(x, y)` tells the occupancy now).
pub fn update(
    field: &mut ProbabilityGrid,
    kernel: &FieldKernel,
    crossings: &[Crossing],
    occupied: impl Fn(i64, i64) -> bool,
) {
    if crossings.is_empty() {
        return;
    }
    let r = kernel.radius;
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    for c in crossings {
        lo = (lo.0.min(c.cell.x - r), lo.1.min(c.cell.y - r));
        hi = (hi.0.max(c.cell.x + r), hi.1.max(c.cell.y + r));
    }
    field.ensure_cells(lo, hi);
    // Cleared walls first: every field cell near one is recomputed from the occupancy
    // (its best kernel value over the occupied cells around it).
    for c in crossings.iter().filter(|c| !c.occupied) {
        for dy in -r..=r {
            for dx in -r..=r {
                let (x, y) = (c.cell.x + dx, c.cell.y + dy);
                let best =
                    kernel.offsets.iter().find(|&&(ox, oy, _)| occupied(x + ox, y + oy)).map_or(0, |&(_, _, v)| v);
                field.set_value(x, y, best);
            }
        }
    }
    // New walls raise their neighbourhood.
    for c in crossings.iter().filter(|c| c.occupied) {
        for &(dx, dy, v) in &kernel.offsets {
            let (x, y) = (c.cell.x + dx, c.cell.y + dy);
            if field.value(x, y) < v {
                field.set_value(x, y, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::slam::grid::UpdateTable;

    /// The field computed from scratch over the occupancy's cells.
    fn from_scratch(occ: &ProbabilityGrid, kernel: &FieldKernel, x: i64, y: i64) -> u16 {
        kernel.offsets.iter().find(|&&(ox, oy, _)| occ.probability(x + ox, y + oy) > 0.5).map_or(0, |o| o.2)
    }

    #[test]
    fn the_kept_field_equals_the_field_from_scratch() {
        let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.45));
        let kernel = FieldKernel::new(0.1, 0.05);
        assert_eq!(kernel.radius(), 6);
        let mut occ = ProbabilityGrid::new(0.05);
        let mut field = ProbabilityGrid::new(0.05);
        let mut crossings = Vec::new();
        // A wall, then rays that clear part of it, then more returns elsewhere.
        let wall: Vec<Point2> = (0..40).map(|k| Point2::new(3.0, -1.0 + 0.05 * k as f64)).collect();
        let through: Vec<Point2> = (0..10).map(|k| Point2::new(5.0, -0.5 + 0.05 * k as f64)).collect();
        let steps: Vec<(&[Point2], &[Point2])> =
            vec![(&wall, &[]), (&[], &through), (&[], &through), (&through[..3], &[]), (&wall[..5], &through[5..])];
        for (hits, misses) in steps {
            crossings.clear();
            occ.insert_tracking(Point2::new(0.0, 0.0), hits, misses, &hit, &miss, &mut crossings);
            update(&mut field, &kernel, &crossings, |x, y| occ.probability(x, y) > 0.5);
            let l = occ.limits();
            for y in l.min.y - 8..l.min.y + l.height as i64 + 8 {
                for x in l.min.x - 8..l.min.x + l.width as i64 + 8 {
                    let want = from_scratch(&occ, &kernel, x, y);
                    assert_eq!(field.value(x, y), want, "cell ({x}, {y})");
                }
            }
        }
        // A wall cell reads P_MAX, far cells P_MIN, and the mirror follows.
        assert_eq!(field.probability(60, 0), P_MAX);
        assert_eq!(field.probability(0, 0), P_MIN);
        let m = field.probabilities().unwrap();
        assert!(field.values().iter().zip(m).all(|(&v, &p)| super::super::grid::value_to_probability(v) == p));
    }
}
