//! The sparse `.npz`: a map too large for one dense raster (past `[limits] export_cells`),
//! written as it is stored, tile by tile.

use super::{NpyArray, NpyData};
use crate::{Error, Location, Result};
use fusemap_core::grid::{SparseTiles, TILE_CELLS, TILE_SIZE};
use std::path::Path;

/// Writes a map's tiles as `.npz`, atomically, with exactly these arrays (N tiles, T =
/// 64 cells on a tile's side):
///
/// | name | dtype | shape | meaning |
/// |---|---|---|---|
/// | `tile_keys` | int64 | (N, 2) | tile `(kx, ky)`: it covers cells `kx·T … kx·T + T − 1` in x, the same in y |
/// | `tile_log_odds` | float32 | (N, T, T) | log-odds `[iy, ix]` inside the tile, row 0 the lowest y; NaN never observed |
/// | `tile_size` | int32 | () | T |
/// | `resolution` | float64 | () | cell side, metres |
/// | `origin` | float64 | (2,) | world x, y of the lower-left corner of grid cell (0, 0) |
///
/// Grid cell `(i, j)` of tile `n` at `[n, iy, ix]` has `i = kx·T + ix`, `j = ky·T + iy`
/// and covers `origin + (i, j) · resolution` to `origin + (i + 1, j + 1) · resolution`.
/// Occupancy is `1 − 1/(1 + e^l)`. A dense map's arrays hold the same log-odds: the cell
/// `(i, j)` of a dense `map.npz` whose `origin` is the corner of cell `(i0, j0)` is its
/// `log_odds[j − j0, i − i0]`.
pub fn write_sparse_map_npz(path: &Path, tiles: &SparseTiles) -> Result<()> {
    let n = tiles.keys.len();
    if tiles.log_odds.len() != n * TILE_CELLS {
        return Err(Error::format(
            path,
            Location::Field("tile_log_odds".into()),
            format!("{} values for {n} tiles of {TILE_CELLS} cells", tiles.log_odds.len()),
        ));
    }
    let keys: Vec<i64> = tiles.keys.iter().flat_map(|k| [k.x, k.y]).collect();
    let tile_size = [TILE_SIZE as i32];
    let resolution = [tiles.resolution];
    let origin = [tiles.origin.x, tiles.origin.y];
    let arrays = vec![
        ("tile_keys", NpyArray::new(&[n, 2], NpyData::I64(&keys))),
        ("tile_log_odds", NpyArray::new(&[n, TILE_SIZE, TILE_SIZE], NpyData::F32(&tiles.log_odds))),
        ("tile_size", NpyArray::new(&[], NpyData::I32(&tile_size))),
        ("resolution", NpyArray::new(&[], NpyData::F64(&resolution))),
        ("origin", NpyArray::new(&[2], NpyData::F64(&origin))),
    ];
    super::write_arrays(path, arrays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npz::{read_npz, NpyValues};
    use fusemap_core::geometry::Point2;
    use fusemap_core::grid::TileKey;

    #[test]
    fn tiles_round_trip_with_their_keys() {
        let mut log_odds = vec![f32::NAN; 2 * TILE_CELLS];
        log_odds[5] = 1.5;
        log_odds[TILE_CELLS + 64] = -0.25;
        let tiles = SparseTiles {
            keys: vec![TileKey { x: -3, y: 1 << 40 }, TileKey { x: 7, y: -9 }],
            log_odds,
            resolution: 0.05,
            origin: Point2::new(-0.025, -0.025),
        };
        let dir = crate::testdata::temp_dir("sparse-npz");
        let path = dir.join("map.npz");
        write_sparse_map_npz(&path, &tiles).unwrap();
        let keys = read_npz(&path, "tile_keys").unwrap();
        assert_eq!(keys.shape, vec![2, 2]);
        assert_eq!(keys.values, NpyValues::I64(vec![-3, 1 << 40, 7, -9]));
        let l = read_npz(&path, "tile_log_odds").unwrap();
        assert_eq!(l.shape, vec![2, 64, 64]);
        let NpyValues::F32(v) = l.values else { panic!("f32") };
        assert_eq!(v[5], 1.5);
        assert_eq!(v[TILE_CELLS + 64], -0.25);
        assert_eq!(v.iter().filter(|x| !x.is_nan()).count(), 2);
        assert_eq!(read_npz(&path, "tile_size").unwrap().values, NpyValues::I32(vec![64]));
        assert_eq!(read_npz(&path, "origin").unwrap().values, NpyValues::F64(vec![-0.025, -0.025]));
        let bad = SparseTiles { log_odds: vec![0.0; 3], ..tiles };
        assert!(write_sparse_map_npz(&path, &bad).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
