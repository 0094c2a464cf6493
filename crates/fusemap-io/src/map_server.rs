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
use crate::{yaml, Error, Location, Result};
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
/// The YAML is parsed as YAML ([`crate::yaml`]): any style, comments, quoted or plain
/// scalars, numbers quoted or not (as `map_server`'s yaml-cpp reads them). Required keys, as
/// in `map_server`: `image`, `resolution`, `origin`, `negate`, `occupied_thresh`,
/// `free_thresh`; `mode` defaults to `trinary`, and `raw` mode is refused. Unknown keys
/// are ignored, as `map_server` ignores them. The image must be binary PGM (`P5`) with
/// maxval 255. Every error names the YAML or image file and the line or field.
pub fn read_map_server(yaml_path: &Path) -> Result<MapServerMap> {
    let text = yaml::read_text(yaml_path)?;
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

/// Parses a map description (any YAML style) into the known keys.
fn parse_description(path: &Path, text: &str) -> Result<Description> {
    let root = yaml::parse(text).map_err(|(line, message)| {
        Error::format(path, if line == 0 { Location::File } else { Location::Line(line) }, message)
    })?;
    if !yaml::is_mapping(&root) {
        return Err(Error::format(
            path,
            Location::Line(yaml::line(&root)),
            "expected a map description (`key: value` lines), got another YAML value",
        ));
    }
    let at = |key: &str, node: &yaml::Node<'_>, message: String| {
        Error::format(path, Location::LineField(yaml::line(node), key.into()), message)
    };
    let number = |key: &str| -> Result<Option<(f64, u64)>> {
        let Some(n) = yaml::get(&root, key) else { return Ok(None) };
        Ok(Some((yaml::number(n).map_err(|m| at(key, n, m))?, yaml::line(n))))
    };
    let mut d = Description {
        resolution: number("resolution")?,
        occupied_thresh: number("occupied_thresh")?,
        free_thresh: number("free_thresh")?,
        ..Description::default()
    };
    if let Some(n) = yaml::get(&root, "image") {
        d.image = Some((yaml::text(n).map_err(|m| at("image", n, m))?, yaml::line(n)));
    }
    if let Some(n) = yaml::get(&root, "negate") {
        d.negate = Some(yaml::boolean(n).map_err(|m| at("negate", n, m))?);
    }
    if let Some(n) = yaml::get(&root, "mode") {
        d.mode = Some(match yaml::text(n).map_err(|m| at("mode", n, m))?.as_str() {
            "trinary" => MapMode::Trinary,
            "scale" => MapMode::Scale,
            "raw" => {
                let why = "`raw` mode stores occupancy values, not a picture of the map: not supported";
                return Err(at("mode", n, why.into()));
            }
            v => return Err(at("mode", n, format!("expected `trinary`, `scale` or `raw`, got `{v}`"))),
        });
    }
    if let Some(n) = yaml::get(&root, "origin") {
        let parts = yaml::items(n).ok_or_else(|| at("origin", n, "expected `[x, y, yaw]`".into()))?;
        if parts.len() != 3 {
            return Err(at("origin", n, format!("expected three numbers `[x, y, yaw]`, got {}", parts.len())));
        }
        let mut o = [0.0; 3];
        for (slot, p) in o.iter_mut().zip(parts) {
            *slot = yaml::number(p).map_err(|m| at("origin", p, m))?;
        }
        d.origin = Some((o, yaml::line(n)));
    }
    // map_server ignores keys it does not know.
    Ok(d)
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

    fn temp_dir(tag: &str) -> crate::testdata::TestDir {
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
        // The same description in flow style and as JSON.
        for text in [
            "{image: my map.pgm, resolution: 1, origin: [1.5, -2, 0.1], negate: 1,\n  occupied_thresh: 0.65, free_thresh: 0.196}\n",
            r#"{"image": "my map.pgm", "resolution": 1, "origin": [1.5, -2, 0.1], "negate": 1, "occupied_thresh": 0.65, "free_thresh": 0.196}"#,
        ] {
            std::fs::write(&yaml, text).unwrap();
            assert_eq!(read_map_server(&yaml).unwrap(), m, "{text}");
        }
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
        check(&good.replace("image: map.pgm", "  nested: x"), ":2: not valid YAML");
        check("[1, 2]\n", "map description");
        check(&good.replace("image: map.pgm", "image: [map.pgm]"), "expected text");
        check(&good.replace("image: map.pgm", "image: 'map.pgm"), "not valid YAML");
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
        assert_eq!(yaml_string("map.pgm"), "map.pgm");
        assert_eq!(yaml_string("my map: #1.pgm"), "\"my map: #1.pgm\"");
        // What is written reads back, through the YAML parser, as what was meant.
        let read = |value: String| {
            let doc = format!("v: {value}  # a comment\n");
            let root = yaml::parse(&doc).unwrap();
            let v = yaml::get(&root, "v").unwrap();
            (yaml::number(v).ok(), yaml::text(v).ok())
        };
        assert_eq!(read(yaml_float(0.1 + 0.2)).0, Some(0.1 + 0.2));
        for name in ["my map: #1.pgm", "a\"b\\c.pgm", "it's.pgm", "map.pgm"] {
            assert_eq!(read(yaml_string(name)).1.as_deref(), Some(name));
        }
        assert_eq!(read("'it''s'".into()).1.as_deref(), Some("it's"));
        assert_eq!(read("nan".into()).0, None);
        assert!(read(".nan".into()).0.unwrap().is_nan());
    }
}
