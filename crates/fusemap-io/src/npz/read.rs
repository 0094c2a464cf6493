//! Reading `.npz` archives back: one `.npy` member at a time, every length checked
//! against what the member holds before it is allocated.

use super::NPY_MAGIC;
use crate::{Error, Location, Result};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;
use zip::ZipArchive;

/// The element values of an array read back from a `.npy` member.
#[derive(Clone, Debug, PartialEq)]
pub enum NpyValues {
    /// `<f4`.
    F32(Vec<f32>),
    /// `<f8`.
    F64(Vec<f64>),
    /// `|b1`.
    Bool(Vec<bool>),
    /// `|u1`.
    U8(Vec<u8>),
    /// `<i4`.
    I32(Vec<i32>),
    /// `<i8`.
    I64(Vec<i64>),
    /// `<i2`.
    I16(Vec<i16>),
    /// `<U{n}`, NUL padding removed.
    Str(Vec<String>),
}

/// An array read from an `.npz`.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyOwned {
    /// The shape (empty for a 0-d array).
    pub shape: Vec<usize>,
    /// The values, C order.
    pub values: NpyValues,
}

/// Reads the array `name` (with or without `.npy`) of an `.npz` file.
///
/// Supports what [`NpyArray`](super::NpyArray) writes: little-endian `f4`, `f8`, `i4`, `i8`, `i2`, `U{n}`, and
/// `b1`, `u1`, C order, `.npy` versions 1.0 to 3.0, stored or deflated members (`np.savez` and
/// `np.savez_compressed`). Anything else is an [`Error::Format`] naming the array.
pub fn read_npz(path: &Path, name: &str) -> Result<NpyOwned> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut zip = ZipArchive::new(BufReader::new(file)).map_err(|e| zip_error(path, e))?;
    let member = if name.ends_with(".npy") { name.to_string() } else { format!("{name}.npy") };
    let field = Location::Field(name.trim_end_matches(".npy").to_string());
    let mut entry = match zip.by_name(&member) {
        Ok(e) => e,
        Err(zip::result::ZipError::FileNotFound) => {
            return Err(Error::format(path, field, "no such array in the archive"))
        }
        Err(e) => return Err(zip_error(path, e)),
    };
    let bad = |msg: String| Error::format(path, field.clone(), msg);

    let header = read_npy_header(&mut entry).map_err(bad)?;
    let (descr, fortran, shape) = parse_header(&header).map_err(bad)?;
    if fortran {
        return Err(bad("Fortran-order arrays are not supported".into()));
    }
    let count = shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or_else(|| bad("shape overflows".into()))?;
    let item = item_size(&descr).map_err(bad)?;
    let bytes = count.checked_mul(item).ok_or_else(|| bad("shape overflows".into()))?;
    if bytes as u64 > entry.size() {
        return Err(bad(format!("shape {shape:?} needs {bytes} bytes but the member holds {}", entry.size())));
    }
    // The member's stated size may lie: read what it holds, growing fallibly, and compare.
    let mut raw = Vec::new();
    crate::bounded::read_to_end_bounded((&mut entry).take(bytes as u64), bytes as u64, &mut raw)
        .map_err(|e| bad(format!("reading the data: {e}")))?;
    if raw.len() != bytes {
        return Err(bad(format!(
            "truncated data: shape {shape:?} needs {bytes} bytes, the member holds {}",
            raw.len()
        )));
    }
    let values = decode(&descr, item, raw);
    Ok(NpyOwned { shape, values })
}

/// The header text of a `.npy` stream: magic, version 1 to 3, and a header length of at
/// most 1 MiB.
fn read_npy_header(entry: &mut impl Read) -> std::result::Result<String, String> {
    let truncated = |e: std::io::Error| format!("truncated .npy header: {e}");
    let mut pre = [0u8; 8];
    entry.read_exact(&mut pre).map_err(truncated)?;
    if &pre[..6] != NPY_MAGIC {
        return Err("not a .npy file (bad magic)".into());
    }
    let header_len = match pre[6] {
        1 => {
            let mut l = [0u8; 2];
            entry.read_exact(&mut l).map_err(truncated)?;
            u16::from_le_bytes(l) as usize
        }
        2 | 3 => {
            let mut l = [0u8; 4];
            entry.read_exact(&mut l).map_err(truncated)?;
            u32::from_le_bytes(l) as usize
        }
        v => return Err(format!("unsupported .npy version {v}.{}", pre[7])),
    };
    if header_len > 1 << 20 {
        return Err(format!("implausible .npy header length {header_len}"));
    }
    let mut header = vec![0u8; header_len];
    entry.read_exact(&mut header).map_err(truncated)?;
    String::from_utf8(header).map_err(|_| "header is not text".into())
}

/// Bytes one item of dtype `descr` takes (`<Un`: n UTF-32 characters).
fn item_size(descr: &str) -> std::result::Result<usize, String> {
    let str_width = descr.strip_prefix("<U").and_then(|n| n.parse::<usize>().ok());
    match (descr, str_width) {
        ("<f4" | "<i4", _) => Ok(4),
        ("<f8" | "<i8", _) => Ok(8),
        ("<i2", _) => Ok(2),
        ("|b1" | "|u1", _) => Ok(1),
        (_, Some(n)) => n.checked_mul(4).ok_or_else(|| format!("unsupported dtype `{descr}`")),
        (d, None) => Err(format!("unsupported dtype `{d}`")),
    }
}

/// The little-endian items of `raw` as dtype `descr` (of `item` bytes each).
fn decode(descr: &str, item: usize, raw: Vec<u8>) -> NpyValues {
    match descr {
        "<f4" => NpyValues::F32(raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()),
        "<i4" => NpyValues::I32(raw.chunks_exact(4).map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()),
        "<i8" => NpyValues::I64(
            raw.chunks_exact(8).map(|c| i64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect(),
        ),
        "<i2" => NpyValues::I16(raw.chunks_exact(2).map(|c| i16::from_le_bytes([c[0], c[1]])).collect()),
        "<f8" => NpyValues::F64(
            raw.chunks_exact(8).map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect(),
        ),
        "|b1" => NpyValues::Bool(raw.iter().map(|&b| b != 0).collect()),
        "|u1" => NpyValues::U8(raw),
        _ => NpyValues::Str(
            raw.chunks_exact(item.max(1))
                .map(|e| {
                    e.chunks_exact(4)
                        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .take_while(|&c| c != 0)
                        .map(|c| char::from_u32(c).unwrap_or(char::REPLACEMENT_CHARACTER))
                        .collect()
                })
                .collect(),
        ),
    }
}

/// Reads a `float32` array of an `.npz`: its shape and values (see [`read_npz`]).
pub fn read_npz_f32(path: &Path, name: &str) -> Result<(Vec<usize>, Vec<f32>)> {
    let a = read_npz(path, name)?;
    match a.values {
        NpyValues::F32(v) => Ok((a.shape, v)),
        _ => Err(Error::format(
            path,
            Location::Field(name.trim_end_matches(".npy").to_string()),
            "the array is not float32 ('<f4')",
        )),
    }
}

fn zip_error(path: &Path, e: zip::result::ZipError) -> Error {
    match e {
        zip::result::ZipError::Io(io) => Error::io(path, io),
        other => Error::format(path, Location::File, format!("not a valid npz: {other}")),
    }
}

/// Parses the header dict: `descr`, `fortran_order`, `shape`. Only the literal forms
/// NumPy writes are accepted (a Python dict of a string, a bool and a tuple of ints).
pub(super) fn parse_header(h: &str) -> std::result::Result<(String, bool, Vec<usize>), String> {
    let body = h
        .trim()
        .strip_prefix('{')
        .and_then(|s| s.strip_suffix('}'))
        .ok_or_else(|| format!("header is not a dict: {h:?}"))?;
    let value_after = |key: &str| -> std::result::Result<&str, String> {
        let at = body.find(&format!("'{key}'")).ok_or_else(|| format!("header lacks `{key}`"))?;
        let rest = &body[at + key.len() + 2..];
        rest.trim_start().strip_prefix(':').map(str::trim_start).ok_or_else(|| format!("header: `{key}` has no value"))
    };
    let d = value_after("descr")?;
    let quote = d.chars().next().filter(|c| *c == '\'' || *c == '"');
    let descr = quote
        .and_then(|q| d[1..].split(q).next())
        .ok_or_else(|| "header: `descr` is not a string".to_string())?
        .to_string();
    let f = value_after("fortran_order")?;
    let fortran = if f.starts_with("True") {
        true
    } else if f.starts_with("False") {
        false
    } else {
        return Err("header: `fortran_order` is not True or False".into());
    };
    let s = value_after("shape")?;
    let inner = s
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| "header: `shape` is not a tuple".to_string())?;
    let shape = inner
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| {
            t.trim_end_matches('L').parse::<usize>().map_err(|_| format!("header: bad dimension `{t}` in `shape`"))
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok((descr, fortran, shape))
}
