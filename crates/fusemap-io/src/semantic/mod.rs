//! The outputs of a semantic run: the semantic layer as an indexed-colour PNG with a YAML
//! description (the design document's "semantic layer: PNG + YAML", §4.4), and the
//! dynamic layer as a greyscale PNG. The same layers go into `map.npz` through
//! [`crate::npz::write_map_npz_with`].
//!
//! Conventions are those of the other map exports ([`crate::map_server`]): one pixel per
//! cell, the **top image row is the highest y** (rasters are row 0 = lowest y and are
//! flipped when written), the YAML's `origin` is `[x, y, 0.0]` of the lower-left corner
//! of the lower-left cell, and every file is written atomically ([`write_atomic`]: a
//! temporary file renamed over the target), the image before the YAML that names it.
//!
//! `semantic.png` is a PNG of colour type 3 (W3C PNG specification §11.2.3, palette):
//! pixel value `i < K` is class index `i` and its `PLTE` entry is the class colour; value
//! `K` is the cell with no semantic evidence, drawn [`UNKNOWN_COLOR`]. A tool reading the
//! indices gets the classes without any colour matching; a person sees the colours.

use crate::atomic::write_atomic;
use crate::map_server::{yaml_float, yaml_string, PIXEL_UNKNOWN};
use crate::{Error, Location, Result};
use fusemap_core::grid::CellRaster;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The colour of a cell with no semantic evidence: a neutral mid grey.
pub const UNKNOWN_COLOR: [u8; 3] = [128, 128, 128];

/// The most classes `semantic.png` can hold: a palette has at most 256 entries, one of
/// which is the unknown cell's.
pub const MAX_CLASSES: usize = 255;

/// One class of the semantic layer, as the class table in the configuration gives it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClassInfo {
    /// The id label images use for it.
    pub id: u16,
    /// Its name (`wall`, `glass`, …).
    pub name: String,
    /// Its RGB colour in pictures.
    pub color: [u8; 3],
}

/// A dense rectangle of the semantic layer (row-major, row 0 = lowest y, like
/// [`fusemap_core::grid::Raster`]): the most likely class of each cell and the class
/// probabilities. K = `classes.len()`.
#[derive(Clone, Debug, PartialEq)]
pub struct SemanticRaster {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell side, metres.
    pub resolution: f64,
    /// World x, y of the lower-left corner of cell (row 0, column 0).
    pub origin: [f64; 2],
    /// The classes; a cell's class is an index into this list.
    pub classes: Vec<ClassInfo>,
    /// Per cell: the most likely class (index into `classes`), -1 where the cell has no
    /// semantic evidence.
    pub best: Vec<i16>,
    /// Per cell: the probability of `best` (any value where `best` is -1).
    pub prob: Vec<f32>,
    /// Per cell and class (`[(row * width + column) * K + class]`): the probability of
    /// each class; empty when not kept.
    pub probs: Vec<f32>,
}

impl SemanticRaster {
    /// Checks that the buffers match the size, the classes fit a palette and every
    /// `best` is -1 or a class index. The error says what is wrong.
    pub fn check(&self) -> std::result::Result<(), String> {
        let cells = self
            .width
            .checked_mul(self.height)
            .ok_or_else(|| format!("the size {} × {} overflows", self.width, self.height))?;
        if self.best.len() != cells || self.prob.len() != cells {
            return Err(format!(
                "{} × {} = {cells} cells but {} classes and {} probabilities",
                self.width,
                self.height,
                self.best.len(),
                self.prob.len()
            ));
        }
        let k = self.classes.len();
        if k > MAX_CLASSES {
            return Err(format!("{k} classes, more than the {MAX_CLASSES} a PNG palette can hold"));
        }
        if !self.probs.is_empty() && Some(self.probs.len()) != cells.checked_mul(k) {
            return Err(format!(
                "{} per-class probabilities for {cells} cells of {k} classes (expected {cells} × {k} or none)",
                self.probs.len()
            ));
        }
        if let Some(i) = self.best.iter().position(|&b| b < -1 || b >= 0 && b as usize >= k) {
            return Err(format!(
                "cell (row {}, column {}) has class {}, not -1 or an index below {k}",
                i / self.width.max(1),
                i % self.width.max(1),
                self.best[i]
            ));
        }
        if !(self.resolution.is_finite() && self.resolution > 0.0 && self.origin.iter().all(|v| v.is_finite())) {
            return Err(format!(
                "resolution ({}) or origin ({}, {}) is not a finite placement",
                self.resolution, self.origin[0], self.origin[1]
            ));
        }
        Ok(())
    }
}

/// Writes the semantic layer as `semantic.yaml`-style description at `yaml_path` and the
/// indexed-colour image beside it, same stem, extension `.png` (`out/semantic.yaml` →
/// `out/semantic.png`); returns the image's path. See the module documentation for the
/// image; the YAML reads:
///
/// ```yaml
/// image: semantic.png
/// resolution: 0.05
/// origin: [-5.0, -2.5, 0.0]
/// unknown_index: 2
/// unknown_color: [128, 128, 128]
/// classes:
///   - index: 0
///     id: 1
///     name: floor
///     color: [170, 170, 170]
///   - index: 1
///     id: 2
///     name: wall
///     color: [90, 90, 200]
/// ```
pub fn write_semantic(yaml_path: &Path, raster: &SemanticRaster) -> Result<PathBuf> {
    raster.check().map_err(|e| Error::format(yaml_path, Location::File, format!("semantic layer: {e}")))?;
    if raster.width == 0 || raster.height == 0 {
        return Err(Error::format(yaml_path, Location::File, "the semantic layer is empty: PNG cannot hold 0 pixels"));
    }
    let image_path = sibling(yaml_path, "png")?;
    let image_name = image_name(yaml_path, &image_path)?;
    let k = raster.classes.len();
    let (width, height) = png_size(yaml_path, raster.width, raster.height)?;

    write_atomic(&image_path, |w| {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Indexed);
        encoder.set_depth(png::BitDepth::Eight);
        let mut palette: Vec<u8> = raster.classes.iter().flat_map(|c| c.color).collect();
        palette.extend(UNKNOWN_COLOR);
        encoder.set_palette(palette);
        encoder
            .add_text_chunk(
                "Description".into(),
                format!(
                    "fusemap semantic layer: {} x {} cells of {} m, lower-left corner at ({}, {}) m; pixel value = class index, {k} = no semantic evidence; north (+y) up",
                    raster.width, raster.height, raster.resolution, raster.origin[0], raster.origin[1]
                ),
            )
            .map_err(io::Error::from)?;
        let mut writer = encoder.write_header().map_err(io::Error::from)?;
        let mut stream = writer.stream_writer().map_err(io::Error::from)?;
        let unknown = k as u8; // k ≤ MAX_CLASSES = 255 (checked)
        let mut line = vec![0u8; raster.width];
        // Top row = highest y = last raster row.
        for cells in raster.best.chunks_exact(raster.width).rev() {
            for (px, &b) in line.iter_mut().zip(cells) {
                *px = u8::try_from(b).unwrap_or(unknown);
            }
            stream.write_all(&line)?;
        }
        stream.finish().map_err(io::Error::from)?;
        writer.finish().map_err(io::Error::from)?;
        Ok(())
    })?;

    let yaml = semantic_yaml(raster, &image_name);
    write_atomic(yaml_path, |w| w.write_all(yaml.as_bytes()))?;
    Ok(image_path)
}

/// The YAML that describes `raster`'s classes and placement, naming `image` as its picture
/// (`semantic.yaml`'s text; `map.mcap` keeps it in a metadata record).
pub fn semantic_yaml(raster: &SemanticRaster, image: &str) -> String {
    let k = raster.classes.len();
    let mut yaml = format!(
        "image: {}\nresolution: {}\norigin: [{}, {}, 0.0]\nunknown_index: {k}\nunknown_color: {}\nclasses:",
        yaml_string(image),
        yaml_float(raster.resolution),
        yaml_float(raster.origin[0]),
        yaml_float(raster.origin[1]),
        color(UNKNOWN_COLOR),
    );
    if raster.classes.is_empty() {
        yaml.push_str(" []");
    }
    yaml.push('\n');
    for (i, c) in raster.classes.iter().enumerate() {
        yaml.push_str(&format!(
            "  - index: {i}\n    id: {}\n    name: {}\n    color: {}\n",
            c.id,
            yaml_string(&c.name),
            color(c.color)
        ));
    }
    yaml
}

/// Writes the dynamic layer's probabilities as an 8-bit greyscale PNG, one pixel per
/// cell, top row = highest y: an observed cell is `round(255 · (1 − p))` (black: surely
/// a moving object, white: surely none), a never-observed or NaN cell is
/// [`PIXEL_UNKNOWN`] (205, the map_server grey); an observed cell whose shade would be 205
/// is drawn 206, so that 205 means exactly "never observed".
pub fn write_dynamic_png(path: &Path, layer: &CellRaster<f32>) -> Result<()> {
    let cells = layer.width.checked_mul(layer.height);
    if cells != Some(layer.cells.len()) || layer.known.len() != layer.cells.len() {
        return Err(Error::format(
            path,
            Location::File,
            format!(
                "the dynamic layer is {} × {} cells but holds {} values and {} known flags",
                layer.width,
                layer.height,
                layer.cells.len(),
                layer.known.len()
            ),
        ));
    }
    if cells == Some(0) {
        return Err(Error::format(path, Location::File, "the dynamic layer is empty: PNG cannot hold 0 pixels"));
    }
    let (width, height) = png_size(path, layer.width, layer.height)?;
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .add_text_chunk(
                "Description".into(),
                format!(
                    "fusemap dynamic layer: {} x {} cells of {} m, lower-left corner at ({}, {}) m; black = moving object, white = none, {PIXEL_UNKNOWN} never observed; north (+y) up",
                    layer.width, layer.height, layer.resolution, layer.origin.x, layer.origin.y
                ),
            )
            .map_err(io::Error::from)?;
        let mut writer = encoder.write_header().map_err(io::Error::from)?;
        let mut stream = writer.stream_writer().map_err(io::Error::from)?;
        let mut line = vec![0u8; layer.width];
        for (values, known) in layer.cells.chunks_exact(layer.width).zip(layer.known.chunks_exact(layer.width)).rev() {
            for ((px, &p), &k) in line.iter_mut().zip(values).zip(known) {
                *px = dynamic_shade(p, k);
            }
            stream.write_all(&line)?;
        }
        stream.finish().map_err(io::Error::from)?;
        writer.finish().map_err(io::Error::from)?;
        Ok(())
    })
}

/// The shade of one dynamic-layer cell (see [`write_dynamic_png`]).
pub fn dynamic_shade(p: f32, known: bool) -> u8 {
    if !known || p.is_nan() {
        return PIXEL_UNKNOWN;
    }
    // In [0, 255] after the clamp, so the cast cannot wrap.
    let v = (255.0 * (1.0 - p.clamp(0.0, 1.0))).round() as u8;
    if v == PIXEL_UNKNOWN {
        PIXEL_UNKNOWN + 1
    } else {
        v
    }
}

/// `[r, g, b]` as a YAML flow list.
fn color(c: [u8; 3]) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

/// `path` with extension `ext`, refused when that is `path` itself.
fn sibling(path: &Path, ext: &str) -> Result<PathBuf> {
    let image = path.with_extension(ext);
    if image == path {
        return Err(Error::format(
            path,
            Location::File,
            format!(
                "the description must not itself end in .{ext}: the image is written beside it with that extension"
            ),
        ));
    }
    Ok(image)
}

fn image_name(yaml_path: &Path, image_path: &Path) -> Result<String> {
    image_path.file_name().and_then(|n| n.to_str()).map(str::to_string).ok_or_else(|| {
        Error::format(yaml_path, Location::File, "the image's file name is not valid UTF-8, which YAML cannot hold")
    })
}

/// The PNG size of a `width` × `height` raster; PNG limits each side to 2³¹ − 1 (§11.2.2).
fn png_size(path: &Path, width: usize, height: usize) -> Result<(u32, u32)> {
    let side = |n: usize| u32::try_from(n).ok().filter(|&v| v <= i32::MAX as u32);
    match (side(width), side(height)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(Error::format(path, Location::File, format!("a {width} × {height} raster is too large for PNG"))),
    }
}

#[cfg(test)]
mod tests;
