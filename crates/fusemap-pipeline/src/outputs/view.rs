//! Which view of the map a run exports: the dense raster of everything observed, of a
//! `--crop` region, or — past `[limits] export_cells` — the map's tiles as stored with an
//! overview picture, so a map that is large only because it spans two distant places is
//! still written instead of failing after it was built.

use super::OutputError;
use fusemap_core::config::{OutputConfig, Plan};
use fusemap_core::fusion::export_bytes_per_cell;
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellBox, ExtraLayers, GridGeometry, LayeredGrid, Raster, SparseTiles, TILE_CELLS};

/// Largest side of the overview picture of a sparse export, in pixels before enlargement.
pub const OVERVIEW_SIDE: usize = 4096;

/// A region of the map to export densely, metres, from `--crop x0,y0,x1,y1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crop {
    /// Lower-left corner.
    pub min: Point2,
    /// Upper-right corner.
    pub max: Point2,
}

/// Parses `x0,y0,x1,y1` (metres, x0 < x1, y0 < y1), for clap.
pub fn parse_crop(s: &str) -> Result<Crop, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|_| format!("`{t}` is not a number")))
        .collect::<Result<_, _>>()?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(format!("expected x0,y0,x1,y1 (four numbers, metres), got {} values", v.len()));
    };
    if !v.iter().all(|x| x.is_finite()) {
        return Err("every value must be finite".into());
    }
    if !(x0 < x1 && y0 < y1) {
        return Err(format!("need x0 < x1 and y0 < y1, got {x0},{y0},{x1},{y1}"));
    }
    Ok(Crop { min: Point2::new(x0, y0), max: Point2::new(x1, y1) })
}

/// What a run exports.
pub struct ExportOptions {
    /// A region to export densely instead of the known box.
    pub crop: Option<Crop>,
    /// `[limits] export_cells`.
    pub export_cells: u64,
    /// `[output]`: the optional formats to write.
    pub formats: OutputConfig,
}

impl Default for ExportOptions {
    fn default() -> Self {
        Self {
            crop: None,
            export_cells: fusemap_core::config::LimitsConfig::default().export_cells,
            formats: OutputConfig::default(),
        }
    }
}

impl ExportOptions {
    /// The export `plan` asks for, with `crop` when the user gave one.
    pub fn of(plan: &Plan, crop: Option<Crop>) -> Self {
        Self { crop, export_cells: plan.limits.export_cells, formats: plan.output }
    }
}

/// The view of the map a run writes.
pub enum MapView {
    /// Nothing was observed (no crop asked for).
    Empty,
    /// One dense raster: the known box, or the crop.
    Dense(Raster),
    /// The map's tiles and an overview of `area` (its resolution says how many cells one
    /// pixel covers).
    Sparse {
        /// The tiles.
        tiles: SparseTiles,
        /// The overview.
        overview: Raster,
        /// The known box.
        area: CellBox,
    },
}

/// Cells in `b`, without overflow.
fn cells(b: CellBox) -> u128 {
    b.width() as u128 * b.height() as u128
}

/// The cells of `crop` on `geometry`, refused past `limit` cells (`[limits] export_cells`)
/// or outside the grid's index range. Checked before a run as well as at its end.
pub fn crop_area(geometry: &GridGeometry, c: &Crop, limit: u64) -> Result<CellBox, OutputError> {
    let (Some(min), Some(max)) = (geometry.cell_of(c.min), geometry.cell_of(c.max)) else {
        return Err(OutputError::Crop(format!(
            "--crop {},{},{},{}: beyond the grid's index range",
            c.min.x, c.min.y, c.max.x, c.max.y
        )));
    };
    let area = CellBox { min, max };
    let n = cells(area);
    if n > limit as u128 {
        return Err(OutputError::Crop(format!(
            "--crop {},{},{},{} is {} x {} = {n} cells at {} m, over limits.export_cells = {limit}; \
             crop a smaller region or raise limits.export_cells",
            c.min.x,
            c.min.y,
            c.max.x,
            c.max.y,
            area.width(),
            area.height(),
            geometry.resolution()
        )));
    }
    Ok(area)
}

/// The memory a dense export may take: the bytes `[limits] memory_mib` leaves beside the
/// maps' tiles, and the bytes a cell of the raster (with its layers) takes
/// ([`Engine::export_room`](fusemap_core::fusion::Engine::export_room)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExportRoom {
    /// Bytes left.
    pub bytes: u64,
    /// Bytes a cell.
    pub per_cell: usize,
}

impl ExportRoom {
    /// The room of `(bytes, per_cell)`, as the engine gives it.
    pub fn of(room: Option<(u64, usize)>) -> Option<Self> {
        room.map(|(bytes, per_cell)| Self { bytes, per_cell })
    }

    /// Bytes `n` cells need.
    fn needs(&self, n: u128) -> u128 {
        n.saturating_mul(self.per_cell as u128)
    }

    /// True when `n` cells fit.
    fn fits(&self, n: u128) -> bool {
        self.needs(n) <= self.bytes as u128
    }

    /// The room left once `bytes` more are held beside the maps (the lidar returns of an
    /// endpoint cloud).
    pub fn without(self, bytes: u64) -> Self {
        Self { bytes: self.bytes.saturating_sub(bytes), ..self }
    }
}

/// The side of a sparse export's overview: [`OVERVIEW_SIDE`], or less where the room left
/// beside the maps, less the copy of their `tiles` as stored (a log-odds a cell,
/// [`SparseTiles`]), cannot hold that picture at what a cell of a dense export without
/// layers takes while it is written.
fn overview_side(room: Option<ExportRoom>, tiles: usize) -> usize {
    let Some(r) = room else { return OVERVIEW_SIDE };
    let copy = (tiles as u64).saturating_mul((TILE_CELLS * std::mem::size_of::<f32>()) as u64);
    let pixels = r.bytes.saturating_sub(copy) / export_bytes_per_cell(0) as u64;
    usize::try_from(pixels.isqrt()).unwrap_or(usize::MAX).clamp(1, OVERVIEW_SIDE)
}

/// Chooses the view of `grid` to export under `options`, within `room` when the run has a
/// memory budget; a note says why when it is not the dense known box.
pub fn view_of<L: ExtraLayers>(
    grid: &LayeredGrid<L>,
    options: &ExportOptions,
    room: Option<ExportRoom>,
    notes: &mut Vec<String>,
) -> Result<MapView, OutputError> {
    let limit = options.export_cells;
    if let Some(c) = options.crop {
        let area = crop_area(grid.geometry(), &c, limit)?;
        if let Some(r) = room.filter(|r| !r.fits(cells(area))) {
            return Err(OutputError::Crop(format!(
                "--crop {},{},{},{}: its {} cells need {} MiB as rasters, more than the {} MiB limits.memory_mib \
                 leaves beside the maps; crop a smaller region or raise limits.memory_mib",
                c.min.x,
                c.min.y,
                c.max.x,
                c.max.y,
                cells(area),
                r.needs(cells(area)) >> 20,
                r.bytes >> 20
            )));
        }
        let raster = grid.raster(area);
        if raster.known_count() == 0 {
            notes.push("no observed cell lies inside --crop: the map files are all unknown".into());
        }
        return Ok(MapView::Dense(raster));
    }
    let Some(area) = grid.known_box() else { return Ok(MapView::Empty) };
    let n = cells(area);
    let over_memory = room.filter(|r| !r.fits(n));
    if n <= limit as u128 && over_memory.is_none() {
        return Ok(match grid.known_raster() {
            Some(r) => MapView::Dense(r),
            None => MapView::Empty,
        });
    }
    let Some((overview, factor)) = grid.overview(overview_side(room, grid.tile_count())) else {
        return Ok(MapView::Empty);
    };
    let tiles = grid.sparse_tiles();
    let why = match over_memory {
        Some(r) if n <= limit as u128 => format!(
            "whose rasters need {} MiB, more than the {} MiB limits.memory_mib leaves beside the maps",
            r.needs(n) >> 20,
            r.bytes >> 20
        ),
        _ => format!("over limits.export_cells = {limit}"),
    };
    notes.push(format!(
        "the observed area spans {} x {} = {n} cells, {why}: the map is written \
         sparsely (map.npz holds its {} tiles of 64 x 64 cells with their keys; map.png is an overview at one \
         pixel per {factor} x {factor} cells; no map.pgm/map.yaml); give --crop x0,y0,x1,y1 for a dense region, \
         or raise the limit",
        area.width(),
        area.height(),
        tiles.keys.len()
    ));
    Ok(MapView::Sparse { tiles, overview, area })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::grid::{GridGeometry, OccupancyGrid, OccupancyParams};
    use fusemap_core::measurement::{Evidence, RangeData, Ray, SensorId};

    #[test]
    fn crops_parse_and_nonsense_is_refused() {
        let c = parse_crop("-1.5, 2,3,4.25").unwrap();
        assert_eq!((c.min.x, c.min.y, c.max.x, c.max.y), (-1.5, 2.0, 3.0, 4.25));
        for bad in ["1,2,3", "1,2,3,4,5", "a,2,3,4", "3,0,1,4", "0,0,inf,1", "0,0,NaN,1", ""] {
            assert!(parse_crop(bad).is_err(), "{bad}");
        }
    }

    fn two_sites(distance_m: f64) -> OccupancyGrid {
        let mut g = OccupancyGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        for x0 in [0.0, distance_m] {
            let mut d = RangeData::empty(SensorId(0), Evidence { p_hit: 0.7, p_miss: 0.4 });
            d.rays.push(Ray { origin: Point2::new(x0, 0.0), end: Point2::new(x0 + 2.0, 0.0), hit: true });
            g.insert(&d);
        }
        g
    }

    #[test]
    fn past_the_export_budget_the_map_is_sparse_and_a_crop_is_dense() {
        let g = two_sites(50.0);
        let mut notes = Vec::new();
        let within = ExportOptions { crop: None, export_cells: 1_000, ..Default::default() };
        assert!(matches!(view_of(&g, &within, None, &mut notes).unwrap(), MapView::Dense(_)));
        assert!(notes.is_empty());
        let tight = ExportOptions { crop: None, export_cells: 100, ..Default::default() };
        let MapView::Sparse { tiles, overview, .. } = view_of(&g, &tight, None, &mut notes).unwrap() else {
            panic!("sparse")
        };
        assert_eq!(tiles.keys.len(), g.tile_count());
        assert_eq!(overview.resolution, 0.1);
        assert!(notes[0].contains("limits.export_cells = 100") && notes[0].contains("--crop"), "{}", notes[0]);
        assert_eq!(overview.log_odds, g.known_raster().unwrap().log_odds);
        let crop =
            ExportOptions { crop: Some(parse_crop("49,-1,53,1").unwrap()), export_cells: 1_000, ..Default::default() };
        let MapView::Dense(r) = view_of(&g, &crop, None, &mut notes).unwrap() else { panic!("dense") };
        assert_eq!((r.width, r.height), (41, 21));
        assert!(r.known_count() > 0);
        let big =
            ExportOptions { crop: Some(parse_crop("0,0,100,100").unwrap()), export_cells: 1_000, ..Default::default() };
        let e = view_of(&g, &big, None, &mut notes).err().unwrap().to_string();
        assert!(e.contains("limits.export_cells = 1000") && e.contains("1001 x 1001"), "{e}");
    }

    #[test]
    fn a_dense_raster_the_memory_budget_cannot_hold_is_written_sparsely() {
        let g = two_sites(50.0);
        let n = g.known_box().map(cells).unwrap() as u64;
        let (mut notes, options) =
            (Vec::new(), ExportOptions { crop: None, export_cells: 1_000_000, ..Default::default() });
        let ample = ExportRoom { bytes: 9 * n, per_cell: 9 };
        assert!(matches!(view_of(&g, &options, Some(ample), &mut notes).unwrap(), MapView::Dense(_)));
        let short = ExportRoom { bytes: 9 * n - 1, per_cell: 9 };
        let MapView::Sparse { tiles, .. } = view_of(&g, &options, Some(short), &mut notes).unwrap() else {
            panic!("sparse")
        };
        assert_eq!(tiles.keys.len(), g.tile_count());
        assert!(notes[0].contains("limits.memory_mib leaves beside the maps"), "{}", notes[0]);
        // The overview fits the room left beside the copy of the tiles: coarser when it
        // is short, never more than OVERVIEW_SIDE.
        let copy = (g.tile_count() * TILE_CELLS * 4) as u64;
        for (bytes, side) in [(copy + 9 * 100, 10), (copy + 9 * 99, 9), (copy, 1), (0, 1), (u64::MAX, OVERVIEW_SIDE)] {
            assert_eq!(overview_side(Some(ExportRoom { bytes, per_cell: 9 }), g.tile_count()), side, "{bytes}");
        }
        let cramped = ExportRoom { bytes: copy + 9 * 100, per_cell: 9 };
        let tight = ExportOptions { export_cells: 100, ..options };
        let MapView::Sparse { overview, .. } = view_of(&g, &tight, Some(cramped), &mut notes).unwrap() else {
            panic!("sparse")
        };
        assert!(overview.width <= 10 && overview.height <= 10, "{} x {}", overview.width, overview.height);
        assert!(overview.known_count() > 0);
        assert_eq!(overview_side(None, g.tile_count()), OVERVIEW_SIDE);
        // A crop the room cannot hold is refused naming the key.
        let crop = ExportOptions { crop: Some(parse_crop("0,-1,4,1").unwrap()), ..options };
        let tiny = ExportRoom { bytes: 1000, per_cell: 9 };
        let e = view_of(&g, &crop, Some(tiny), &mut notes).err().unwrap().to_string();
        assert!(e.contains("limits.memory_mib"), "{e}");
    }
}
