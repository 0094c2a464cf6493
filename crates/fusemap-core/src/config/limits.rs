//! `[limits]`: resource budgets, so that no input — a wrong resolution, a range limit of
//! 10¹² m, a pose kilometres from the rest — can make a run grow until the allocator
//! aborts it.
//!
//! Each limit is checked before the allocation it guards and, when broken, gives one error
//! naming the limit, the value met and the key that raises it. The defaults are far above
//! what a real robot log needs (a 2.7 km² map at 5 cm, a 2.5 km ray at 5 cm), so a
//! run that meets one has a configuration or a log worth a look.
//!
//! * `ray_cells` is checked when the configuration is validated: every lidar's
//!   `max_range`, every camera's `max_depth_m` and SLAM's `max_range_m` over its cell size
//!   (a ray's length in cells bounds both its walk and the tiles it can allocate).
//! * `memory_mib` bounds the bytes of every grid a run holds at once. The maps count each
//!   tile with every layer it can carry (occupancy, semantic counts, the dynamic layer,
//!   the correlation scratch); their tile stores refuse to allocate past it and the engine
//!   turns that into an error after the observation that met it (see
//!   [`TileMap::set_tile_budget`](crate::grid::TileMap::set_tile_budget)). SLAM counts its
//!   submaps' grids and its loop search's branch-and-bound grids (whose cache,
//!   `slam.loop_closure_grid_cache_mib`, is a part of this budget, not beside it) after
//!   every scan; SLAM's pass ends before the mapping pass begins, so each holds to the
//!   whole budget.
//! * `map_cells` is the older cap in cells (whole 64 × 64 tiles), kept for configurations
//!   that set it: whichever of the two is tighter holds.
//! * `export_cells` is applied by the exporters: past it, a run writes the map's tiles
//!   sparsely instead of one dense raster of the bounding box of everything it touched.
//! * `decompressed_mib` is passed to the log readers (`fusemap-io`'s `ReadOptions`): a
//!   chunk that says or turns out to inflate past it is refused there.
//! * `beams_per_scan` and `image_pixels` are passed to the log readers too: a scan or an
//!   image (whose pixels a pass decodes) past them ends the read with an error at that
//!   message. The world-file loader holds its simulated scanner to `beams_per_scan`.
//! * `world_poses` and `world_beams` are checked by the world-file loader before it builds
//!   the trajectory.

use super::{err, FieldError};
use crate::grid::TILE_CELLS;
use serde::{Deserialize, Serialize};

/// The `[limits]` table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// MiB the grids of a run may hold: the maps (every layer of every tile counted) and
    /// SLAM's submaps. 1 GiB is 0.67 km² of lidar-only map at 5 cm (a cell costs a little
    /// over 4 bytes, plus 4 a class where a camera writes semantics and 12 with a dynamic
    /// layer), and leaves a 4 GiB machine room for the rest of the run.
    pub memory_mib: u64,
    /// Cells a map may hold, counted in whole 64 × 64 tiles: an older cap than
    /// `memory_mib`, which is the one to raise (2³⁰ cells need over 4 GiB).
    pub map_cells: u64,
    /// Cells one ray may cross: the longest range of any lidar, camera or SLAM over its
    /// cell size. 50,000 is 2.5 km at 5 cm, or 500 m at 1 cm.
    pub ray_cells: u64,
    /// Cells of a dense raster export (`map.npz`, `map.pgm`, pictures): 10⁸ is a 10,000 ×
    /// 10,000 raster, 500 m × 500 m at 5 cm. Past it the map is written sparsely (its
    /// tiles) unless `--crop` names a region that fits.
    pub export_cells: u64,
    /// MiB one chunk, message or line of a log may hold once decompressed (ROS 1 bz2/lz4
    /// chunks, MCAP chunks and records, rosbag2 zstd messages, gzipped CARMEN lines): past
    /// it the read stops with an error where the bomb or the corrupt size is met.
    pub decompressed_mib: u64,
    /// Beams one scan may hold, in a log or from a world file's simulated scanner: real 2D
    /// lidars have a few thousand, so 10⁶ is a corrupt message or a typo.
    pub beams_per_scan: u64,
    /// Pixels (`width × height`) of a camera image whose pixels a run decodes: 2²⁶ is an
    /// 8192 × 8192 image, eight times a 4K frame.
    pub image_pixels: u64,
    /// Poses (scans) a simulated world file's trajectory may have: 10⁷ is more than ten
    /// days of driving at 10 Hz; a larger `count` is far more likely a typo than a plan.
    pub world_poses: u64,
    /// Beams a world file's run may cast in all (poses × beams a scan; each is mapped):
    /// 2 × 10⁷ is about 110,000 scans of 181 beams, ten seconds of mapping.
    pub world_beams: u64,
}

impl Default for LimitsConfig {
    fn default() -> Self {
        Self {
            memory_mib: 1024,
            map_cells: 1 << 30,
            ray_cells: 50_000,
            export_cells: 100_000_000,
            decompressed_mib: 512,
            beams_per_scan: 1_000_000,
            image_pixels: 1 << 26,
            world_poses: 10_000_000,
            world_beams: 20_000_000,
        }
    }
}

impl LimitsConfig {
    /// The number of whole tiles `map_cells` allows (at least one).
    pub fn map_tiles(&self) -> usize {
        usize::try_from(self.map_cells.div_ceil(TILE_CELLS as u64)).unwrap_or(usize::MAX).max(1)
    }

    /// `memory_mib` in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.memory_mib.saturating_mul(1 << 20)
    }

    /// `decompressed_mib` in bytes.
    pub fn decompressed_bytes(&self) -> u64 {
        self.decompressed_mib.saturating_mul(1 << 20)
    }

    /// Checks the values themselves (every limit at least 1).
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        for (key, v) in [
            ("memory_mib", self.memory_mib),
            ("map_cells", self.map_cells),
            ("ray_cells", self.ray_cells),
            ("export_cells", self.export_cells),
            ("decompressed_mib", self.decompressed_mib),
            ("beams_per_scan", self.beams_per_scan),
            ("image_pixels", self.image_pixels),
            ("world_poses", self.world_poses),
            ("world_beams", self.world_beams),
        ] {
            if v == 0 {
                return Err(err(format!("limits.{key}"), "must be at least 1"));
            }
        }
        Ok(())
    }

    /// Checks that a ray of `range_m` metres over cells of `cell_m` metres stays within
    /// `ray_cells`. `what` names the range's key (`sensor[0].max_range`), `cell_key` the
    /// cell size's.
    pub(super) fn check_ray(&self, what: &str, range_m: f64, cell_key: &str, cell_m: f64) -> Result<(), FieldError> {
        let cells = range_m / cell_m;
        if cells.is_finite() && cells <= self.ray_cells as f64 {
            return Ok(());
        }
        Err(err(
            "limits.ray_cells",
            format!(
                "{what} = {range_m} m over {cell_key} = {cell_m} m is {cells:.0} cells per ray, over the limit of {}; \
                 coarsen {cell_key}, shorten {what}, or raise limits.ray_cells",
                self.ray_cells
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_within_the_budget_pass_and_longer_ones_name_every_key() {
        let l = LimitsConfig::default();
        assert!(l.check_ray("sensor[0].max_range", 10.0, "map.resolution", 0.05).is_ok());
        assert!(l.check_ray("sensor[0].max_range", 2500.0, "map.resolution", 0.05).is_ok());
        let e = l.check_ray("sensor[0].max_range", 10.0, "map.resolution", 1e-5).unwrap_err();
        assert_eq!(e.field, "limits.ray_cells");
        for part in ["sensor[0].max_range = 10 m", "map.resolution = 0.00001 m", "1000000 cells", "50000"] {
            assert!(e.message.contains(part), "{part}: {}", e.message);
        }
        assert!(l.check_ray("x", f64::INFINITY, "map.resolution", 0.05).is_err());
        assert!(l.check_ray("x", 1.0, "map.resolution", 0.0).is_err());
    }

    #[test]
    fn the_map_budget_is_whole_tiles_and_never_zero() {
        let l = |map_cells| LimitsConfig { map_cells, ..Default::default() };
        assert_eq!(l(1).map_tiles(), 1);
        assert_eq!(l(4096).map_tiles(), 1);
        assert_eq!(l(4097).map_tiles(), 2);
        assert_eq!(LimitsConfig::default().map_tiles(), 1 << 18);
        assert!(l(0).validate().is_err());
    }
}
