//! Camera images decoded into the core's image types: class labels ([`LabelImage`]) and
//! depth in metres ([`DepthImage`]).
//!
//! | wanted | encodings | pixel value |
//! |---|---|---|
//! | labels | `mono8`, `8UC1` | the class id |
//! | labels | `mono16`, `16UC1` | the class id |
//! | depth | `32FC1` | metres; NaN, ±inf, 0 or negative: no depth |
//! | depth | `16UC1`, `mono16` | millimetres; 0 is no depth and becomes NaN |
//!
//! The depth conventions are ROS's REP 118 (*Depth Images*): `32FC1` in metres with NaN
//! for no reading, `16UC1` in millimetres with 0 for no reading. Multi-byte pixels are
//! read in the byte order the message states (`is_bigendian`), rows `step` bytes apart
//! (padding at the end of a row is skipped). Any other encoding (`rgb8`, `bgr8`,
//! `32FC3`, …) is refused with an error naming it and the supported ones: guessing a
//! channel would silently map colours to classes.
//!
//! Decoding checks the layout again ([`check_image_layout`]; the message's fields are
//! public, so it may not come from a reader) before it allocates, so the allocation is
//! bounded by the data the message holds. Whether the label and depth images of one
//! frame have the same size is the caller's check ([`check_same_size`] helps); both
//! decode on their own.

use crate::log::{bytes_per_pixel, check_image_layout, ImageMessage};
use fusemap_core::sensor::{DepthImage, ImageError, LabelImage};

/// The encodings [`labels`] reads.
pub const LABEL_ENCODINGS: [&str; 4] = ["mono8", "8UC1", "mono16", "16UC1"];

/// The encodings [`depth`] reads.
pub const DEPTH_ENCODINGS: [&str; 3] = ["32FC1", "16UC1", "mono16"];

/// Why an image could not be decoded.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CameraDecodeError {
    /// The encoding is not one this decoding reads.
    #[error("image on `{topic}`: encoding `{encoding}` cannot be read as {wanted}; supported: {}", supported.join(", "))]
    Unsupported {
        /// The image's topic.
        topic: String,
        /// The encoding as written.
        encoding: String,
        /// `labels` or `depth`.
        wanted: &'static str,
        /// The encodings that are read as `wanted`.
        supported: &'static [&'static str],
    },
    /// The declared sizes do not fit the data ([`check_image_layout`]).
    #[error("image on `{topic}`: {reason}")]
    Layout {
        /// The image's topic.
        topic: String,
        /// What is wrong.
        reason: String,
    },
    /// The decoded pixels do not make an image (cannot happen after the layout check;
    /// kept so that no path panics).
    #[error("image on `{topic}`: {source}")]
    Image {
        /// The image's topic.
        topic: String,
        /// The core's refusal.
        source: ImageError,
    },
    /// A label and a depth image meant to be read together differ in size.
    #[error("labels are {label_width}×{label_height} but depth is {depth_width}×{depth_height}: they must be aligned pixel for pixel")]
    SizeMismatch {
        /// Label image columns.
        label_width: u32,
        /// Label image rows.
        label_height: u32,
        /// Depth image columns.
        depth_width: u32,
        /// Depth image rows.
        depth_height: u32,
    },
}

/// Decodes a class-label image (`mono8`, `8UC1`, `mono16`, `16UC1`).
pub fn labels(m: &ImageMessage) -> Result<LabelImage, CameraDecodeError> {
    let labels = match m.encoding.as_str() {
        "mono8" | "8UC1" => pixels(m, |p: [u8; 1]| u16::from(p[0]))?,
        "mono16" | "16UC1" => {
            if m.is_bigendian {
                pixels(m, u16::from_be_bytes)?
            } else {
                pixels(m, u16::from_le_bytes)?
            }
        }
        _ => return Err(unsupported(m, "labels", &LABEL_ENCODINGS)),
    };
    LabelImage::new(m.width, m.height, labels)
        .map_err(|source| CameraDecodeError::Image { topic: m.topic.clone(), source })
}

/// Decodes a depth image into metres (`32FC1` metres, `16UC1`/`mono16` millimetres with
/// 0 = no depth → NaN; REP 118).
pub fn depth(m: &ImageMessage) -> Result<DepthImage, CameraDecodeError> {
    let metres = match (m.encoding.as_str(), m.is_bigendian) {
        ("32FC1", false) => pixels(m, f32::from_le_bytes)?,
        ("32FC1", true) => pixels(m, f32::from_be_bytes)?,
        ("16UC1" | "mono16", false) => pixels(m, |p| millimetres(u16::from_le_bytes(p)))?,
        ("16UC1" | "mono16", true) => pixels(m, |p| millimetres(u16::from_be_bytes(p)))?,
        _ => return Err(unsupported(m, "depth", &DEPTH_ENCODINGS)),
    };
    DepthImage::new(m.width, m.height, metres)
        .map_err(|source| CameraDecodeError::Image { topic: m.topic.clone(), source })
}

/// Refuses a label and a depth image of different sizes (the camera model needs them
/// aligned pixel for pixel).
pub fn check_same_size(labels: &LabelImage, depth: &DepthImage) -> Result<(), CameraDecodeError> {
    if (labels.width, labels.height) == (depth.width, depth.height) {
        Ok(())
    } else {
        Err(CameraDecodeError::SizeMismatch {
            label_width: labels.width,
            label_height: labels.height,
            depth_width: depth.width,
            depth_height: depth.height,
        })
    }
}

/// A 16-bit depth in millimetres as metres; 0 (no reading, REP 118) as NaN.
fn millimetres(mm: u16) -> f32 {
    if mm == 0 {
        f32::NAN
    } else {
        f32::from(mm) / 1000.0
    }
}

fn unsupported(m: &ImageMessage, wanted: &'static str, supported: &'static [&'static str]) -> CameraDecodeError {
    CameraDecodeError::Unsupported { topic: m.topic.clone(), encoding: m.encoding.clone(), wanted, supported }
}

/// Every pixel of `m` (of `N` bytes, which must be the encoding's size) through `f`, row
/// by row, skipping each row's padding.
fn pixels<const N: usize, T>(m: &ImageMessage, f: impl Fn([u8; N]) -> T) -> Result<Vec<T>, CameraDecodeError> {
    let layout = |reason: String| CameraDecodeError::Layout { topic: m.topic.clone(), reason };
    check_image_layout(m.width, m.height, &m.encoding, m.step, m.data.len() as u64).map_err(layout)?;
    debug_assert_eq!(bytes_per_pixel(&m.encoding), Some(N as u64));
    // After the check, step × height ≤ data.len() and width × N ≤ step, so every product
    // below fits in usize and every row is inside the data.
    let (width, height, step) = (m.width as usize, m.height as usize, m.step as usize);
    let mut out = Vec::with_capacity(width * height);
    for v in 0..height {
        let start = v * step;
        let row = m
            .data
            .get(start..start + width * N)
            .ok_or_else(|| layout(format!("row {v} lies outside the {} bytes of data", m.data.len())))?;
        let (chunks, _) = row.as_chunks::<N>();
        out.extend(chunks.iter().map(|c| f(*c)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
