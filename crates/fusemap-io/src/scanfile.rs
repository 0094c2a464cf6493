//! The benchmark scan file of the project's baselines (`SCAN2D01`): the same simulated
//! scans fed to fusemap, the design document's numpy pipeline, OctoMap and a bare C loop,
//! so their throughput is compared on identical input.
//!
//! Little endian: 8 bytes magic `SCAN2D01`; `i64` n_scans, n_beams, grid_width,
//! grid_height; `f64` angle_min, angle_increment, range_min, range_max, resolution,
//! origin_x, origin_y; then n_scans records of (n_beams + 3) `f64`: x, y, θ, ranges.

use crate::{Error, Location, Result};
use fusemap_core::geometry::Pose2;
use std::io::Read;
use std::path::Path;

/// The contents of a scan file.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanFile {
    /// Beams per scan.
    pub beams: usize,
    /// Angle of beam 0, radians.
    pub angle_min: f64,
    /// Angle between beams, radians.
    pub angle_increment: f64,
    /// Shortest valid range, metres.
    pub range_min: f64,
    /// Longest valid range (exclusive), metres.
    pub range_max: f64,
    /// Cell size of the baselines' grid, metres.
    pub resolution: f64,
    /// Lower-left corner of the baselines' grid, metres.
    pub origin: [f64; 2],
    /// `world_from_base` of each scan.
    pub poses: Vec<Pose2>,
    /// Ranges, `beams` per scan, as `f32` (the precision of `sensor_msgs/LaserScan`).
    pub ranges: Vec<f32>,
}

const MAGIC: &[u8; 8] = b"SCAN2D01";
const HEADER: usize = 8 + 4 * 8 + 7 * 8;

/// Reads a scan file.
pub fn read_scanfile(path: &Path) -> Result<ScanFile> {
    let mut bytes = Vec::new();
    std::fs::File::open(path).and_then(|mut f| f.read_to_end(&mut bytes)).map_err(|e| Error::io(path, e))?;
    let bad = |at: u64, m: &str| Error::format(path, Location::Offset(at), m);
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err(bad(0, "not a SCAN2D01 scan file"));
    }
    let i64_at = |o: usize| i64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or([0; 8]));
    let f64_at = |o: usize| f64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or([0; 8]));
    let (n_scans, n_beams) = (i64_at(8), i64_at(16));
    if n_scans < 0 || !(1..=1_000_000).contains(&n_beams) {
        return Err(bad(8, "implausible scan or beam count"));
    }
    let (n_scans, n_beams) = (n_scans as usize, n_beams as usize);
    let d = |k: usize| f64_at(40 + 8 * k);
    let record = (n_beams + 3) * 8;
    let need = n_scans.checked_mul(record).and_then(|v| v.checked_add(HEADER));
    if need != Some(bytes.len()) {
        return Err(bad(HEADER as u64, "file size does not match the header's scan and beam counts"));
    }
    let mut poses = Vec::with_capacity(n_scans);
    let mut ranges = Vec::with_capacity(n_scans * n_beams);
    for s in 0..n_scans {
        let base = HEADER + s * record;
        poses.push(Pose2::new(f64_at(base), f64_at(base + 8), f64_at(base + 16)));
        ranges.extend((0..n_beams).map(|b| f64_at(base + 24 + 8 * b) as f32));
    }
    Ok(ScanFile {
        beams: n_beams,
        angle_min: d(0),
        angle_increment: d(1),
        range_min: d(2),
        range_max: d(3),
        resolution: d(4),
        origin: [d(5), d(6)],
        poses,
        ranges,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let dir = crate::testdata::temp_dir("scanfile");
        let p = dir.join("a.scan");
        let b = crate::testdata::tiny_scanfile_bytes();
        assert_eq!(&b[..8], MAGIC);
        std::fs::write(&p, &b).unwrap();
        let f = read_scanfile(&p).unwrap();
        assert_eq!(f.beams, 3);
        assert_eq!(f.poses[1], Pose2::new(4.0, 5.0, 6.0));
        assert_eq!(f.ranges, vec![1.0, 2.0, 3.0, 7.0, 8.0, 9.0]);
        assert_eq!(f.origin, [-5.0, -5.0]);
        std::fs::write(&p, &b[..b.len() - 1]).unwrap();
        assert!(read_scanfile(&p).unwrap_err().to_string().contains("does not match"));
        std::fs::write(&p, b"garbage").unwrap();
        assert!(read_scanfile(&p).unwrap_err().to_string().contains("not a SCAN2D01"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
