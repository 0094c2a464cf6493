//! Sparse tiled storage shared by every layer.
//!
//! The map is a hash map from full-width [`TileKey`]s to fixed-size tiles of
//! `TILE_SIZE × TILE_SIZE` cells, so it grows in any direction as the robot explores and
//! unobserved tiles cost nothing (the "fixed-size maps" and "20-bit key" lessons of
//! Hector mapping and Bonxai). Hot loops resolve a tile once and then index inside it;
//! the hash map is touched only when a ray crosses into another tile.

use super::{CellIndex, TileKey};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiply-rotate hasher for tile keys (the FxHash recipe): tile keys are small
/// integers, not attacker-controlled, and SipHash would cost more than the walk inside a
/// tile.
#[derive(Default, Clone, Copy)]
pub struct TileKeyHasher(u64);

impl Hasher for TileKeyHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    #[inline]
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
}

/// Something that can be stored as a tile of a layer.
pub trait Tile {
    /// A tile in which every cell is unobserved.
    fn empty() -> Self;
}

/// Sparse tiles keyed by [`TileKey`]. Tiles live in a `Vec` and the hash map holds their
/// index, so iteration order is insertion order and deterministic.
///
/// **Budget.** A map can be given a largest number of tiles
/// ([`set_tile_budget`](Self::set_tile_budget)). Past it, [`get_or_insert`](Self::get_or_insert)
/// allocates nothing: it hands out one scratch tile that is not part of the map and raises
/// [`over_budget`](Self::over_budget). The walk inside a tile stays as it is (no fallible
/// path in the hot loop, one comparison on the cold path that allocates); whoever drives
/// the insertion checks the flag after each observation and stops the run — the map is no
/// longer complete once it is raised.
pub struct TileMap<T> {
    index: HashMap<TileKey, u32, BuildHasherDefault<TileKeyHasher>>,
    keys: Vec<TileKey>,
    tiles: Vec<Box<T>>,
    budget: usize,
    scratch: Option<Box<T>>,
    over_budget: bool,
}

impl<T: Tile> Default for TileMap<T> {
    fn default() -> Self {
        Self {
            index: HashMap::default(),
            keys: Vec::new(),
            tiles: Vec::new(),
            budget: usize::MAX,
            scratch: None,
            over_budget: false,
        }
    }
}

impl<T: Tile> TileMap<T> {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of allocated tiles.
    pub fn len(&self) -> usize {
        self.tiles.len()
    }

    /// True when no tile is allocated.
    pub fn is_empty(&self) -> bool {
        self.tiles.is_empty()
    }

    /// The tile at `key`, if allocated.
    #[inline]
    pub fn get(&self, key: TileKey) -> Option<&T> {
        self.index.get(&key).map(|&i| &*self.tiles[i as usize])
    }

    /// The index of the tile at `key` in allocation order, if allocated.
    #[inline]
    pub(super) fn index_of(&self, key: TileKey) -> Option<usize> {
        self.index.get(&key).map(|&i| i as usize)
    }

    /// The tile at allocation index `i`.
    #[inline]
    pub(super) fn tile_at_mut(&mut self, i: usize) -> &mut T {
        &mut self.tiles[i]
    }

    /// The tiles at allocation indices `indices` (strictly increasing), each once.
    pub(super) fn tiles_at_mut(&mut self, indices: impl Iterator<Item = usize>) -> Vec<&mut T> {
        super::tile_waves::pick_mut(&mut self.tiles, indices).into_iter().map(|b| &mut **b).collect()
    }

    /// Adds `tile` at `key` (not yet allocated); the caller made sure the budget has room.
    pub(super) fn adopt(&mut self, key: TileKey, tile: Box<T>) {
        debug_assert!(!self.index.contains_key(&key), "a tile is adopted once");
        self.index.insert(key, self.tiles.len() as u32);
        self.keys.push(key);
        self.tiles.push(tile);
    }

    /// The tile at `key`, allocating an empty one if needed; past the budget, the scratch
    /// tile (see the type docs). The lookup inlines into the walks; the allocation, once
    /// per tile in a map's life, does not.
    #[inline(always)]
    pub fn get_or_insert(&mut self, key: TileKey) -> &mut T {
        match self.index.get(&key) {
            Some(&i) => &mut self.tiles[i as usize],
            None => self.allocate(key),
        }
    }

    /// A new empty tile at `key` (not yet allocated); past the budget, the scratch tile.
    #[inline(never)]
    fn allocate(&mut self, key: TileKey) -> &mut T {
        if self.tiles.len() >= self.budget {
            return self.scratch_tile();
        }
        let i = self.tiles.len();
        self.tiles.push(Box::new(T::empty()));
        self.keys.push(key);
        self.index.insert(key, i as u32);
        &mut self.tiles[i]
    }

    #[cold]
    fn scratch_tile(&mut self) -> &mut T {
        self.over_budget = true;
        self.scratch.get_or_insert_with(|| Box::new(T::empty()))
    }

    /// Allocates at most `tiles` tiles from now on (tiles already allocated stay).
    pub fn set_tile_budget(&mut self, tiles: usize) {
        self.budget = tiles;
    }

    /// The largest number of tiles this map allocates.
    pub fn tile_budget(&self) -> usize {
        self.budget
    }

    /// True once a write needed a tile past the budget: the map misses that write.
    pub fn over_budget(&self) -> bool {
        self.over_budget
    }

    /// The tile holding `cell`, if allocated, and the cell's offset in it.
    pub fn get_cell(&self, cell: CellIndex) -> Option<(&T, usize)> {
        self.get(cell.tile()).map(|t| (t, cell.offset_in_tile()))
    }

    /// All tiles with their keys, in allocation order.
    pub fn iter(&self) -> impl Iterator<Item = (TileKey, &T)> {
        self.keys.iter().copied().zip(self.tiles.iter().map(|b| &**b))
    }

    /// Bytes held by tiles (not counting the index).
    pub fn tile_bytes(&self) -> usize {
        self.tiles.len() * std::mem::size_of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Counter([u8; 4]);
    impl Tile for Counter {
        fn empty() -> Self {
            Counter([0; 4])
        }
    }

    #[test]
    fn tiles_are_allocated_on_demand_with_wide_keys() {
        let mut m: TileMap<Counter> = TileMap::new();
        assert!(m.is_empty());
        let far = TileKey { x: i64::MAX >> 7, y: i64::MIN >> 7 };
        m.get_or_insert(far).0[0] = 7;
        m.get_or_insert(TileKey { x: -1, y: 0 }).0[1] = 3;
        assert_eq!(m.len(), 2);
        assert_eq!(m.get(far).unwrap().0[0], 7);
        // A key that differs only in the high bits is a different tile.
        assert!(m.get(TileKey { x: (i64::MAX >> 7) ^ (1 << 40), y: i64::MIN >> 7 }).is_none());
        m.get_or_insert(far).0[0] += 1;
        assert_eq!(m.len(), 2);
        assert_eq!(m.get(far).unwrap().0[0], 8);
        let keys: Vec<_> = m.iter().map(|(k, _)| k).collect();
        assert_eq!(keys, vec![far, TileKey { x: -1, y: 0 }]);
    }

    #[test]
    fn past_the_budget_nothing_is_allocated_and_the_map_says_so() {
        let mut m: TileMap<Counter> = TileMap::new();
        m.set_tile_budget(2);
        m.get_or_insert(TileKey { x: 0, y: 0 }).0[0] = 1;
        m.get_or_insert(TileKey { x: 1, y: 0 }).0[0] = 2;
        assert!(!m.over_budget());
        // Tiles already held are still served; a third one is not allocated.
        m.get_or_insert(TileKey { x: 0, y: 0 }).0[0] += 1;
        assert!(!m.over_budget());
        m.get_or_insert(TileKey { x: 2, y: 0 }).0[0] = 9;
        m.get_or_insert(TileKey { x: 3, y: 0 }).0[0] = 9;
        assert!(m.over_budget());
        assert_eq!(m.len(), 2);
        assert!(m.get(TileKey { x: 2, y: 0 }).is_none());
        assert_eq!(m.get(TileKey { x: 0, y: 0 }).unwrap().0[0], 2);
        assert_eq!(m.tile_budget(), 2);
    }
}
