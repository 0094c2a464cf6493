//! World ↔ cell arithmetic, in one place (after grid_map's `GridMapMath` and Cartographer's
//! `MapLimits`). Storage never does its own index arithmetic.

use crate::geometry::Point2;
use serde::{Deserialize, Serialize};

/// Cells per tile side. Tiles are square, `TILE_SIZE × TILE_SIZE` cells.
pub const TILE_SIZE: usize = 64;
/// log2 of [`TILE_SIZE`].
pub const TILE_SHIFT: u32 = 6;
/// Mask of a cell's position inside its tile.
pub const TILE_MASK: i64 = TILE_SIZE as i64 - 1;
/// Cells per tile.
pub const TILE_CELLS: usize = TILE_SIZE * TILE_SIZE;

/// A cell's integer coordinates. Full 64-bit width: the map can grow anywhere a `f64`
/// metre coordinate can point without the key truncation that Bonxai and MOLA had to fix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct CellIndex {
    /// Column (x direction).
    pub x: i64,
    /// Row (y direction).
    pub y: i64,
}

impl CellIndex {
    /// A cell index from its column and row.
    pub const fn new(x: i64, y: i64) -> Self {
        Self { x, y }
    }

    /// The tile holding this cell (`floor(x / TILE_SIZE)` via an arithmetic shift).
    #[inline]
    pub fn tile(self) -> TileKey {
        TileKey { x: self.x >> TILE_SHIFT, y: self.y >> TILE_SHIFT }
    }

    /// The cell's offset inside its tile, row-major (`row * TILE_SIZE + column`).
    #[inline]
    pub fn offset_in_tile(self) -> usize {
        (((self.y & TILE_MASK) << TILE_SHIFT) | (self.x & TILE_MASK)) as usize
    }
}

/// A tile's integer coordinates (`cell >> TILE_SHIFT`), full 64-bit width.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TileKey {
    /// Tile column.
    pub x: i64,
    /// Tile row.
    pub y: i64,
}

impl TileKey {
    /// The tile's first (lowest x, lowest y) cell.
    pub fn first_cell(self) -> CellIndex {
        CellIndex::new(self.x << TILE_SHIFT, self.y << TILE_SHIFT)
    }
}

/// An inclusive rectangle of cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellBox {
    /// Lowest column and row.
    pub min: CellIndex,
    /// Highest column and row (inclusive).
    pub max: CellIndex,
}

impl CellBox {
    /// Columns covered.
    pub fn width(&self) -> usize {
        (self.max.x - self.min.x + 1) as usize
    }

    /// Rows covered.
    pub fn height(&self) -> usize {
        (self.max.y - self.min.y + 1) as usize
    }

    /// Cells covered.
    pub fn len(&self) -> usize {
        self.width() * self.height()
    }

    /// Never true: a box holds at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The smallest box holding both.
    pub fn union(self, other: CellBox) -> CellBox {
        CellBox {
            min: CellIndex::new(self.min.x.min(other.min.x), self.min.y.min(other.min.y)),
            max: CellIndex::new(self.max.x.max(other.max.x), self.max.y.max(other.max.y)),
        }
    }

    /// True when the cell lies inside.
    pub fn contains(&self, c: CellIndex) -> bool {
        c.x >= self.min.x && c.x <= self.max.x && c.y >= self.min.y && c.y <= self.max.y
    }
}

/// The metric placement of a grid: cell size and where cell (0, 0) sits.
///
/// Cell `(i, j)` covers `[origin.x + i·res, origin.x + (i+1)·res) × [origin.y + j·res, …)`.
/// `origin` is the lower-left *corner* of cell (0, 0), as in ROS map_server YAML files.
/// The default alignment puts cell *centres* on multiples of the resolution
/// (`origin = -res/2`): the robot's start sits mid-cell and walls at round coordinates do
/// not fall on a cell border, where floating-point rounding would scatter their hits over
/// two rows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridGeometry {
    resolution: f64,
    origin: Point2,
}

/// Why a grid geometry is invalid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// Resolution not finite and positive.
    #[error("resolution must be a finite number > 0, got {0}")]
    Resolution(f64),
    /// Origin not finite.
    #[error("origin must be finite, got ({0}, {1})")]
    Origin(f64, f64),
}

impl GridGeometry {
    /// A geometry with cell (0, 0)'s lower-left corner at `origin`.
    pub fn new(resolution: f64, origin: Point2) -> Result<Self, GeometryError> {
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(GeometryError::Resolution(resolution));
        }
        if !origin.is_finite() {
            return Err(GeometryError::Origin(origin.x, origin.y));
        }
        Ok(Self { resolution, origin })
    }

    /// A geometry whose cell centres lie on multiples of `resolution`.
    pub fn centered(resolution: f64) -> Result<Self, GeometryError> {
        Self::new(resolution, Point2::new(-resolution / 2.0, -resolution / 2.0))
    }

    /// Cell side, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Lower-left corner of cell (0, 0), metres.
    pub fn origin(&self) -> Point2 {
        self.origin
    }

    /// A world point in continuous cell units (cell (i, j) spans `[i, i+1) × [j, j+1)`).
    #[inline]
    pub fn to_cell_units(&self, p: Point2) -> (f64, f64) {
        ((p.x - self.origin.x) / self.resolution, (p.y - self.origin.y) / self.resolution)
    }

    /// The cell holding a world point. Uses `floor`: truncation toward zero (the design
    /// document's `int()`) would put every point in (-res, 0) into cell 0.
    /// Returns `None` for non-finite points or ones beyond the `i64` range.
    #[inline]
    pub fn cell_of(&self, p: Point2) -> Option<CellIndex> {
        let (u, v) = self.to_cell_units(p);
        let (fx, fy) = (u.floor(), v.floor());
        // 2^62 keeps all later ±1 and tile arithmetic clear of overflow.
        const LIMIT: f64 = 4.611_686_018_427_388e18;
        if fx.abs() < LIMIT && fy.abs() < LIMIT {
            Some(CellIndex::new(fx as i64, fy as i64))
        } else {
            None
        }
    }

    /// The world coordinates of a cell's centre.
    pub fn cell_center(&self, c: CellIndex) -> Point2 {
        Point2::new(
            self.origin.x + (c.x as f64 + 0.5) * self.resolution,
            self.origin.y + (c.y as f64 + 0.5) * self.resolution,
        )
    }

    /// The world coordinates of a cell's lower-left corner.
    pub fn cell_corner(&self, c: CellIndex) -> Point2 {
        Point2::new(self.origin.x + c.x as f64 * self.resolution, self.origin.y + c.y as f64 * self.resolution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn floor_not_truncation_for_negative_coordinates() {
        let g = GridGeometry::new(0.05, Point2::new(0.0, 0.0)).unwrap();
        // The document's int((x - origin) / res) gives 0 for x = -0.01; the right cell is -1.
        assert_eq!(g.cell_of(Point2::new(-0.01, -0.01)), Some(CellIndex::new(-1, -1)));
        assert_eq!((-0.01f64 / 0.05) as i64, 0, "what truncation would have done");
        assert_eq!(g.cell_of(Point2::new(0.01, -0.06)), Some(CellIndex::new(0, -2)));
        assert_eq!(g.cell_of(Point2::new(-0.05, 0.0)), Some(CellIndex::new(-1, 0)));
    }

    #[test]
    fn centered_geometry_puts_round_coordinates_mid_cell() {
        let g = GridGeometry::centered(0.05).unwrap();
        assert_eq!(g.cell_of(Point2::new(0.0, 0.0)), Some(CellIndex::new(0, 0)));
        assert_eq!(g.cell_of(Point2::new(2.0, -2.0)), Some(CellIndex::new(40, -40)));
        // A wall point that rounding put 1 ulp either side of y = 2 stays in one row.
        assert_eq!(g.cell_of(Point2::new(1.0, 2.0 - 4e-16)).unwrap().y, 40);
        assert_eq!(g.cell_of(Point2::new(1.0, 2.0 + 4e-16)).unwrap().y, 40);
        let c = g.cell_center(CellIndex::new(40, -40));
        assert!((c.x - 2.0).abs() < 1e-12 && (c.y + 2.0).abs() < 1e-12);
    }

    #[test]
    fn tiles_use_floor_division() {
        assert_eq!(CellIndex::new(-1, 64).tile(), TileKey { x: -1, y: 1 });
        assert_eq!(CellIndex::new(-64, -65).tile(), TileKey { x: -1, y: -2 });
        assert_eq!(CellIndex::new(-1, 0).offset_in_tile(), 63);
        assert_eq!(CellIndex::new(0, -1).offset_in_tile(), 63 * 64);
    }

    #[test]
    fn non_finite_points_have_no_cell() {
        let g = GridGeometry::centered(0.1).unwrap();
        assert_eq!(g.cell_of(Point2::new(f64::NAN, 0.0)), None);
        assert_eq!(g.cell_of(Point2::new(0.0, f64::INFINITY)), None);
        assert_eq!(g.cell_of(Point2::new(1e300, 0.0)), None);
    }

    #[test]
    fn bad_geometry_is_rejected() {
        assert!(GridGeometry::new(0.0, Point2::default()).is_err());
        assert!(GridGeometry::new(-1.0, Point2::default()).is_err());
        assert!(GridGeometry::new(f64::NAN, Point2::default()).is_err());
        assert!(GridGeometry::new(0.1, Point2::new(f64::INFINITY, 0.0)).is_err());
    }

    proptest! {
        #[test]
        fn a_point_lies_in_its_cell(x in -1e5..1e5f64, y in -1e5..1e5f64, res in 0.01..1.0f64) {
            let g = GridGeometry::new(res, Point2::new(-3.3, 7.1)).unwrap();
            let c = g.cell_of(Point2::new(x, y)).unwrap();
            let lo = g.cell_corner(c);
            // Allow for the rounding of the division at the cell border.
            let eps = 1e-9 * (1.0 + x.abs().max(y.abs()));
            prop_assert!(lo.x <= x + eps && x < lo.x + res + eps);
            prop_assert!(lo.y <= y + eps && y < lo.y + res + eps);
            prop_assert_eq!(g.cell_of(g.cell_center(c)), Some(c));
        }

        #[test]
        fn tile_and_offset_recompose_the_cell(x in -1_000_000i64..1_000_000, y in -1_000_000i64..1_000_000) {
            let c = CellIndex::new(x, y);
            let t = c.tile();
            let o = c.offset_in_tile() as i64;
            let first = t.first_cell();
            prop_assert_eq!(first.x + (o & TILE_MASK), x);
            prop_assert_eq!(first.y + (o >> TILE_SHIFT), y);
        }
    }
}
