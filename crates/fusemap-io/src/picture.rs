//! A PNG picture of a map, for people: the quick look the design document gets from
//! `matplotlib.imshow` (§3.3), without Python.
//!
//! The image is 8-bit grayscale PNG (W3C *Portable Network Graphics (PNG)
//! Specification*, colour type 0, bit depth 8), drawn the way occupancy maps are usually
//! shown:
//!
//! * an observed cell is shaded by where its log-odds `l` lies in the layer's clamp range:
//!   `round(255 · (l_max − l) / (l_max − l_min))`, so a cell as free as the map allows is
//!   white (255), one as occupied as it allows is black (0), and uncertain cells are grey
//!   in proportion. (Shading by `1 − p` instead would draw the clamped free cells at
//!   p = 0.12 light grey, hard to tell from unknown.)
//! * a never-observed cell is [`UNKNOWN_SHADE`] (160), a mid grey. An observed cell whose
//!   shade would also be 160 is drawn 161 instead, one step lighter and invisible to the
//!   eye, so that the value 160 means exactly "never observed" to anyone reading the
//!   pixels;
//! * the top row is the highest y (north up, as in the `map_server` image), x to the
//!   right;
//! * a small map is enlarged by an integer factor with nearest-neighbour sampling (each
//!   cell becomes a square block of pixels, no smoothing that would invent values), so a
//!   200 × 200 cell map is not a postage stamp: the factor is `600 / max(width, height)`
//!   (integer division), at least 1 and at most 16.

use crate::atomic::{check_raster, write_atomic};
use crate::{Error, Location, Result};
use fusemap_core::grid::Raster;
use std::io;
use std::path::Path;

/// Shade of a never-observed cell; no observed cell is drawn with it.
pub const UNKNOWN_SHADE: u8 = 160;

/// The longer side, in pixels, that small maps are enlarged towards.
pub const TARGET_SIDE: usize = 600;

/// The largest enlargement factor (a 1-cell map would otherwise be a 600-pixel square).
pub const MAX_SCALE: usize = 16;

/// The enlargement factor for a `width` × `height` map: `TARGET_SIDE / max(w, h)`,
/// clamped to `1..=MAX_SCALE`.
pub fn scale_factor(width: usize, height: usize) -> usize {
    (TARGET_SIDE / width.max(height).max(1)).clamp(1, MAX_SCALE)
}

/// The shade of one cell with log-odds `l` in a layer clamped to `[l_min, l_max]` (see
/// the module documentation).
pub fn shade(l: f32, known: bool, l_min: f32, l_max: f32) -> u8 {
    if !known {
        return UNKNOWN_SHADE;
    }
    let span = l_max - l_min;
    let t = if l.is_nan() || span.is_nan() || span <= 0.0 { 0.5 } else { ((l_max - l) / span).clamp(0.0, 1.0) };
    // In [0, 255] after the clamp, so the cast cannot wrap.
    let v = (255.0 * t).round() as u8;
    if v == UNKNOWN_SHADE {
        UNKNOWN_SHADE + 1
    } else {
        v
    }
}

/// Writes the picture of `raster` to `path` (atomically) and returns the enlargement
/// factor used, so the caller can tell the user how many pixels a cell is.
///
/// Errors: an empty map (PNG cannot hold a 0-pixel image), an enlarged size beyond
/// PNG's 2³¹−1 pixel limit, and I/O errors, all naming `path`.
pub fn write_map_png(path: &Path, raster: &Raster) -> Result<usize> {
    check_raster(path, raster, true)?;
    let factor = scale_factor(raster.width, raster.height);
    let too_big = || {
        Error::format(
            path,
            Location::File,
            format!("a {} × {} map enlarged {factor}× is too large for PNG", raster.width, raster.height),
        )
    };
    // PNG limits width and height to 2^31 - 1 (specification §11.2.2).
    let side = |n: usize| n.checked_mul(factor).and_then(|v| u32::try_from(v).ok()).filter(|&v| v <= i32::MAX as u32);
    let width_px = side(raster.width).ok_or_else(too_big)?;
    let height_px = side(raster.height).ok_or_else(too_big)?;

    let table = fusemap_core::grid::LogOddsTable::new(&raster.params);
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width_px, height_px);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .add_text_chunk(
                "Description".into(),
                format!(
                    "fusemap occupancy map: {} x {} cells of {} m, lower-left corner at ({}, {}) m, {} pixels per cell; white free, black occupied, grey {} never observed; north (+y) up",
                    raster.width,
                    raster.height,
                    raster.resolution,
                    raster.origin.x,
                    raster.origin.y,
                    factor,
                    UNKNOWN_SHADE
                ),
            )
            .map_err(io::Error::from)?;
        let mut writer = encoder.write_header().map_err(io::Error::from)?;
        let mut stream = writer.stream_writer().map_err(io::Error::from)?;
        let mut line = vec![0u8; width_px as usize];
        // Top row = highest y = last raster row.
        for row in (0..raster.height).rev() {
            let start = row * raster.width;
            let cells =
                raster.log_odds[start..start + raster.width].iter().zip(&raster.known[start..start + raster.width]);
            for (block, (&p, &k)) in line.chunks_exact_mut(factor).zip(cells) {
                block.fill(shade(p, k, table.min, table.max));
            }
            for _ in 0..factor {
                io::Write::write_all(&mut stream, &line)?;
            }
        }
        stream.finish().map_err(io::Error::from)?;
        writer.finish().map_err(io::Error::from)?;
        Ok(())
    })?;
    Ok(factor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::geometry::Point2;
    use fusemap_core::grid::{logodds::logit, CellIndex, OccupancyParams};

    fn temp_dir(tag: &str) -> crate::testdata::TestDir {
        crate::testdata::temp_dir(&format!("picture-{tag}"))
    }

    fn decode(p: &Path) -> (png::OutputInfo, Vec<u8>) {
        let file = std::io::BufReader::new(std::fs::File::open(p).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info, buf)
    }

    #[test]
    fn factors() {
        assert_eq!(scale_factor(200, 200), 3);
        assert_eq!(scale_factor(200, 10), 3);
        assert_eq!(scale_factor(10, 700), 1);
        assert_eq!(scale_factor(1, 1), 16);
        assert_eq!(scale_factor(0, 0), 16);
        assert_eq!(scale_factor(5000, 5000), 1);
    }

    #[test]
    fn shades() {
        assert_eq!(shade(-2.0, true, -2.0, 3.0), 255);
        assert_eq!(shade(3.0, true, -2.0, 3.0), 0);
        assert_eq!(shade(0.5, true, -2.0, 3.0), 128);
        assert_eq!(shade(0.5, false, -2.0, 3.0), UNKNOWN_SHADE);
        // 255 * (3 - l) / 5 = 160 at l = 3 - 160 * 5 / 255.
        assert_eq!(shade(3.0 - 160.0 * 5.0 / 255.0, true, -2.0, 3.0), 161);
        assert_eq!(shade(f32::NAN, true, -2.0, 3.0), 128);
        assert_eq!(shade(7.0, true, -2.0, 3.0), 0);
        assert_eq!(shade(-7.0, true, -2.0, 3.0), 255);
    }

    #[test]
    fn picture_pixels() {
        let d = temp_dir("px");
        let p = d.join("map.png");
        // 3 columns × 2 rows; row 0 (lowest y): occupied, free, unknown; row 1: p = 0.5, free, occupied.
        let occ = logit(0.97) as f32;
        let free = logit(0.12) as f32;
        let r = Raster {
            width: 3,
            height: 2,
            resolution: 0.05,
            origin: Point2::new(0.0, 0.0),
            first_cell: CellIndex { x: 0, y: 0 },
            log_odds: vec![occ, free, 0.0, 0.0, free, occ],
            known: vec![true, true, false, true, true, true],
            params: OccupancyParams::default(),
        };
        let factor = write_map_png(&p, &r).unwrap();
        assert_eq!(factor, 16);
        let (info, px) = decode(&p);
        assert_eq!((info.width, info.height), (48, 32));
        assert_eq!(info.color_type, png::ColorType::Grayscale);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        let at = |x: usize, y: usize| px[y * 48 + x];
        let t = fusemap_core::grid::LogOddsTable::new(&OccupancyParams::default());
        let (o, f, prior) =
            (shade(occ, true, t.min, t.max), shade(free, true, t.min, t.max), shade(0.0, true, t.min, t.max));
        assert_eq!((o, f, prior), (0, 255, 162));
        // Top block row = raster row 1 (highest y).
        for (col, want) in [(0, prior), (1, f), (2, o)] {
            for dy in 0..16 {
                for dx in 0..16 {
                    assert_eq!(at(col * 16 + dx, dy), want, "top row, column {col}");
                    let bottom = [o, f, UNKNOWN_SHADE][col];
                    assert_eq!(at(col * 16 + dx, 16 + dy), bottom, "bottom row, column {col}");
                }
            }
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn empty_map_is_refused() {
        let d = temp_dir("empty");
        let r = Raster {
            width: 0,
            height: 0,
            resolution: 0.05,
            origin: Point2::new(0.0, 0.0),
            first_cell: CellIndex { x: 0, y: 0 },
            log_odds: vec![],
            known: vec![],
            params: OccupancyParams::default(),
        };
        let e = write_map_png(&d.join("m.png"), &r).unwrap_err();
        assert!(e.to_string().contains("m.png"), "{e}");
        assert!(!d.join("m.png").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
