//! NumPy `.npz` output: the design document's hand-over format (§3.3 saves `occupancy`
//! and `log_odds` to `map_result.npz`; §4.4 adds `resolution` and `origin` so tools such as
//! slam_toolbox and cartographer_ros can pick the map up).
//!
//! An `.npz` is a zip archive of `.npy` files, one per array, named `<array>.npy`
//! (`numpy.savez`). The `.npy` format is NumPy's own, specified in
//! `numpy/lib/format.py` (NEP 1, "A Simple File Format for NumPy Arrays"):
//!
//! * the magic string `\x93NUMPY`, then the format version as two bytes (1, 0);
//! * a little-endian `u16` header length (version 2.0: `u32`, needed only past 64 KiB);
//! * an ASCII header that is the `repr` of a Python dict with the keys `descr` (the dtype,
//!   e.g. `'<f4'`), `fortran_order` and `shape` (a tuple), padded with spaces and ended by
//!   `\n` so that magic + version + length + header is a multiple of 64 bytes, which keeps
//!   the data aligned for memory mapping;
//! * the raw data, C (row-major) order.
//!
//! `numpy.savez` stores its members uncompressed (`ZIP_STORED`); this writer does the
//! same, so the files are the ones NumPy itself would make and `np.load(..., mmap_mode=)`
//! style readers that expect stored members work. Member timestamps are fixed at the zip
//! epoch (1980-01-01) so the same map gives byte-identical files.

use crate::atomic::{check_raster, write_atomic};
use crate::semantic::SemanticRaster;
use crate::{Error, Location, Result};
use fusemap_core::grid::{CellRaster, Raster};
use sink::QuietAfterError;
use std::collections::HashSet;
use std::io::{self, Seek, Write};
use std::path::Path;
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

mod read;
mod sink;
mod sparse;
pub use read::{read_npz, read_npz_f32, NpyOwned, NpyValues};
pub use sparse::write_sparse_map_npz;

/// The `.npy` magic string (format.py `MAGIC_PREFIX`).
pub const NPY_MAGIC: &[u8; 6] = b"\x93NUMPY";

/// Alignment of the data after the header (format.py `ARRAY_ALIGN`).
const ARRAY_ALIGN: usize = 64;

/// The element data of an array to write, borrowed from the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NpyData<'a> {
    /// `float32`, written as `'<f4'`.
    F32(&'a [f32]),
    /// `float64`, written as `'<f8'`.
    F64(&'a [f64]),
    /// `bool`, written as `'|b1'` (one byte, 0 or 1).
    Bool(&'a [bool]),
    /// `uint8`, written as `'|u1'`.
    U8(&'a [u8]),
    /// `int32`, written as `'<i4'`.
    I32(&'a [i32]),
    /// `int64`, written as `'<i8'`.
    I64(&'a [i64]),
    /// `int16`, written as `'<i2'`.
    I16(&'a [i16]),
    /// Unicode strings, written as NumPy's fixed-width `'<U{n}'` (UTF-32, little-endian,
    /// `n` the longest string's length in characters, shorter ones padded with NUL),
    /// which `np.load` reads without `allow_pickle`.
    Str(&'a [String]),
}

impl NpyData<'_> {
    /// NumPy's dtype string (`descr`): explicit little-endian (`<`) for multi-byte types,
    /// `|` (not applicable) for single bytes, as `numpy.dtype.str` spells them.
    pub fn descr(&self) -> String {
        match self {
            NpyData::F32(_) => "<f4".into(),
            NpyData::F64(_) => "<f8".into(),
            NpyData::Bool(_) => "|b1".into(),
            NpyData::U8(_) => "|u1".into(),
            NpyData::I32(_) => "<i4".into(),
            NpyData::I64(_) => "<i8".into(),
            NpyData::I16(_) => "<i2".into(),
            NpyData::Str(_) => format!("<U{}", self.str_width()),
        }
    }

    /// Characters per element of a [`NpyData::Str`] array: the longest string's (at
    /// least 1, as NumPy has no `<U0` it round-trips).
    fn str_width(&self) -> usize {
        match self {
            NpyData::Str(d) => d.iter().map(|s| s.chars().count()).max().unwrap_or(0).max(1),
            _ => 0,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            NpyData::F32(d) => d.len(),
            NpyData::F64(d) => d.len(),
            NpyData::Bool(d) => d.len(),
            NpyData::U8(d) => d.len(),
            NpyData::I32(d) => d.len(),
            NpyData::I64(d) => d.len(),
            NpyData::I16(d) => d.len(),
            NpyData::Str(d) => d.len(),
        }
    }

    /// True when there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn item_size(&self) -> usize {
        match self {
            NpyData::F32(_) | NpyData::I32(_) => 4,
            NpyData::F64(_) | NpyData::I64(_) => 8,
            NpyData::I16(_) => 2,
            NpyData::Bool(_) | NpyData::U8(_) => 1,
            NpyData::Str(_) => 4 * self.str_width(),
        }
    }
}

/// One C-order array ready to be written as a `.npy` file.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray<'a> {
    shape: Vec<usize>,
    data: NpyData<'a>,
}

impl<'a> NpyArray<'a> {
    /// An array of `shape` (empty for a 0-d scalar) holding `data` in C (row-major)
    /// order. `None` when the shape's product is not `data.len()`: a wrong shape would
    /// otherwise produce a file NumPy refuses or, worse, reads with the wrong layout.
    pub fn new(shape: &[usize], data: NpyData<'a>) -> Option<Self> {
        let count = shape.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d))?;
        (count == data.len()).then(|| Self { shape: shape.to_vec(), data })
    }

    /// The shape.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// The data.
    pub fn data(&self) -> NpyData<'a> {
        self.data
    }

    /// The complete header: magic, version, length and the padded dict. Version 1.0
    /// unless the dict needs more than 65535 bytes (only absurdly many dimensions), then
    /// 2.0 as format.py does.
    pub fn header(&self) -> Vec<u8> {
        let shape = match self.shape.as_slice() {
            [] => "()".to_string(),
            [n] => format!("({n},)"),
            dims => format!("({})", dims.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")),
        };
        let dict = format!("{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}", self.data.descr());
        // magic (6) + version (2) + length (2 for v1, 4 for v2) + dict + padding + '\n';
        // the padded header (dict + padding + '\n') is at most dict + ARRAY_ALIGN bytes.
        let (version, len_size) = if dict.len() + ARRAY_ALIGN <= u16::MAX as usize { (1u8, 2) } else { (2u8, 4) };
        let unpadded = 6 + 2 + len_size + dict.len() + 1;
        let padding = (ARRAY_ALIGN - unpadded % ARRAY_ALIGN) % ARRAY_ALIGN;
        let header_len = dict.len() + padding + 1;
        let mut out = Vec::with_capacity(unpadded + padding);
        out.extend_from_slice(NPY_MAGIC);
        out.extend_from_slice(&[version, 0]);
        match u16::try_from(header_len) {
            Ok(len) if version == 1 => out.extend_from_slice(&len.to_le_bytes()),
            _ => out.extend_from_slice(&u32::try_from(header_len).unwrap_or(u32::MAX).to_le_bytes()),
        }
        out.extend_from_slice(dict.as_bytes());
        out.resize(out.len() + padding, b' ');
        out.push(b'\n');
        out
    }

    /// Size in bytes of the whole `.npy` file.
    pub fn file_size(&self) -> u64 {
        self.header().len() as u64 + (self.data.len() as u64) * self.data.item_size() as u64
    }

    /// Writes the `.npy` file: header, then the data in little-endian byte order
    /// whatever the host's, in chunks so memory stays small.
    pub fn write_to(&self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&self.header())?;
        const CHUNK: usize = 8192;
        let mut buf = Vec::with_capacity(CHUNK * 8);
        macro_rules! chunks {
            ($d:expr, $conv:expr) => {
                for part in $d.chunks(CHUNK) {
                    buf.clear();
                    for &v in part {
                        buf.extend_from_slice(&$conv(v));
                    }
                    w.write_all(&buf)?;
                }
            };
        }
        match self.data {
            NpyData::F32(d) => chunks!(d, f32::to_le_bytes),
            NpyData::F64(d) => chunks!(d, f64::to_le_bytes),
            NpyData::I32(d) => chunks!(d, i32::to_le_bytes),
            NpyData::I64(d) => chunks!(d, i64::to_le_bytes),
            NpyData::I16(d) => chunks!(d, i16::to_le_bytes),
            NpyData::Str(d) => {
                let width = self.data.str_width();
                for s in d {
                    buf.clear();
                    for c in s.chars() {
                        buf.extend_from_slice(&u32::from(c).to_le_bytes());
                    }
                    buf.resize(4 * width, 0);
                    w.write_all(&buf)?;
                }
            }
            NpyData::Bool(d) => chunks!(d, |b: bool| [u8::from(b)]),
            NpyData::U8(d) => w.write_all(d)?,
        }
        Ok(())
    }
}

/// Writes `.npz` archives the way `numpy.savez` does: each array is a stored (not
/// compressed) member `<name>.npy`.
pub struct NpzWriter<W: Write + Seek> {
    zip: ZipWriter<QuietAfterError<W>>,
    names: HashSet<String>,
}

impl<W: Write + Seek> NpzWriter<W> {
    /// An archive written to `inner`.
    pub fn new(inner: W) -> Self {
        Self { zip: ZipWriter::new(QuietAfterError::new(inner)), names: HashSet::new() }
    }

    /// Adds `array` as `<name>.npy`. Names must be unique, non-empty and without `/`
    /// (NumPy turns member names into the keys of the loaded dict; a `/` would make a
    /// directory in the archive).
    pub fn add(&mut self, name: &str, array: &NpyArray<'_>) -> io::Result<()> {
        if name.is_empty() || name.contains(['/', '\\']) {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, format!("`{name}` is not a valid npz array name")));
        }
        if !self.names.insert(name.to_string()) {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, format!("array `{name}` added twice")));
        }
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Stored)
            .last_modified_time(DateTime::default())
            .unix_permissions(0o644)
            .large_file(array.file_size() >= u32::MAX as u64);
        self.zip.start_file(format!("{name}.npy"), options)?;
        array.write_to(&mut self.zip)
    }

    /// Writes the central directory and returns the inner writer.
    pub fn finish(self) -> io::Result<W> {
        Ok(self.zip.finish()?.inner)
    }
}

/// Layers written into the map's `.npz` beside the occupancy arrays, each optional; they
/// must cover the same cells as the occupancy raster (same size, resolution and origin).
#[derive(Clone, Copy, Debug, Default)]
pub struct NpzLayers<'a> {
    /// The semantic layer: `semantic_class`, `semantic_prob`, `semantic_probs` and the
    /// class table (`semantic_class_ids`, `semantic_class_names`, `semantic_class_colors`).
    pub semantic: Option<&'a SemanticRaster>,
    /// The dynamic layer's probability per cell: `dynamic` (NaN where never observed).
    pub dynamic: Option<&'a CellRaster<f32>>,
}

/// Writes a map as `.npz`, atomically, with exactly these arrays:
///
/// | name | dtype | shape | meaning |
/// |---|---|---|---|
/// | `occupancy` | float32 | (height, width) | `1 - 1/(1 + e^l)`; the prior where unknown |
/// | `log_odds` | float32 | (height, width) | `l`; the prior's log-odds where unknown |
/// | `known` | bool | (height, width) | whether the cell was ever observed |
/// | `resolution` | float64 | () | cell side, metres |
/// | `origin` | float64 | (2,) | world x, y of the lower-left corner of cell `[0, 0]` |
///
/// Arrays are indexed `[iy, ix]` with row 0 the lowest y, the design document's
/// `log_odds[iy, ix]` (§3.3): cell `[iy, ix]` covers
/// `origin + (ix, iy) · resolution` to `origin + (ix + 1, iy + 1) · resolution`. To show
/// it the right way up, use `imshow(occupancy, origin='lower')`.
pub fn write_map_npz(path: &Path, raster: &Raster) -> Result<()> {
    write_map_npz_with(path, raster, &NpzLayers::default())
}

/// [`write_map_npz`] plus the optional layers, same indexing (`[iy, ix]`, row 0 the
/// lowest y), K the number of classes:
///
/// | name | dtype | shape | meaning |
/// |---|---|---|---|
/// | `semantic_class` | int16 | (height, width) | most likely class, an index into the class arrays; -1: no semantic evidence |
/// | `semantic_prob` | float32 | (height, width) | its probability |
/// | `semantic_probs` | float32 | (height, width, K) | every class's probability (only when given) |
/// | `semantic_class_ids` | int32 | (K,) | the label id of each class index |
/// | `semantic_class_names` | `<U{n}` | (K,) | its name |
/// | `semantic_class_colors` | uint8 | (K, 3) | its RGB colour (as in `semantic.png`) |
/// | `dynamic` | float32 | (height, width) | the dynamic layer's probability; NaN where never observed |
///
/// A layer that does not match the occupancy raster's cells, or a semantic raster that
/// fails [`SemanticRaster::check`], is an error naming the file; nothing is written.
pub fn write_map_npz_with(path: &Path, raster: &Raster, layers: &NpzLayers<'_>) -> Result<()> {
    check_raster(path, raster, false)?;
    let bad = |what: String| Error::format(path, Location::File, what);
    let shape = [raster.height, raster.width];
    let occupancy = raster.occupancy();
    let mut arrays = vec![
        ("occupancy", NpyArray::new(&shape, NpyData::F32(&occupancy))),
        ("log_odds", NpyArray::new(&shape, NpyData::F32(&raster.log_odds))),
        ("known", NpyArray::new(&shape, NpyData::Bool(&raster.known))),
    ];
    let resolution = [raster.resolution];
    let origin = [raster.origin.x, raster.origin.y];
    arrays.push(("resolution", NpyArray::new(&[], NpyData::F64(&resolution))));
    arrays.push(("origin", NpyArray::new(&[2], NpyData::F64(&origin))));

    let same_cells = |what: &str, w: usize, h: usize, res: f64, o: [f64; 2]| -> Result<()> {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()));
        if (w, h) != (raster.width, raster.height)
            || !close(res, raster.resolution)
            || !close(o[0], raster.origin.x)
            || !close(o[1], raster.origin.y)
        {
            return Err(bad(format!(
                "the {what} layer ({w} × {h} cells of {res} m at ({}, {})) does not cover the occupancy map's cells \
                 ({} × {} of {} m at ({}, {}))",
                o[0], o[1], raster.width, raster.height, raster.resolution, raster.origin.x, raster.origin.y
            )));
        }
        Ok(())
    };
    let (names, ids, colors);
    let k_shape;
    if let Some(s) = layers.semantic {
        s.check().map_err(|e| bad(format!("semantic layer: {e}")))?;
        same_cells("semantic", s.width, s.height, s.resolution, s.origin)?;
        names = s.classes.iter().map(|c| c.name.clone()).collect::<Vec<_>>();
        ids = s.classes.iter().map(|c| i32::from(c.id)).collect::<Vec<_>>();
        colors = s.classes.iter().flat_map(|c| c.color).collect::<Vec<_>>();
        k_shape = [raster.height, raster.width, s.classes.len()];
        arrays.push(("semantic_class", NpyArray::new(&shape, NpyData::I16(&s.best))));
        arrays.push(("semantic_prob", NpyArray::new(&shape, NpyData::F32(&s.prob))));
        if !s.probs.is_empty() {
            arrays.push(("semantic_probs", NpyArray::new(&k_shape, NpyData::F32(&s.probs))));
        }
        arrays.push(("semantic_class_ids", NpyArray::new(&[ids.len()], NpyData::I32(&ids))));
        arrays.push(("semantic_class_names", NpyArray::new(&[names.len()], NpyData::Str(&names))));
        arrays.push(("semantic_class_colors", NpyArray::new(&[names.len(), 3], NpyData::U8(&colors))));
    }
    let dynamic;
    if let Some(d) = layers.dynamic {
        same_cells("dynamic", d.width, d.height, d.resolution, [d.origin.x, d.origin.y])?;
        if d.cells.len() != d.width * d.height || d.known.len() != d.cells.len() {
            return Err(bad(format!(
                "the dynamic layer is {} × {} cells but holds {} values and {} known flags",
                d.width,
                d.height,
                d.cells.len(),
                d.known.len()
            )));
        }
        dynamic = d.cells.iter().zip(&d.known).map(|(&p, &k)| if k { p } else { f32::NAN }).collect::<Vec<_>>();
        arrays.push(("dynamic", NpyArray::new(&shape, NpyData::F32(&dynamic))));
    }

    // The checks above guarantee the sizes; this keeps the writer panic-free regardless.
    write_arrays(path, arrays)
}

/// Writes `arrays` as an `.npz` at `path`, atomically; an array whose shape did not match
/// its data (`None`) is an error naming it, and nothing is written.
pub fn write_arrays(path: &Path, arrays: Vec<(&str, Option<NpyArray<'_>>)>) -> Result<()> {
    let mut all = Vec::with_capacity(arrays.len());
    for (name, array) in arrays {
        let array = array.ok_or_else(|| {
            Error::format(path, Location::Field(name.into()), "array size does not match the map's shape")
        })?;
        all.push((name, array));
    }
    write_atomic(path, |w| {
        let mut npz = NpzWriter::new(w);
        for (name, array) in &all {
            npz.add(name, array)?;
        }
        npz.finish()?;
        Ok(())
    })
}

#[cfg(test)]
mod tests;
