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
//! allocated for its pixels: a message whose declared sizes do not fit its data is a
//! malformed message (counted and skipped by callers like any other payload that does
//! not decode), never a panic or an allocation sized by a header field. An image whose
//! pixels are wanted must also stay within [`ReadOptions::max_image_pixels`]
//! (`[limits] image_pixels`), which bounds what a consumer allocates to decode it.

use super::LogMessage;
use fusemap_core::config::LimitsConfig;
use fusemap_core::time::Stamp;
use std::collections::BTreeSet;

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
/// one piece of it may grow (`[limits]`, [`ReadOptions::within`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadOptions {
    /// The images whose pixels are decoded.
    pub images: ImagePayloads,
    /// The most bytes one chunk, message or line may hold once decompressed (ROS 1 bz2 and
    /// lz4 chunks, MCAP records, rosbag2 zstd messages, CARMEN lines): a decompression bomb
    /// or a corrupt size is refused at that point, not after the memory is taken.
    pub max_decompressed_bytes: u64,
    /// The most beams one scan may hold (`[limits] beams_per_scan`). A scan's ranges are
    /// already bounded by its message's bytes; this bounds the per-beam work and buffers
    /// of everything downstream (points, de-skew, matching), checked as the scan is read.
    pub max_scan_beams: u64,
    /// The most pixels (`width × height`) of an image whose pixels are decoded
    /// (`[limits] image_pixels`): it bounds what the camera model allocates per image.
    /// Header-only images take no pixel memory and are not held to it.
    pub max_image_pixels: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self::within(&LimitsConfig::default())
    }
}

impl ReadOptions {
    /// Options within `limits` (`decompressed_mib`, `beams_per_scan`, `image_pixels`),
    /// decoding no image's pixels.
    pub fn within(limits: &LimitsConfig) -> Self {
        Self {
            images: ImagePayloads::default(),
            max_decompressed_bytes: limits.decompressed_bytes(),
            max_scan_beams: limits.beams_per_scan,
            max_image_pixels: limits.image_pixels,
        }
    }

    /// Options that decode the pixels of the images of `topics`.
    pub fn with_image_topics<I, S>(topics: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        Self::default().images_of(topics)
    }

    /// These options, decoding the pixels of the images of `topics` (and no others).
    pub fn images_of<I, S>(self, topics: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        Self { images: ImagePayloads::Topics(topics.into_iter().map(Into::into).collect()), ..self }
    }

    /// The budget a decoded message breaks, if any, in words that name the value met, the
    /// limit and the key that raises it. Readers turn it into [`crate::Error::Limit`]
    /// at the message: never a skip, for a limit that dropped scans silently would hide
    /// that the budget is too small for the log.
    pub fn over_limit(&self, message: &LogMessage) -> Option<String> {
        match message {
            LogMessage::Scan(s) => scan_over_limit(s.scan.ranges.len(), self.max_scan_beams),
            LogMessage::Image(i) => image_over_limit(i.width, i.height, self.max_image_pixels),
            _ => None,
        }
    }
}

/// The words for a `width` × `height` image past a limit of `max` pixels, if it is.
pub fn image_over_limit(width: u32, height: u32, max: u64) -> Option<String> {
    let pixels = u64::from(width) * u64::from(height);
    (pixels > max).then(|| {
        format!(
            "a {width} × {height} image is {pixels} pixels, over the limit of {max} (limits.image_pixels raises it)"
        )
    })
}

/// The words for a scan of `beams` beams past a limit of `max`, if it is.
pub(crate) fn scan_over_limit(beams: usize, max: u64) -> Option<String> {
    (beams as u64 > max)
        .then(|| format!("a scan of {beams} beams, over the limit of {max} (limits.beams_per_scan raises it)"))
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
/// it: rows and columns both or neither; `step × height` within the
/// `data_len` bytes the message holds; and, for an encoding [`bytes_per_pixel`] knows,
/// `step` at least a row of `width` pixels. Products are taken in 64 bits, where two
/// 32-bit fields cannot overflow. The error says what is wrong, in the message's terms.
pub fn check_image_layout(width: u32, height: u32, encoding: &str, step: u32, data_len: u64) -> Result<(), String> {
    // 0 × 0 is an empty image; 0 × 10⁹ is no image either, but a decoder walking its rows
    // would take a billion steps for nothing (found by fuzzing the camera decoding).
    if (width == 0) != (height == 0) {
        return Err(format!(
            "declares {width} × {height} pixels: an image with rows but no columns, or columns but no rows"
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
        // 64-bit products: two 32-bit fields cannot overflow them.
        assert!(check_image_layout(u32::MAX, u32::MAX, "mono8", u32::MAX, 1 << 40).unwrap_err().contains("truncated"));
        // An unknown encoding still has its step × height checked.
        assert!(check_image_layout(2, 2, "weird", 1, 1).is_err());
        assert!(check_image_layout(2, 2, "weird", 1, 2).is_ok());
    }

    fn image(width: u32, height: u32) -> LogMessage {
        LogMessage::Image(ImageMessage {
            topic: "/depth".into(),
            stamp: Stamp::from_sec_nsec(0, 0),
            receive_stamp: None,
            frame_id: "cam".into(),
            width,
            height,
            encoding: "mono8".into(),
            is_bigendian: false,
            step: width,
            data: Vec::new(),
        })
    }

    #[test]
    fn images_past_the_pixel_budget_name_the_key() {
        let limits = LimitsConfig { image_pixels: 100, ..Default::default() };
        let options = ReadOptions::within(&limits);
        assert_eq!(options.over_limit(&image(10, 10)), None);
        let e = options.over_limit(&image(101, 1)).unwrap();
        for part in ["101 × 1", "101 pixels", "limit of 100", "limits.image_pixels"] {
            assert!(e.contains(part), "{part}: {e}");
        }
        // The default is an 8192 × 8192 image.
        let side = 1u32 << 13;
        assert_eq!(ReadOptions::default().over_limit(&image(side, side)), None);
        assert!(ReadOptions::default().over_limit(&image(side + 1, side)).is_some());
    }

    #[test]
    fn payload_choice() {
        assert!(!ImagePayloads::default().wants("/cam"));
        assert!(ImagePayloads::All.wants("/cam"));
        let o = ReadOptions::with_image_topics(["/labels", "/depth"]);
        assert!(o.images.wants("/depth") && !o.images.wants("/rgb"));
    }
}
