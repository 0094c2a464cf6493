//! The distance from any point of the map plane to the nearest wall surface a lidar saw:
//! the cost surface a sensor's points are scored on when its clock or mount is searched.
//!
//! Which cells: the *faces* of the obstacles, occupied cells next to a free one. The cells
//! behind a face (a thick wall, a shelf's inside) are no surface anything was measured on;
//! counted as obstacles they give a zero-cost region behind every face, and noisy points
//! that fall behind it cost nothing while those in front pay, which pulls the whole cloud
//! into the walls (measured on the production line: the camera's clock came out 27 ms
//! late with every obstacle cell, 14 ms with the faces' centres).
//!
//! Where in the cell: the mean of the lidar returns that landed in it ([`SurfaceHits`])
//! when they were kept, else its centre. A face at a random place in its cell is half a
//! cell from the centre at worst, and which of two cells a face's returns make occupied is
//! not symmetric (the cell in front is crossed by other rays and cleared), so centres put
//! the surface a centimetre or two behind the wall; the returns' mean is where the wall
//! was measured.
//!
//! The nearest face cell to every cell comes from the exact Euclidean distance transform
//! of Felzenszwalb & Huttenlocher ("Distance transforms of sampled functions", 2012),
//! kept as a feature transform (which face is nearest, not only how far); a point's
//! distance is then the least to the surface points of the faces nearest its cell and its
//! eight neighbours, exact within a cell and continuous across most cell borders, so a
//! cost summed over many points moves smoothly with a parameter. Distances are truncated at
//! `max_m`: a point far from every wall (a shelf above the lidar's plane, a person) costs
//! the same wherever it lands and cannot pull the estimate.

use crate::geometry::Point2;
use crate::grid::{CellIndex, GridGeometry, Raster};
use crate::measurement::RangeData;
use std::collections::HashMap;

/// The lidar returns of a pass, summed per cell: where in each cell the walls were hit.
/// Bounded by the cells hit, not by the log's length.
#[derive(Clone, Debug, Default)]
pub struct SurfaceHits {
    sums: HashMap<CellIndex, (f64, f64, u32)>,
}

impl SurfaceHits {
    /// Adds an observation's returns (rays ending in a hit).
    pub fn add(&mut self, data: &RangeData, geometry: &GridGeometry) {
        for r in data.rays.iter().filter(|r| r.hit) {
            if let Some(c) = geometry.cell_of(r.end) {
                let s = self.sums.entry(c).or_insert((0.0, 0.0, 0));
                *s = (s.0 + r.end.x, s.1 + r.end.y, s.2.saturating_add(1));
            }
        }
    }

    /// The mean return in cell `c`, if any landed there.
    pub fn mean(&self, c: CellIndex) -> Option<Point2> {
        self.sums.get(&c).map(|&(x, y, n)| Point2::new(x / n as f64, y / n as f64))
    }
}

/// Distances to the nearest obstacle face over a raster's cells, truncated.
#[derive(Clone, Debug)]
pub struct DistanceField {
    width: usize,
    height: usize,
    resolution: f64,
    /// World position of the centre of cell (row 0, column 0).
    first_centre: Point2,
    max_m: f64,
    /// Cell `i`'s candidate pieces are `candidates[starts[i]..starts[i + 1]]`: the pieces
    /// of the faces nearest it and its eight neighbours, each once. Listed when the field
    /// is built, so that [`DistanceField::at`], called for every point at every step of a
    /// calibration's searches, reads one short list instead of nine cells.
    starts: Vec<usize>,
    /// Indices into `pieces`.
    candidates: Vec<u32>,
    /// One per face.
    pieces: Vec<Piece>,
}

/// A face's piece of wall: its surface point, and the wall's direction through it (unit)
/// when the faces around it lie on a line (`None` at a corner or an isolated face).
#[derive(Clone, Copy, Debug)]
struct Piece {
    surface: Point2,
    along: Option<Point2>,
}

/// Faces within this many cells of a face fit its wall's direction.
const FIT_REACH: usize = 2;
/// A face's neighbours lie on a line when the spread across it is below this share of
/// the spread along it (ratio of the covariance's eigenvalues).
const LINE_RATIO: f64 = 0.1;
/// Each face stands for the wall this far along it either way, in cells: past half a cell
/// so that the pieces of a diagonal wall (faces √2 cells apart along it) meet.
const PIECE_HALF_CELLS: f64 = 0.75;

/// "Infinite" squared distance for the transform (cells, so any map fits well below it).
const FAR: f64 = 1e20;

/// One row or column's squared distances `out` and the index each came from `from`
/// (Felzenszwalb & Huttenlocher, §2.1: the lower envelope of the parabolas rooted at `f`).
fn transform_1d(f: &[f64], v: &mut [usize], z: &mut [f64], out: &mut [f64], from: &mut [usize]) {
    let n = f.len();
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let intersect = |p: usize| ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
        let mut s = intersect(v[k]);
        while s <= z[k] {
            k -= 1;
            s = intersect(v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for q in 0..n {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let d = q as f64 - v[k] as f64;
        out[q] = d * d + f[v[k]];
        from[q] = v[k];
    }
}

impl DistanceField {
    /// The field of the faces of `raster`'s cells for which `obstacle(log_odds)` holds
    /// (unknown cells are never obstacles; a face has a known free neighbour, log-odds
    /// below 0), each at its mean return in `hits` if it has one, else its centre;
    /// truncated at `max_m`. `None` when the raster has no face.
    pub fn new(
        raster: &Raster,
        obstacle: impl Fn(f32) -> bool,
        hits: Option<&SurfaceHits>,
        max_m: f64,
    ) -> Option<Self> {
        let (w, h) = (raster.width, raster.height);
        let free = |i: usize| raster.known[i] && raster.log_odds[i] < 0.0;
        let face = |i: usize| {
            let (c, r) = (i % w, i / w);
            raster.known[i]
                && obstacle(raster.log_odds[i])
                && ((c > 0 && free(i - 1))
                    || (c + 1 < w && free(i + 1))
                    || (r > 0 && free(i - w))
                    || (r + 1 < h && free(i + w)))
        };
        // Face indices are kept as u32 (a raster is bounded by `limits.export_cells`, 10⁸).
        if w.checked_mul(h).is_none_or(|n| n >= u32::MAX as usize) {
            return None;
        }
        let faces: Vec<bool> = (0..w * h).map(face).collect();
        if !faces.contains(&true) {
            return None;
        }
        let nearest = feature_transform(w, h, &faces);
        let res = raster.resolution;
        let first_centre = Point2::new(raster.origin.x + 0.5 * res, raster.origin.y + 0.5 * res);
        let surface: Vec<Point2> = (0..w * h)
            .map(|i| {
                let centre = Point2::new(first_centre.x + (i % w) as f64 * res, first_centre.y + (i / w) as f64 * res);
                let cell = CellIndex::new(raster.first_cell.x + (i % w) as i64, raster.first_cell.y + (i / w) as i64);
                match (faces[i], hits) {
                    (true, Some(hits)) => hits.mean(cell).unwrap_or(centre),
                    _ => centre,
                }
            })
            .collect();
        // Pieces numbered in cell order, one per face.
        let mut piece_of = vec![u32::MAX; w * h];
        let mut pieces = Vec::new();
        for i in (0..w * h).filter(|&i| faces[i]) {
            piece_of[i] = pieces.len() as u32;
            pieces.push(Piece { surface: surface[i], along: direction(w, h, i, &faces, &surface) });
        }
        let (starts, candidates) = candidate_lists(w, h, &nearest, &piece_of);
        Some(Self { width: w, height: h, resolution: res, first_centre, max_m, starts, candidates, pieces })
    }

    /// The truncation distance, metres.
    pub fn max_m(&self) -> f64 {
        self.max_m
    }

    /// The distance at `p` to the wall pieces of the faces nearest its cell and its
    /// neighbours (a face on a line: the segment through its surface point along the
    /// wall, three quarters of a cell either way, so a point on the wall between two faces is
    /// on it, as in point-to-line ICP; a corner: its surface point); `max_m` outside the
    /// raster or farther.
    pub fn at(&self, p: Point2) -> f64 {
        // The nearest cell centre, ⌊x + ½⌋ on the cell grid (truncation is the floor once
        // the range is checked; it spares a call to libm's `round` per point). `> 0`, not
        // `≥ 0`: a point half a cell before the first centre rounds away from it, as
        // `round` does (x + ½ is exact for x in (−½, 0)).
        let u = (p.x - self.first_centre.x) / self.resolution + 0.5;
        let v = (p.y - self.first_centre.y) / self.resolution + 0.5;
        if !(u > 0.0 && v > 0.0 && u < self.width as f64 && v < self.height as f64) {
            return self.max_m;
        }
        let cell = v as usize * self.width + u as usize;
        let mut best = self.max_m * self.max_m;
        for &c in &self.candidates[self.starts[cell]..self.starts[cell + 1]] {
            best = best.min(self.piece_distance2(&self.pieces[c as usize], p));
        }
        best.sqrt()
    }
}

/// For every cell, the pieces of the faces nearest it and its eight neighbours, each once
/// (neighbouring cells mostly share their nearest face), as `(starts, candidates)`.
fn candidate_lists(w: usize, h: usize, nearest: &[u32], piece_of: &[u32]) -> (Vec<usize>, Vec<u32>) {
    let mut starts = Vec::with_capacity(w * h + 1);
    let mut candidates = Vec::with_capacity(w * h);
    starts.push(0);
    for j in 0..h {
        for i in 0..w {
            let first = candidates.len();
            for jj in j.saturating_sub(1)..(j + 2).min(h) {
                for ii in i.saturating_sub(1)..(i + 2).min(w) {
                    let f = nearest[jj * w + ii];
                    if f != u32::MAX {
                        let piece = piece_of[f as usize];
                        if !candidates[first..].contains(&piece) {
                            candidates.push(piece);
                        }
                    }
                }
            }
            starts.push(candidates.len());
        }
    }
    (starts, candidates)
}

impl DistanceField {
    /// The squared distance from `p` to a face's piece of wall.
    fn piece_distance2(&self, piece: &Piece, p: Point2) -> f64 {
        let s = piece.surface;
        let (dx, dy) = (p.x - s.x, p.y - s.y);
        match piece.along {
            Some(t) => {
                let a = dx * t.x + dy * t.y;
                let n = -dx * t.y + dy * t.x;
                let past = (a.abs() - PIECE_HALF_CELLS * self.resolution).max(0.0);
                n * n + past * past
            }
            None => dx * dx + dy * dy,
        }
    }
}

/// The direction of the wall through face `i`: the principal axis of the surface points
/// of the faces within [`FIT_REACH`] cells, when they lie on a line.
fn direction(w: usize, h: usize, i: usize, faces: &[bool], surface: &[Point2]) -> Option<Point2> {
    let (c, r) = (i % w, i / w);
    let mut pts = Vec::with_capacity(25);
    for rr in r.saturating_sub(FIT_REACH)..(r + FIT_REACH + 1).min(h) {
        for cc in c.saturating_sub(FIT_REACH)..(c + FIT_REACH + 1).min(w) {
            if faces[rr * w + cc] {
                pts.push(surface[rr * w + cc]);
            }
        }
    }
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.x).sum::<f64>() / n, pts.iter().map(|p| p.y).sum::<f64>() / n);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p.x - mx, p.y - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // The eigenvalues of the 2 × 2 covariance and the major one's eigenvector.
    let (half_trace, det) = (0.5 * (sxx + syy), sxx * syy - sxy * sxy);
    let root = (half_trace * half_trace - det).max(0.0).sqrt();
    let (major, minor) = (half_trace + root, half_trace - root);
    if major <= 0.0 || minor > LINE_RATIO * major {
        return None;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    Some(Point2::new(theta.cos(), theta.sin()))
}

/// For every cell, the index of the nearest cell where `seed` holds (Euclidean, by
/// centres): Felzenszwalb & Huttenlocher's transform along the rows, then along the
/// columns over the rows' results, each pass remembering which parabola won.
fn feature_transform(w: usize, h: usize, seed: &[bool]) -> Vec<u32> {
    let n = w.max(h);
    let (mut v, mut z, mut f, mut out, mut from) =
        (vec![0; n], vec![0.0; n + 1], vec![0.0; n], vec![0.0; n], vec![0; n]);
    // Rows: squared distance along the row and the column of the nearest seed.
    let mut row_d = vec![FAR; w * h];
    let mut row_src = vec![0usize; w * h];
    for r in 0..h {
        for c in 0..w {
            f[c] = if seed[r * w + c] { 0.0 } else { FAR };
        }
        transform_1d(&f[..w], &mut v, &mut z, &mut out[..w], &mut from[..w]);
        for c in 0..w {
            row_d[r * w + c] = out[c];
            row_src[r * w + c] = from[c];
        }
    }
    // Columns: over the rows' squared distances; the winner's row gives the seed's column.
    let mut nearest = vec![u32::MAX; w * h];
    for c in 0..w {
        for r in 0..h {
            f[r] = row_d[r * w + c];
        }
        transform_1d(&f[..h], &mut v, &mut z, &mut out[..h], &mut from[..h]);
        for r in 0..h {
            if out[r] < FAR / 2.0 {
                let src_row = from[r];
                nearest[r * w + c] = (src_row * w + row_src[src_row * w + c]) as u32;
            }
        }
    }
    nearest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyParams;
    use crate::measurement::{Evidence, Ray, SensorId};
    use proptest::prelude::*;

    /// A raster of free cells with occupied `walls`, 0.1 m cells, centres on multiples.
    fn raster(w: usize, h: usize, walls: &[(usize, usize)]) -> Raster {
        let mut log_odds = vec![-2.0f32; w * h];
        for &(c, r) in walls {
            log_odds[r * w + c] = 3.0;
        }
        Raster {
            width: w,
            height: h,
            resolution: 0.1,
            origin: Point2::new(-0.05, -0.05),
            first_cell: CellIndex::new(0, 0),
            log_odds,
            known: vec![true; w * h],
            params: OccupancyParams::default(),
        }
    }

    #[test]
    fn no_obstacle_no_field() {
        assert!(DistanceField::new(&raster(5, 4, &[]), |l| l > 1.0, None, 1.0).is_none());
    }

    #[test]
    fn measures_to_the_face_and_truncates() {
        let f = DistanceField::new(&raster(30, 20, &[(10, 10)]), |l| l > 1.0, None, 0.5).unwrap();
        // Cell (10, 10)'s centre is at (1.0, 1.0).
        assert!(f.at(Point2::new(1.0, 1.0)).abs() < 1e-9);
        assert!((f.at(Point2::new(1.3, 1.0)) - 0.3).abs() < 1e-9);
        assert!((f.at(Point2::new(1.03, 1.04)) - 0.05).abs() < 1e-9);
        assert_eq!(f.at(Point2::new(2.5, 1.0)), 0.5);
        assert_eq!(f.at(Point2::new(-4.0, 1.0)), 0.5);
        // The raster's edge: half a cell before the first centre is outside (as `round`
        // puts it), just inside is in cell 0.
        let edge = DistanceField::new(&raster(30, 20, &[(0, 10)]), |l| l > 1.0, None, 0.5).unwrap();
        assert_eq!(edge.at(Point2::new(-0.05, 1.0)), 0.5);
        assert!((edge.at(Point2::new(-0.0499, 1.0)) - 0.0499).abs() < 1e-9);
    }

    #[test]
    fn the_inside_of_a_thick_wall_is_no_surface() {
        // A wall three cells thick (columns 10..=12): its middle column has no free
        // neighbour, so a point there is a cell from the faces, not on a surface.
        let walls: Vec<(usize, usize)> = (0..20).flat_map(|r| (10..=12).map(move |c| (c, r))).collect();
        let f = DistanceField::new(&raster(30, 20, &walls), |l| l > 1.0, None, 0.5).unwrap();
        assert!((f.at(Point2::new(1.1, 1.0)) - 0.1).abs() < 1e-9);
        assert!(f.at(Point2::new(1.0, 1.0)).abs() < 1e-9);
    }

    #[test]
    fn a_face_sits_at_its_returns() {
        let r = raster(30, 20, &[(10, 10)]);
        let geometry = GridGeometry::new(0.1, Point2::new(-0.05, -0.05)).unwrap();
        let mut hits = SurfaceHits::default();
        let mut data = RangeData::empty(SensorId(0), Evidence { p_hit: 0.7, p_miss: 0.4 });
        for y in [0.98, 1.02] {
            data.rays.push(Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(1.03, y), hit: true });
        }
        data.rays.push(Ray { origin: Point2::new(0.0, 0.0), end: Point2::new(0.97, 1.0), hit: false });
        hits.add(&data, &geometry);
        let f = DistanceField::new(&r, |l| l > 1.0, Some(&hits), 0.5).unwrap();
        assert!(f.at(Point2::new(1.03, 1.0)).abs() < 1e-9);
        assert!((f.at(Point2::new(1.23, 1.0)) - 0.2).abs() < 1e-9);
    }

    #[test]
    fn a_wall_is_a_line_not_a_row_of_points() {
        // A wall along column 10 (x = 1.0): between two faces' centres a point on it is on
        // the wall, and a point beside it is its normal distance off.
        let walls: Vec<(usize, usize)> = (0..20).map(|r| (10, r)).collect();
        let f = DistanceField::new(&raster(30, 20, &walls), |l| l > 1.0, None, 0.5).unwrap();
        assert!(f.at(Point2::new(1.0, 1.03)).abs() < 1e-9);
        assert!((f.at(Point2::new(1.07, 1.05)) - 0.07).abs() < 1e-9);
        // A diagonal wall: its faces are a cell apart in x and y, √2 cells along it.
        let diagonal: Vec<(usize, usize)> = (0..20).map(|r| (r + 5, r)).collect();
        let f = DistanceField::new(&raster(30, 20, &diagonal), |l| l > 1.0, None, 0.5).unwrap();
        // (1.05, 0.55) lies on the line y = x − 0.5 through the faces' centres.
        assert!(f.at(Point2::new(1.05, 0.55)).abs() < 1e-9, "{}", f.at(Point2::new(1.05, 0.55)));
    }

    proptest! {
        /// The candidate lists give what the nine-cell look-up they replaced gave, to the
        /// bit: the least over the pieces of the faces nearest the point's cell (rounded to
        /// the nearest centre) and its eight neighbours.
        #[test]
        fn the_candidate_lists_equal_the_nine_cell_lookup(
            walls in prop::collection::vec((0usize..17, 0usize..11), 1..8),
            (px, py) in (-0.2f64..1.8, -0.2f64..1.2),
        ) {
            let (w, h, max_m) = (17usize, 11usize, 100.0);
            let r = raster(w, h, &walls);
            let f = DistanceField::new(&r, |l| l > 1.0, None, max_m).unwrap();
            let wall = |c: usize, row: usize| r.log_odds[row * w + c] > 1.0;
            let faces: Vec<bool> = (0..w * h)
                .map(|i| {
                    let (c, row) = (i % w, i / w);
                    let around = [(c.wrapping_sub(1), row), (c + 1, row), (c, row.wrapping_sub(1)), (c, row + 1)];
                    wall(c, row) && around.iter().any(|&(cc, rr)| cc < w && rr < h && !wall(cc, rr))
                })
                .collect();
            let nearest = feature_transform(w, h, &faces);
            let p = Point2::new(px, py);
            // The first centre is at the origin.
            let (u, v) = ((p.x / 0.1).round(), (p.y / 0.1).round());
            let want = if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
                max_m
            } else {
                let (i, j) = (u as usize, v as usize);
                let mut best = max_m * max_m;
                for jj in j.saturating_sub(1)..(j + 2).min(h) {
                    for ii in i.saturating_sub(1)..(i + 2).min(w) {
                        let face = nearest[jj * w + ii] as usize;
                        let piece = faces[..face].iter().filter(|b| **b).count();
                        best = best.min(f.piece_distance2(&f.pieces[piece], p));
                    }
                }
                best.sqrt()
            };
            prop_assert_eq!(f.at(p).to_bits(), want.to_bits(), "{} against {} at {:?}", f.at(p), want, p);
        }

        /// A point is never farther from the walls than from the nearest face's centre,
        /// nor nearer than that less a piece's half length.
        #[test]
        fn bounded_by_the_faces_centres(
            walls in prop::collection::vec((0usize..17, 0usize..11), 1..6),
            (du, dv) in (-0.05f64..0.05, -0.05f64..0.05),
        ) {
            let r = raster(17, 11, &walls);
            let f = DistanceField::new(&r, |l| l > 1.0, None, 100.0).unwrap();
            for row in 0..11 {
                for col in 0..17 {
                    let p = Point2::new(col as f64 * 0.1 + du, row as f64 * 0.1 + dv);
                    let brute = walls
                        .iter()
                        .map(|&(c, w)| ((c as f64 * 0.1 - p.x).powi(2) + (w as f64 * 0.1 - p.y).powi(2)).sqrt())
                        .fold(f64::INFINITY, f64::min);
                    let got = f.at(p);
                    // Within reach of the neighbours' nearest faces.
                    if brute < 0.1 {
                        prop_assert!(got <= brute + 1e-9 && got >= brute - PIECE_HALF_CELLS * 0.1 - 1e-9, "{got} {brute} at {p:?}");
                    }
                }
            }
        }
    }
}
