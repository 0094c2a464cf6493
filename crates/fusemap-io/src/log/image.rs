//! Camera messages: `sensor_msgs/Image` and `sensor_msgs/CameraInfo`, and the choice of
//! which images a reader copies the pixels of.
//!
//! An image is by far the largest message a log holds (a 640 × 480 depth image is
//! 1.2 MB, a thousand laser scans' worth). A pass that only wants scans and pose streams
//! must not pay for it, so readers decode an image's pixels only for the topics
//! [`ReadOptions::images`] names; every other image becomes an [`ImageHeader`]: its
//! stamps, frame, size and encoding, which is what an inventory of the camera topics
//! needs, with the payload's length checked but its bytes neither decoded nor copied.
//!
//! Every image, header-only or not, passes [`check_image_layout`] before anything is
//! allocated for its pixels: a message whose declared sizes do not fit its data, or
//! exceed [`MAX_IMAGE_PIXELS`], is a malformed message (counted and skipped by callers
//! like any other payload that does not decode), never a panic or an allocation sized
//! by a header field.

use fusemap_core::time::Stamp;
use std::collections::BTreeSet;

/// The most pixels (`width × height`) an image message may declare: 2²⁶, an 8192 × 8192
/// image, eight times a 4K frame. Past it the message is refused as malformed, so a
/// corrupt size field cannot make a consumer allocate gigabytes for its decoded pixels.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// `sensor_msgs/Image` with its pixels (row 0 at the top, `step` bytes a row).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageMessage {
    /// Topic.
    pub topic: String,
    /// `header.stamp`: acquisition time of the image.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`: the camera's optical frame (REP 103: z forward, x right, y down).
    pub frame_id: String,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Pixel encoding as written (`mono8`, `16UC1`, `32FC1`, `rgb8`, …; the names of
    /// `sensor_msgs/image_encodings.h`).
    pub encoding: String,
    /// Multi-byte pixels are big-endian (`is_bigendian != 0`).
    pub is_bigendian: bool,
    /// Bytes per row (at least `width ×` the pixel size; rows may be padded).
    pub step: u32,
    /// The pixels, at least `step × height` bytes (checked by the reader).
    pub data: Vec<u8>,
}

impl ImageMessage {
    /// The same message without its pixels.
    pub fn header(&self) -> ImageHeader {
        ImageHeader {
            topic: self.topic.clone(),
            stamp: self.stamp,
            receive_stamp: self.receive_stamp,
            frame_id: self.frame_id.clone(),
            width: self.width,
            height: self.height,
            encoding: self.encoding.clone(),
            is_bigendian: self.is_bigendian,
            step: self.step,
            data_len: self.data.len() as u64,
        }
    }
}

/// A `sensor_msgs/Image` read without its pixels: what a first pass keeps of an image
/// topic (stamps, frame, size, encoding). Readers give one for every image whose topic
/// [`ReadOptions::images`] does not ask for; the payload's length is checked
/// ([`check_image_layout`]) but its bytes are neither decoded nor copied.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageHeader {
    /// Topic.
    pub topic: String,
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`.
    pub frame_id: String,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Pixel encoding as written.
    pub encoding: String,
    /// Multi-byte pixels are big-endian.
    pub is_bigendian: bool,
    /// Bytes per row.
    pub step: u32,
    /// Length of the message's `data` field, bytes (checked against `step × height`).
    pub data_len: u64,
}

/// `sensor_msgs/CameraInfo`: the calibration of the camera that took the images of the
/// same frame, the fields fusemap uses (ROS 1 spells `d` and `k` as `D` and `K`).
///
/// `R`, `P`, binning and region of interest are read past, not kept: fusemap projects
/// through the raw pinhole `K` of the (undistorted) image.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfoMessage {
    /// Topic.
    pub topic: String,
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Log/receive time, if the format has one.
    pub receive_stamp: Option<Stamp>,
    /// `header.frame_id`: the optical frame.
    pub frame_id: String,
    /// Image columns the calibration was made for.
    pub width: u32,
    /// Image rows the calibration was made for.
    pub height: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`, … or empty.
    pub distortion_model: String,
    /// Distortion coefficients (`plumb_bob`: k1, k2, t1, t2, k3), as many as written.
    pub d: Vec<f64>,
    /// Row-major 3 × 3 intrinsic matrix: `fx 0 cx; 0 fy cy; 0 0 1`.
    pub k: [f64; 9],
}

/// Which images a reader decodes the pixels of.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ImagePayloads {
    /// None: every image is an [`ImageHeader`] (the default, for passes that do not map
    /// camera data).
    #[default]
    HeadersOnly,
    /// The images of these topics, in full ([`ImageMessage`]); the others as headers.
    Topics(BTreeSet<String>),
    /// Every image in full.
    All,
}

impl ImagePayloads {
    /// True when the pixels of images on `topic` are wanted.
    pub fn wants(&self, topic: &str) -> bool {
        match self {
            ImagePayloads::HeadersOnly => false,
            ImagePayloads::Topics(t) => t.contains(topic),
            ImagePayloads::All => true,
        }
    }
}

/// Default of [`ReadOptions::max_decompressed_bytes`]: 512 MiB, `[limits] decompressed_mib`.
pub const DEFAULT_MAX_DECOMPRESSED_BYTES: u64 = 512 << 20;

/// What a log reader decodes beyond the small messages it always decodes, and how large
/// one piece of it may grow.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadOptions {
    /// The images whose pixels are decoded.
    pub images: ImagePayloads,
    /// The most bytes one chunk, message or line may hold once decompressed (ROS 1 bz2 and
    /// lz4 chunks, MCAP records, rosbag2 zstd messages, CARMEN lines): a decompression bomb
    /// or a corrupt size is refused at that point, not after the memory is taken.
    pub max_decompressed_bytes: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self { images: ImagePayloads::default(), max_decompressed_bytes: DEFAULT_MAX_DECOMPRESSED_BYTES }
    }
}

impl ReadOptions {
    /// Options that decode the pixels of the images of `topics`.
    pub fn with_image_topics<I, S>(topics: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        Self { images: ImagePayloads::Topics(topics.into_iter().map(Into::into).collect()), ..Self::default() }
    }
}

/// Bytes per pixel of a `sensor_msgs/image_encodings.h` encoding: the named ones
/// (`mono8`, `rgb8`, `bgra16`, `bayer_rggb8`, `yuv422`, …) and the OpenCV-style
/// `<bits><U|S|F>C<channels>` ones (`8UC1`, `16UC1`, `32FC1`, `32FC3`, …). `None` for
/// an encoding it does not know, whose row length then cannot be checked.
pub fn bytes_per_pixel(encoding: &str) -> Option<u64> {
    let named = match encoding {
        "mono8" | "bayer_rggb8" | "bayer_bggr8" | "bayer_gbrg8" | "bayer_grbg8" => Some(1),
        "mono16" | "bayer_rggb16" | "bayer_bggr16" | "bayer_gbrg16" | "bayer_grbg16" => Some(2),
        "rgb8" | "bgr8" => Some(3),
        "rgba8" | "bgra8" => Some(4),
        "rgb16" | "bgr16" => Some(6),
        "rgba16" | "bgra16" => Some(8),
        // Packed YUV 4:2:2: two bytes per pixel on average.
        "yuv422" | "uyvy" | "yuyv" | "yuv422_yuy2" => Some(2),
        _ => None,
    };
    if named.is_some() {
        return named;
    }
    // `<bits><U|S|F>C<channels>`, e.g. `16UC1`, `32FC3`.
    let kind_at = encoding.find(['U', 'S', 'F'])?;
    let bits: u64 = encoding[..kind_at].parse().ok()?;
    let rest = &encoding[kind_at + 1..];
    let channels: u64 = rest.strip_prefix('C')?.parse().ok()?;
    let valid = matches!((&encoding[kind_at..=kind_at], bits), ("U" | "S", 8 | 16 | 32) | ("F", 16 | 32 | 64));
    (valid && (1..=4).contains(&channels)).then_some(bits / 8 * channels)
}

/// Checks an image's declared layout against its data before anything is allocated for
/// it: `width × height` at most [`MAX_IMAGE_PIXELS`]; `step × height` within the
/// `data_len` bytes the message holds; and, for an encoding [`bytes_per_pixel`] knows,
/// `step` at least a row of `width` pixels. Products are taken in 64 bits, where two
/// 32-bit fields cannot overflow. The error says what is wrong, in the message's terms.
pub fn check_image_layout(width: u32, height: u32, encoding: &str, step: u32, data_len: u64) -> Result<(), String> {
    let pixels = u64::from(width) * u64::from(height);
    // 0 × 0 is an empty image; 0 × 10⁹ is no image either, but a decoder walking its rows
    // would take a billion steps for nothing (found by fuzzing the camera decoding).
    if (width == 0) != (height == 0) {
        return Err(format!(
            "declares {width} × {height} pixels: an image with rows but no columns, or columns but no rows"
        ));
    }
    if pixels > MAX_IMAGE_PIXELS {
        return Err(format!(
            "declares {width} × {height} = {pixels} pixels, more than the {MAX_IMAGE_PIXELS} an image may have"
        ));
    }
    if let Some(bpp) = bytes_per_pixel(encoding) {
        let row = u64::from(width) * bpp;
        if u64::from(step) < row {
            return Err(format!(
                "step {step} is shorter than a row of {width} {encoding} pixels ({row} bytes at {bpp} a pixel)"
            ));
        }
    }
    let needed = u64::from(step) * u64::from(height);
    if needed > data_len {
        return Err(format!(
            "step {step} × height {height} = {needed} bytes, but the data holds {data_len}: the image is truncated"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_sizes_of_the_usual_encodings() {
        for (e, n) in [
            ("mono8", 1),
            ("8UC1", 1),
            ("mono16", 2),
            ("16UC1", 2),
            ("32FC1", 4),
            ("rgb8", 3),
            ("bgra8", 4),
            ("32FC3", 12),
            ("64FC1", 8),
            ("16SC4", 8),
        ] {
            assert_eq!(bytes_per_pixel(e), Some(n), "{e}");
        }
        for e in ["", "jpeg", "8FC1", "32UC", "16UC0", "16UC5", "UC1", "12UC1", "F"] {
            assert_eq!(bytes_per_pixel(e), None, "{e}");
        }
    }

    #[test]
    fn layouts_are_checked_in_64_bits() {
        assert!(check_image_layout(4, 2, "mono8", 4, 8).is_ok());
        // Padded rows and data longer than needed are fine.
        assert!(check_image_layout(3, 2, "mono16", 8, 20).is_ok());
        assert!(check_image_layout(0, 0, "mono8", 0, 0).is_ok());
        assert!(check_image_layout(0, 1_124_073_476, "16UC1", 0, 0).unwrap_err().contains("rows but no columns"));
        assert!(check_image_layout(640, 0, "mono8", 640, 0).is_err());
        let e = check_image_layout(4, 2, "mono8", 4, 7).unwrap_err();
        assert!(e.contains("= 8 bytes") && e.contains("holds 7"), "{e}");
        let e = check_image_layout(4, 2, "mono16", 7, 100).unwrap_err();
        assert!(e.contains("step 7") && e.contains("8 bytes"), "{e}");
        let e = check_image_layout(u32::MAX, u32::MAX, "mono8", u32::MAX, u64::MAX).unwrap_err();
        assert!(e.contains("pixels"), "{e}");
        // An unknown encoding still has its step × height checked.
        assert!(check_image_layout(2, 2, "weird", 1, 1).is_err());
        assert!(check_image_layout(2, 2, "weird", 1, 2).is_ok());
        let side = 1u32 << 13;
        assert!(check_image_layout(side, side, "mono8", side, u64::from(side) * u64::from(side)).is_ok());
        assert!(check_image_layout(side + 1, side, "mono8", side + 1, u64::MAX).is_err());
    }

    #[test]
    fn payload_choice() {
        assert!(!ImagePayloads::default().wants("/cam"));
        assert!(ImagePayloads::All.wants("/cam"));
        let o = ReadOptions::with_image_topics(["/labels", "/depth"]);
        assert!(o.images.wants("/depth") && !o.images.wants("/rgb"));
    }
}
