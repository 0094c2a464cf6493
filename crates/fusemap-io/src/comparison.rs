//! One picture of several maps side by side, each with a caption: the design document's
//! "switch a sensor off and compare" (§4.3 habit 3, §5.2) as something to look at.
//!
//! Panels are drawn left to right at one common scale (nearest-neighbour enlargement, as
//! in [`picture`](crate::picture)), top row = highest y, with their caption lines above
//! them in an 8 × 8 bitmap font (`font8x8`, the public-domain IBM PC BIOS glyphs) drawn at
//! twice its size. The image is 8-bit RGB PNG, written atomically.

use crate::atomic::write_atomic;
use crate::picture::{scale_factor, shade};
use crate::{Error, Location, Result};
use fusemap_core::grid::{LogOddsTable, Raster};
use std::io;
use std::path::Path;

/// Pixels per font pixel.
const TEXT_SCALE: usize = 2;
/// Height of one caption line, pixels.
const LINE_PX: usize = 8 * TEXT_SCALE + 4;
/// Margin around and between panels, pixels.
const MARGIN: usize = 12;
/// Largest picture side accepted, pixels.
const MAX_SIDE: usize = 20_000;

/// One panel: an RGB image of cells (row 0 = lowest y) and its caption.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Caption lines, the first one the title.
    pub caption: Vec<String>,
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// One colour per cell, row-major, row 0 = lowest y.
    pub rgb: Vec<[u8; 3]>,
}

impl Panel {
    /// A panel of an occupancy raster, shaded as [`picture`](crate::picture) shades it.
    pub fn occupancy(caption: Vec<String>, raster: &Raster) -> Self {
        let t = LogOddsTable::new(&raster.params);
        let rgb = raster
            .log_odds
            .iter()
            .zip(&raster.known)
            .map(|(&l, &k)| {
                let s = shade(l, k, t.min, t.max);
                [s, s, s]
            })
            .collect();
        Self { caption, width: raster.width, height: raster.height, rgb }
    }
}

/// Draws `text` at pixel (`x`, `y`) (top-left) of an RGB image `width` pixels wide.
fn draw_text(img: &mut [u8], width: usize, x: usize, y: usize, text: &str) {
    let height = img.len() / 3 / width;
    for (i, ch) in text.chars().enumerate() {
        let code = if ch.is_ascii() { ch as usize } else { '?' as usize };
        let glyph = font8x8::legacy::BASIC_LEGACY[code];
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) == 0 {
                    continue;
                }
                for dy in 0..TEXT_SCALE {
                    for dx in 0..TEXT_SCALE {
                        let px = x + (i * 8 + col) * TEXT_SCALE + dx;
                        let py = y + row * TEXT_SCALE + dy;
                        if px < width && py < height {
                            img[(py * width + px) * 3..(py * width + px) * 3 + 3].copy_from_slice(&[0, 0, 0]);
                        }
                    }
                }
            }
        }
    }
}

/// Writes `panels` side by side to `path`. Returns the enlargement factor used.
pub fn write_comparison_png(path: &Path, panels: &[Panel]) -> Result<usize> {
    let bad = |m: String| Error::format(path, Location::File, m);
    if panels.is_empty() || panels.iter().any(|p| p.width == 0 || p.height == 0) {
        return Err(bad("nothing to draw: a comparison needs non-empty panels".into()));
    }
    for p in panels {
        if p.rgb.len() != p.width * p.height {
            return Err(bad(format!("a {} × {} panel holds {} cells", p.width, p.height, p.rgb.len())));
        }
    }
    let widest = panels.iter().map(|p| p.width).max().unwrap_or(1);
    let tallest = panels.iter().map(|p| p.height).max().unwrap_or(1);
    let factor = scale_factor(widest, tallest);
    let lines = panels.iter().map(|p| p.caption.len()).max().unwrap_or(0);
    let text_w = |p: &Panel| p.caption.iter().map(|l| l.chars().count()).max().unwrap_or(0) * 8 * TEXT_SCALE;
    let col_w: Vec<usize> = panels.iter().map(|p| (p.width * factor).max(text_w(p))).collect();
    let width = MARGIN + col_w.iter().map(|w| w + MARGIN).sum::<usize>();
    let top = MARGIN + lines * LINE_PX;
    let height = top + tallest * factor + MARGIN;
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(bad(format!("a {width} × {height} pixel comparison is larger than {MAX_SIDE} pixels a side")));
    }
    let mut img = vec![255u8; width * height * 3];
    let mut x0 = MARGIN;
    for (p, w) in panels.iter().zip(&col_w) {
        for (i, line) in p.caption.iter().enumerate() {
            draw_text(&mut img, width, x0, MARGIN + i * LINE_PX, line);
        }
        for row in 0..p.height {
            // Top row = highest y.
            let py0 = top + (p.height - 1 - row) * factor;
            for col in 0..p.width {
                let c = p.rgb[row * p.width + col];
                for dy in 0..factor {
                    let start = ((py0 + dy) * width + x0 + col * factor) * 3;
                    for px in img[start..start + factor * 3].chunks_exact_mut(3) {
                        px.copy_from_slice(&c);
                    }
                }
            }
        }
        x0 += w + MARGIN;
    }
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(io::Error::from)?;
        writer.write_image_data(&img).map_err(io::Error::from)?;
        writer.finish().map_err(io::Error::from)?;
        Ok(())
    })?;
    Ok(factor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_are_drawn_side_by_side_with_captions() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cmp.png");
        let red = Panel { caption: vec!["A".into()], width: 2, height: 1, rgb: vec![[255, 0, 0], [0, 0, 255]] };
        let green =
            Panel { caption: vec!["B".into(), "F1 0.5".into()], width: 1, height: 2, rgb: vec![[0, 255, 0]; 2] };
        let factor = write_comparison_png(&path, &[red, green]).unwrap();
        assert_eq!(factor, 16);
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        let (w, h) = (info.width as usize, info.height as usize);
        let at = |x: usize, y: usize| [buf[(y * w + x) * 3], buf[(y * w + x) * 3 + 1], buf[(y * w + x) * 3 + 2]];
        let top = MARGIN + 2 * LINE_PX;
        assert_eq!(h, top + 2 * 16 + MARGIN);
        // Panels are top-aligned: the one-row panel's red then blue cell on the first band.
        assert_eq!(at(MARGIN + 1, top + 1), [255, 0, 0]);
        assert_eq!(at(MARGIN + 17, top + 1), [0, 0, 255]);
        // Some caption pixel is black.
        assert!((MARGIN..MARGIN + 16).any(|y| (MARGIN..MARGIN + 16).any(|x| at(x, y) == [0, 0, 0])));
        assert!(write_comparison_png(&path, &[]).is_err());
    }
}
