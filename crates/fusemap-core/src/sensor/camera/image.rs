//! Decoded camera images: what a reader hands the camera model, independent of the
//! message encoding (`mono8`/`mono16` labels, `32FC1`/`16UC1` depth).

/// Why a decoded image cannot be built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// The pixel buffer does not hold `width × height` pixels.
    #[error("a {width}×{height} image needs {expected} pixels, the buffer holds {actual}")]
    Size {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
        /// `width × height`.
        expected: u64,
        /// Pixels given.
        actual: u64,
    },
}

fn check(width: u32, height: u32, actual: usize) -> Result<(), ImageError> {
    let expected = width as u64 * height as u64;
    if expected != actual as u64 {
        return Err(ImageError::Size { width, height, expected, actual: actual as u64 });
    }
    Ok(())
}

/// A row-major class-label image: one class id per pixel, row 0 at the top (as
/// `sensor_msgs/Image` stores it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Class ids, `width × height`, row-major.
    pub labels: Vec<u16>,
}

impl LabelImage {
    /// An image from its pixels; refuses a buffer of the wrong size.
    pub fn new(width: u32, height: u32, labels: Vec<u16>) -> Result<Self, ImageError> {
        check(width, height, labels.len())?;
        Ok(Self { width, height, labels })
    }

    /// The label at column `u`, row `v` (both in range).
    #[inline]
    pub fn at(&self, u: u32, v: u32) -> u16 {
        self.labels[v as usize * self.width as usize + u as usize]
    }
}

/// A row-major depth image in metres along the optical axis (the `z` of the optical
/// frame, REP 103), row 0 at the top. NaN, ±inf, 0 and negative values mean "no depth".
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Depth per pixel, metres, `width × height`, row-major.
    pub metres: Vec<f32>,
}

impl DepthImage {
    /// An image from its pixels; refuses a buffer of the wrong size.
    pub fn new(width: u32, height: u32, metres: Vec<f32>) -> Result<Self, ImageError> {
        check(width, height, metres.len())?;
        Ok(Self { width, height, metres })
    }

    /// The depth at column `u`, row `v` (both in range).
    #[inline]
    pub fn at(&self, u: u32, v: u32) -> f32 {
        self.metres[v as usize * self.width as usize + u as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked() {
        assert!(LabelImage::new(3, 2, vec![0; 6]).is_ok());
        let e = LabelImage::new(3, 2, vec![0; 5]).unwrap_err();
        assert_eq!(e, ImageError::Size { width: 3, height: 2, expected: 6, actual: 5 });
        let d = DepthImage::new(2, 2, vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(d.at(1, 1), 4.0);
        assert!(DepthImage::new(u32::MAX, 2, vec![]).is_err());
    }
}
