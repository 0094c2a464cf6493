//! The ROS `map_server` map pair: a PGM image and a YAML file describing it (the design
//! document's §4.4 hand-over to navigation stacks, as `nav_msgs/OccupancyGrid` maps are
//! stored on disk).
//!
//! Specification: the ROS wiki page *map_server*, section "Map format", and the sources
//! of ROS 1 `map_server` (`map_saver.cpp`, `image_loader.cpp`) and ROS 2 Nav2
//! `nav2_map_server` (`map_io.cpp`), which agree on everything written here:
//!
//! * The image is binary 8-bit PGM (Netpbm `P5`, maxval 255). Its **top row is the
//!   highest y**: image rows go down the page while map y goes up, so the raster (row 0 =
//!   lowest y) is flipped when written and flipped back when read.
//! * Cells are written as `map_saver` writes them in trinary mode: occupied = 0 (black),
//!   free = 254 (white), unknown = 205 (grey), by [`Raster::ternary`].
//! * The YAML gives `image` (relative to the YAML's directory), `resolution` (m/pixel),
//!   `origin` `[x, y, yaw]` — the pose of the **lower-left corner of the lower-left
//!   pixel** —, `negate`, `occupied_thresh`, `free_thresh` and, for Nav2, `mode`.
//! * Loading turns pixel value `v` into `p = (255 - v) / 255` (`p = v / 255` with
//!   `negate: 1`); trinary mode then says occupied when `p > occupied_thresh`, free when
//!   `p < free_thresh`, unknown otherwise.
//!
//! **Why `free_thresh: 0.196` and not the often-seen 0.25.** Unknown is written as 205,
//! which loads as `p = 50/255 = 0.19608`. With `free_thresh: 0.196` that is not below the
//! threshold, so 205 stays unknown; with 0.25 it would load as **free**, and a planner
//! would happily drive into space nobody ever saw. 0.196 is exactly what ROS 1
//! `map_saver` writes, for this reason. `occupied_thresh: 0.65` (map_saver's too) decodes
//! 0 (`p = 1`) as occupied, and 254 (`p = 0.0039`) is free under either. These decode
//! thresholds belong to the PGM encoding, not to the map's own classification
//! thresholds, which were already applied when the cells were turned into 0/205/254.

use crate::atomic::{check_raster, write_atomic};
use crate::{Error, Location, Result};
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{Raster, Ternary};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Pixel value of an occupied cell (black), as `map_saver` writes it.
pub const PIXEL_OCCUPIED: u8 = 0;
/// Pixel value of a free cell (white), as `map_saver` writes it.
pub const PIXEL_FREE: u8 = 254;
/// Pixel value of an unknown cell (grey), as `map_saver` writes it.
pub const PIXEL_UNKNOWN: u8 = 205;
/// The `occupied_thresh` written to the YAML (see the module documentation).
pub const OCCUPIED_THRESH: f64 = 0.65;
/// The `free_thresh` written to the YAML: below 50/255 so that 205 loads as unknown (see
/// the module documentation).
pub const FREE_THRESH: f64 = 0.196;

/// Writes a map as a `map_server` pair: the YAML at `yaml_path` and the image beside it,
/// same stem, extension `.pgm` (`out/map.yaml` → `out/map.pgm`). Returns the image's
/// path.
///
/// The image is written first, then the YAML, each atomically, so a YAML never names a
/// missing or half-written image. The YAML refers to the image by its bare file name,
/// which `map_server` resolves against the YAML's directory, so the pair can be moved
/// together.
pub fn write_map_server(yaml_path: &Path, raster: &Raster) -> Result<PathBuf> {
    check_raster(yaml_path, raster, true)?;
    let image_path = yaml_path.with_extension("pgm");
    if image_path == yaml_path {
        return Err(Error::format(
            yaml_path,
            Location::File,
            "the map description must not itself end in .pgm: the image is written beside it with that extension",
        ));
    }
    let image_name = image_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| {
            Error::format(yaml_path, Location::File, "the image's file name is not valid UTF-8, which YAML cannot hold")
        })?
        .to_string();

    write_atomic(&image_path, |w| {
        write!(w, "P5\n# CREATOR: fusemap {} m/pix\n{} {}\n255\n", raster.resolution, raster.width, raster.height)?;
        let ternary = raster.ternary();
        let mut row = vec![0u8; raster.width];
        // Top image row = highest y = last raster row.
        for cells in ternary.chunks_exact(raster.width).rev() {
            for (px, t) in row.iter_mut().zip(cells) {
                *px = match t {
                    Ternary::Occupied => PIXEL_OCCUPIED,
                    Ternary::Free => PIXEL_FREE,
                    Ternary::Unknown => PIXEL_UNKNOWN,
                };
            }
            w.write_all(&row)?;
        }
        Ok(())
    })?;

    let yaml = format!(
        "image: {}\nmode: trinary\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: {}\nfree_thresh: {}\n",
        yaml_string(&image_name),
        yaml_float(raster.resolution),
        yaml_float(raster.origin.x),
        yaml_float(raster.origin.y),
        OCCUPIED_THRESH,
        FREE_THRESH,
    );
    write_atomic(yaml_path, |w| w.write_all(yaml.as_bytes()))?;
    Ok(image_path)
}

/// A finite float in plain decimal that reads back to the same `f64`, always with a
/// decimal point so YAML 1.1 readers (PyYAML) see a float and not an integer or a string
/// (`1e-7`, which YAML 1.1 does not take as a float).
pub(crate) fn yaml_float(v: f64) -> String {
    // Display never uses exponent notation and is the shortest round-trip form.
    let s = format!("{v}");
    if s.contains('.') {
        s
    } else {
        format!("{s}.0")
    }
}

/// A YAML scalar for `s`: plain when it is unambiguous (what `map_saver` writes),
/// double-quoted with escapes otherwise (spaces, `#`, `:`, quotes, leading dashes…).
pub(crate) fn yaml_string(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-' | '/'))
        && !s.starts_with('-')
        && !s.starts_with('.');
    if plain {
        s.to_string()
    } else {
        let mut out = String::from("\"");
        for c in s.chars() {
            match c {
                '"' => out.push_str("\\\""),
                '\\' => out.push_str("\\\\"),
                c if (c as u32) < 0x20 => out.push_str(&format!("\\x{:02x}", c as u32)),
                c => out.push(c),
            }
        }
        out.push('"');
        out
    }
}

/// How `map_server` interprets pixel values (`mode` in the YAML).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapMode {
    /// Occupied / free / unknown by the two thresholds (the default).
    Trinary,
    /// As trinary at the extremes; in between, `map_server` scales the probability to
    /// 0–100. There is no ternary value for that, so [`read_map_server`] returns
    /// [`Ternary::Unknown`] for such cells (not enough evidence either way).
    Scale,
}

/// A map read from a `map_server` pair.
#[derive(Clone, Debug, PartialEq)]
pub struct MapServerMap {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell side, metres.
    pub resolution: f64,
    /// World coordinates of the lower-left corner of cell (row 0, column 0).
    pub origin: Point2,
    /// The origin's yaw, radians. `map_server` documents that much of the ROS stack
    /// ignores it; it is returned so a caller can refuse a rotated map.
    pub origin_yaw: f64,
    /// How the pixels were interpreted.
    pub mode: MapMode,
    /// Cells in raster order: row-major, row 0 = lowest y (the image's bottom row).
    pub cells: Vec<Ternary>,
}

/// The YAML keys, parsed.
#[derive(Default)]
struct Description {
    image: Option<(String, u64)>,
    resolution: Option<(f64, u64)>,
    origin: Option<([f64; 3], u64)>,
    negate: Option<bool>,
    occupied_thresh: Option<(f64, u64)>,
    free_thresh: Option<(f64, u64)>,
    mode: Option<MapMode>,
}

/// Reads a `map_server` pair from its YAML, decoding cells exactly as `map_server` does
/// in trinary mode (see the module documentation).
///
/// The YAML reader understands the subset map files use: one `key: value` per line,
/// comments (`#`), plain or quoted scalars and the `origin` flow list. Required keys, as
/// in `map_server`: `image`, `resolution`, `origin`, `negate`, `occupied_thresh`,
/// `free_thresh`; `mode` defaults to `trinary`, and `raw` mode is refused. Unknown keys
/// are ignored, as `map_server` ignores them. The image must be binary PGM (`P5`) with
/// maxval 255. Every error names the YAML or image file and the line or field.
pub fn read_map_server(yaml_path: &Path) -> Result<MapServerMap> {
    let text = std::fs::read_to_string(yaml_path).map_err(|e| Error::io(yaml_path, e))?;
    let d = parse_description(yaml_path, &text)?;
    let missing = |key: &str| Error::format(yaml_path, Location::Field(key.into()), "missing (required)");
    let (image, image_line) = d.image.ok_or_else(|| missing("image"))?;
    let (resolution, res_line) = d.resolution.ok_or_else(|| missing("resolution"))?;
    let (origin, origin_line) = d.origin.ok_or_else(|| missing("origin"))?;
    let negate = d.negate.ok_or_else(|| missing("negate"))?;
    let (occ_t, occ_line) = d.occupied_thresh.ok_or_else(|| missing("occupied_thresh"))?;
    let (free_t, free_line) = d.free_thresh.ok_or_else(|| missing("free_thresh"))?;
    let mode = d.mode.unwrap_or(MapMode::Trinary);
    let at = |line: u64, key: &str, msg: String| Error::format(yaml_path, Location::LineField(line, key.into()), msg);
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(at(res_line, "resolution", format!("must be a positive number of metres, got {resolution}")));
    }
    if origin.iter().any(|v| !v.is_finite()) {
        return Err(at(origin_line, "origin", "must be three finite numbers".into()));
    }
    for (v, line, key) in [(occ_t, occ_line, "occupied_thresh"), (free_t, free_line, "free_thresh")] {
        if !(0.0..=1.0).contains(&v) {
            return Err(at(line, key, format!("must be within [0, 1], got {v}")));
        }
    }
    if image.is_empty() {
        return Err(at(image_line, "image", "is empty".into()));
    }
    let image_path = if Path::new(&image).is_absolute() {
        PathBuf::from(&image)
    } else {
        yaml_path.parent().unwrap_or_else(|| Path::new("")).join(&image)
    };
    let bytes = std::fs::read(&image_path).map_err(|e| Error::io(&image_path, e))?;
    let (width, height, pixels) = parse_pgm(&image_path, &bytes)?;

    let mut cells = Vec::with_capacity(width * height);
    // Bottom image row first: raster row 0 is the lowest y.
    for row in pixels.chunks_exact(width.max(1)).rev() {
        for &v in row {
            let p = if negate { v as f64 / 255.0 } else { (255.0 - v as f64) / 255.0 };
            cells.push(if p > occ_t {
                Ternary::Occupied
            } else if p < free_t {
                Ternary::Free
            } else {
                Ternary::Unknown
            });
        }
    }
    Ok(MapServerMap {
        width,
        height,
        resolution,
        origin: Point2::new(origin[0], origin[1]),
        origin_yaw: origin[2],
        mode,
        cells,
    })
}

/// Parses the YAML subset of map files into the known keys.
fn parse_description(path: &Path, text: &str) -> Result<Description> {
    let mut d = Description::default();
    let mut seen: Vec<String> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i as u64 + 1;
        let content = strip_comment(raw);
        let content = content.trim_end();
        if content.trim().is_empty() || content == "---" || content == "..." {
            continue;
        }
        let err = |msg: String| Error::format(path, Location::Line(line), msg);
        if content.starts_with([' ', '\t']) {
            return Err(err("nested YAML is not part of the map format: expected `key: value`".into()));
        }
        let (key, value) =
            content.split_once(':').ok_or_else(|| err(format!("expected `key: value`, got `{}`", content.trim())))?;
        let key = key.trim();
        let value = value.trim();
        if seen.iter().any(|k| k == key) {
            return Err(err(format!("`{key}` is given twice")));
        }
        seen.push(key.to_string());
        let field = |msg: String| Error::format(path, Location::LineField(line, key.into()), msg);
        let number = |v: &str| -> Result<f64> {
            parse_yaml_float(v).ok_or_else(|| field(format!("expected a number, got `{v}`")))
        };
        match key {
            "image" => d.image = Some((unquote(value).map_err(field)?, line)),
            "resolution" => d.resolution = Some((number(value)?, line)),
            "occupied_thresh" => d.occupied_thresh = Some((number(value)?, line)),
            "free_thresh" => d.free_thresh = Some((number(value)?, line)),
            "negate" => {
                d.negate = Some(match value {
                    "0" | "false" | "False" | "FALSE" => false,
                    "1" | "true" | "True" | "TRUE" => true,
                    v => return Err(field(format!("expected 0 or 1, got `{v}`"))),
                })
            }
            "mode" => {
                d.mode = Some(match unquote(value).map_err(field)?.as_str() {
                    "trinary" => MapMode::Trinary,
                    "scale" => MapMode::Scale,
                    "raw" => {
                        return Err(field(
                            "`raw` mode stores occupancy values, not a picture of the map: not supported".into(),
                        ))
                    }
                    v => return Err(field(format!("expected `trinary`, `scale` or `raw`, got `{v}`"))),
                })
            }
            "origin" => {
                let inner = value
                    .strip_prefix('[')
                    .and_then(|v| v.strip_suffix(']'))
                    .ok_or_else(|| field(format!("expected `[x, y, yaw]`, got `{value}`")))?;
                let parts: Vec<&str> = inner.split(',').map(str::trim).collect();
                if parts.len() != 3 {
                    return Err(field(format!("expected three numbers `[x, y, yaw]`, got {}", parts.len())));
                }
                let mut o = [0.0; 3];
                for (slot, p) in o.iter_mut().zip(&parts) {
                    *slot = number(p)?;
                }
                d.origin = Some((o, line));
            }
            _ => {} // map_server ignores keys it does not know.
        }
    }
    Ok(d)
}

/// The line without a trailing comment: `#` at the start or after whitespace, outside
/// quotes (YAML's rule; `a#b` is not a comment).
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    let mut prev_space = true;
    for (i, c) in line.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == '\'' || c == '"' => quote = Some(c),
            None if c == '#' && prev_space => return &line[..i],
            None => {}
        }
        prev_space = c == ' ' || c == '\t';
    }
    line
}

/// A scalar string: plain, `'single'` (with `''` for a quote) or `"double"` (with
/// backslash escapes for `\"`, `\\`, `\n`, `\t`, `\xNN`).
fn unquote(v: &str) -> std::result::Result<String, String> {
    if let Some(inner) = v.strip_prefix('\'') {
        let inner = inner.strip_suffix('\'').ok_or_else(|| format!("unterminated quoted string `{v}`"))?;
        return Ok(inner.replace("''", "'"));
    }
    if let Some(inner) = v.strip_prefix('"') {
        let inner = inner.strip_suffix('"').ok_or_else(|| format!("unterminated quoted string `{v}`"))?;
        let mut out = String::new();
        let mut chars = inner.chars();
        while let Some(c) = chars.next() {
            if c != '\\' {
                out.push(c);
                continue;
            }
            match chars.next() {
                Some('"') => out.push('"'),
                Some('\\') => out.push('\\'),
                Some('/') => out.push('/'),
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some('x') => {
                    let hex: String = chars.by_ref().take(2).collect();
                    let code = u32::from_str_radix(&hex, 16)
                        .ok()
                        .and_then(char::from_u32)
                        .ok_or_else(|| format!("bad escape `\\x{hex}`"))?;
                    out.push(code);
                }
                other => return Err(format!("unsupported escape `\\{}`", other.map(String::from).unwrap_or_default())),
            }
        }
        return Ok(out);
    }
    Ok(v.to_string())
}

/// A YAML number (integers too; `.inf`/`.nan` spellings are read so they can be
/// refused with a clear message rather than "not a number").
fn parse_yaml_float(v: &str) -> Option<f64> {
    let v = v.trim();
    match v.to_ascii_lowercase().as_str() {
        ".inf" | "+.inf" => return Some(f64::INFINITY),
        "-.inf" => return Some(f64::NEG_INFINITY),
        ".nan" => return Some(f64::NAN),
        _ => {}
    }
    // Rust's parser also takes `inf`/`nan`/`infinity`, which YAML does not.
    if v.chars().all(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')) {
        v.parse().ok()
    } else {
        None
    }
}

/// Parses a binary PGM (Netpbm `P5`, maxval 255): width, height and the pixel rows, top
/// row first. Header tokens are separated by whitespace, `#` comments run to the end of
/// their line, and exactly one whitespace byte follows the maxval (Netpbm's `pgm(5)`).
fn parse_pgm(path: &Path, bytes: &[u8]) -> Result<(usize, usize, Vec<u8>)> {
    let mut pos = 0usize;
    let mut tokens = Vec::with_capacity(4);
    while tokens.len() < 4 {
        // Skip whitespace and comments.
        loop {
            match bytes.get(pos) {
                Some(b) if b.is_ascii_whitespace() => pos += 1,
                Some(b'#') => {
                    while bytes.get(pos).is_some_and(|&b| b != b'\n') {
                        pos += 1;
                    }
                }
                _ => break,
            }
        }
        let start = pos;
        while bytes.get(pos).is_some_and(|b| !b.is_ascii_whitespace() && *b != b'#') {
            pos += 1;
        }
        if start == pos {
            return Err(Error::format(path, Location::Offset(pos as u64), "truncated PGM header"));
        }
        tokens.push((String::from_utf8_lossy(&bytes[start..pos]).into_owned(), start));
    }
    let (magic, _) = &tokens[0];
    if magic != "P5" {
        return Err(Error::format(
            path,
            Location::Offset(0),
            format!(
                "not a binary PGM: magic `{magic}`, expected `P5` (only 8-bit binary PGM map images are supported)"
            ),
        ));
    }
    let number = |i: usize, what: &str| -> Result<usize> {
        let (t, at) = &tokens[i];
        t.parse::<usize>().map_err(|_| Error::format(path, Location::Offset(*at as u64), format!("bad {what} `{t}`")))
    };
    let width = number(1, "width")?;
    let height = number(2, "height")?;
    let maxval = number(3, "maxval")?;
    if maxval != 255 {
        return Err(Error::format(
            path,
            Location::Offset(tokens[3].1 as u64),
            format!("maxval {maxval}: only 8-bit PGM with maxval 255 is supported"),
        ));
    }
    if width == 0 || height == 0 {
        return Err(Error::format(path, Location::File, format!("empty image ({width} × {height})")));
    }
    // Exactly one whitespace byte ends the header.
    if !bytes.get(pos).is_some_and(u8::is_ascii_whitespace) {
        return Err(Error::format(path, Location::Offset(pos as u64), "no whitespace after the PGM maxval"));
    }
    pos += 1;
    let size = width.checked_mul(height).ok_or_else(|| Error::format(path, Location::File, "image size overflows"))?;
    let data = &bytes[pos..];
    if data.len() < size {
        return Err(Error::format(
            path,
            Location::Offset(bytes.len() as u64),
            format!("truncated: {width} × {height} needs {size} pixel bytes, the file has {}", data.len()),
        ));
    }
    Ok((width, height, data[..size].to_vec()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::grid::{logodds::logit, CellIndex, OccupancyParams};

    fn temp_dir(tag: &str) -> PathBuf {
        crate::testdata::temp_dir(&format!("mapserver-{tag}"))
    }

    /// 3 columns × 2 rows. Row 0 (lowest y): occupied, free, unknown (never seen).
    /// Row 1: unknown (seen, p = 0.5), occupied, free.
    fn raster() -> Raster {
        let occ = logit(0.9) as f32;
        let free = logit(0.1) as f32;
        Raster {
            width: 3,
            height: 2,
            resolution: 0.05,
            origin: Point2::new(-5.0, -2.5),
            first_cell: CellIndex { x: -100, y: -50 },
            log_odds: vec![occ, free, 0.0, 0.0, occ, free],
            known: vec![true, true, false, true, true, true],
            params: OccupancyParams::default(),
        }
    }

    #[test]
    fn round_trip_and_pixel_convention() {
        let d = temp_dir("rt");
        let yaml = d.join("map.yaml");
        let r = raster();
        let image = write_map_server(&yaml, &r).unwrap();
        assert_eq!(image, d.join("map.pgm"));
        let pgm = std::fs::read(&image).unwrap();
        let header = b"P5\n# CREATOR: fusemap 0.05 m/pix\n3 2\n255\n";
        assert_eq!(&pgm[..header.len()], header);
        // Top image row = raster row 1 (highest y), then row 0.
        assert_eq!(&pgm[header.len()..], &[205, 0, 254, 0, 254, 205]);
        let text = std::fs::read_to_string(&yaml).unwrap();
        assert_eq!(
            text,
            "image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-5.0, -2.5, 0.0]\n\
             negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        );
        let m = read_map_server(&yaml).unwrap();
        assert_eq!((m.width, m.height), (3, 2));
        assert_eq!(m.resolution, 0.05);
        assert_eq!(m.origin, Point2::new(-5.0, -2.5));
        assert_eq!(m.origin_yaw, 0.0);
        assert_eq!(m.mode, MapMode::Trinary);
        assert_eq!(m.cells, r.ternary());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn thresholds_decode_the_three_values() {
        // The rule of map_server with what we write.
        let decode = |v: u8| {
            let p = (255.0 - v as f64) / 255.0;
            if p > OCCUPIED_THRESH {
                Ternary::Occupied
            } else if p < FREE_THRESH {
                Ternary::Free
            } else {
                Ternary::Unknown
            }
        };
        assert_eq!(decode(PIXEL_OCCUPIED), Ternary::Occupied);
        assert_eq!(decode(PIXEL_FREE), Ternary::Free);
        assert_eq!(decode(PIXEL_UNKNOWN), Ternary::Unknown);
        // The trap the module documents: with free_thresh 0.25, 205 would be free.
        assert!((255.0 - PIXEL_UNKNOWN as f64) / 255.0 < 0.25);
    }

    #[test]
    fn reads_what_other_tools_write() {
        let d = temp_dir("foreign");
        // A map_saver-style pair: comments, quotes, negate, unknown keys, odd header.
        std::fs::write(d.join("my map.pgm"), [b"P5 # comment\n2\n# another\n 1 255\n".as_slice(), &[255, 0]].concat())
            .unwrap();
        let yaml = d.join("m.yaml");
        std::fs::write(
            &yaml,
            "# saved by hand\nimage: 'my map.pgm'  # relative\nresolution: 1\n\
             origin: [ 1.5, -2, 0.1 ]\nnegate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196\n\
             extra_key: whatever\n",
        )
        .unwrap();
        let m = read_map_server(&yaml).unwrap();
        assert_eq!((m.width, m.height, m.resolution), (2, 1, 1.0));
        assert_eq!(m.origin, Point2::new(1.5, -2.0));
        assert_eq!(m.origin_yaw, 0.1);
        // negate: p = v / 255, so 255 is occupied and 0 free.
        assert_eq!(m.cells, [Ternary::Occupied, Ternary::Free]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn errors_name_file_and_line() {
        let d = temp_dir("err");
        let yaml = d.join("map.yaml");
        write_map_server(&yaml, &raster()).unwrap();
        let good = std::fs::read_to_string(&yaml).unwrap();
        let check = |text: &str, needle: &str| {
            std::fs::write(&yaml, text).unwrap();
            let e = read_map_server(&yaml).unwrap_err().to_string();
            assert!(e.contains("map.yaml"), "{e}");
            assert!(e.contains(needle), "expected `{needle}` in: {e}");
        };
        check(&good.replace("resolution: 0.05", "resolution: abc"), ":3:");
        check(&good.replace("resolution: 0.05", "resolution: -1"), ":3:");
        check(&good.replace("origin: [-5.0, -2.5, 0.0]", "origin: [1, 2]"), ":4:");
        check(&good.replace("negate: 0", "negate: maybe"), ":5:");
        check(&good.replace("mode: trinary", "mode: raw"), ":2:");
        check(&good.replace("negate: 0\n", ""), "`negate`");
        check(&format!("{good}resolution: 1\n"), "twice");
        check(&good.replace("image: map.pgm", "  nested: x"), ":1:");
        check(&good.replace("image: map.pgm", "image: 'map.pgm"), "unterminated");
        // A missing image is an I/O error naming the image.
        std::fs::write(&yaml, good.replace("map.pgm", "gone.pgm")).unwrap();
        let e = read_map_server(&yaml).unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path.ends_with("gone.pgm")), "{e}");
        // A broken image names the image.
        std::fs::write(&yaml, &good).unwrap();
        std::fs::write(d.join("map.pgm"), b"P2\n3 2\n255\n").unwrap();
        let e = read_map_server(&yaml).unwrap_err().to_string();
        assert!(e.contains("map.pgm") && e.contains("P5"), "{e}");
        std::fs::write(d.join("map.pgm"), b"P5\n3 2\n255\n\x00").unwrap();
        let e = read_map_server(&yaml).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        std::fs::write(d.join("map.pgm"), b"P5\n3 2\n65535\n").unwrap();
        assert!(read_map_server(&yaml).is_err());
        std::fs::write(d.join("map.pgm"), b"P5\n3").unwrap();
        assert!(read_map_server(&yaml).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn refuses_bad_targets_and_maps() {
        let d = temp_dir("bad");
        let e = write_map_server(&d.join("map.pgm"), &raster()).unwrap_err();
        assert!(e.to_string().contains(".pgm"), "{e}");
        let mut empty = raster();
        empty.width = 0;
        empty.height = 0;
        empty.log_odds.clear();
        empty.known.clear();
        assert!(write_map_server(&d.join("e.yaml"), &empty).is_err());
        assert!(!d.join("e.pgm").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn yaml_scalars() {
        assert_eq!(yaml_float(-5.0), "-5.0");
        assert_eq!(yaml_float(0.05), "0.05");
        assert_eq!(yaml_float(1e-7), "0.0000001");
        assert_eq!(parse_yaml_float(&yaml_float(0.1 + 0.2)), Some(0.1 + 0.2));
        assert_eq!(yaml_string("map.pgm"), "map.pgm");
        assert_eq!(yaml_string("my map: #1.pgm"), "\"my map: #1.pgm\"");
        assert_eq!(unquote(&yaml_string("a\"b\\c.pgm")).unwrap(), "a\"b\\c.pgm");
        assert_eq!(unquote("'it''s'").unwrap(), "it's");
        assert_eq!(strip_comment("a: 'x # y' # z"), "a: 'x # y' ");
        assert_eq!(strip_comment("a: b#c"), "a: b#c");
        assert_eq!(parse_yaml_float("nan"), None);
        assert!(parse_yaml_float(".nan").unwrap().is_nan());
    }
}
