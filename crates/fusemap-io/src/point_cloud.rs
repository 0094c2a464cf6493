//! The map as a point cloud: each occupied cell's centre, for tools that localise and
//! close loops against points (the design document's §4.4 "PCD/PLY"), written as
//! `map.pcd` and `map.ply`; `map.mcap`'s `/map_points` carries the same points.
//!
//! - **PCD** follows PCL's *The PCD (Point Cloud Data) file format*, version 0.7: a text
//!   header (`VERSION`, `FIELDS`, `SIZE`, `TYPE`, `COUNT`, `WIDTH`, `HEIGHT`,
//!   `VIEWPOINT`, `POINTS`, `DATA binary`), then the points as packed little-endian
//!   records. The colour is PCL's `rgb` field: `0x00RRGGBB` stored in the bytes of a
//!   `float32` (`TYPE F`), as `pcl::PointXYZRGB` and CloudCompare read it.
//! - **PLY** follows Turk's PLY format as `plyfile`, Open3D and CloudCompare read it:
//!   `format binary_little_endian 1.0`, one `vertex` element whose properties are
//!   listed in the header in record order, then the records.
//!
//! Fields: `x`, `y`, `z` (`float32`, metres, `z = 0`: the map is planar),
//! `probability` (`float32`, the cell's occupancy probability), and with a semantic
//! layer `class` (`uint16`, the class id label images use; 65535 where the cell has no
//! semantic evidence) and the class colour. Both files are written atomically.

use crate::atomic::write_atomic;
use crate::semantic::{ClassInfo, UNKNOWN_COLOR};
use crate::Result;
use fusemap_core::grid::{Raster, Ternary};
use std::io::Write;
use std::path::Path;

/// The `class` of a point whose cell has no semantic evidence.
pub const NO_CLASS: u16 = u16::MAX;

/// One point of the map's cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPoint {
    /// The cell centre, metres, in the map frame (z = 0).
    pub xyz: [f32; 3],
    /// The cell's occupancy probability.
    pub probability: f32,
    /// Its class id ([`NO_CLASS`] when none), with a semantic layer.
    pub class: u16,
    /// Its class colour ([`UNKNOWN_COLOR`] when none).
    pub rgb: [u8; 3],
}

/// The map's points, and whether they carry classes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapCloud {
    /// The points, in raster order (row 0 = lowest y).
    pub points: Vec<MapPoint>,
    /// Whether `class` and `rgb` mean anything (a run with a semantic layer).
    pub classes: bool,
}

impl MapCloud {
    /// The occupied cells of `raster` (those [`Raster::ternary`] calls occupied, the
    /// black cells of `map.pgm`); `semantic` gives each raster cell's class index into
    /// its class list (−1: none) when the run has a semantic layer.
    pub fn occupied_cells(raster: &Raster, semantic: Option<(&[i16], &[ClassInfo])>) -> Self {
        let occupancy = raster.occupancy();
        let half = 0.5 * raster.resolution;
        let points = raster
            .ternary()
            .iter()
            .enumerate()
            .filter(|(_, t)| **t == Ternary::Occupied)
            .map(|(i, _)| {
                let (col, row) = (i % raster.width, i / raster.width);
                let x = raster.origin.x + col as f64 * raster.resolution + half;
                let y = raster.origin.y + row as f64 * raster.resolution + half;
                let class = semantic.and_then(|(best, classes)| {
                    let b = usize::try_from(*best.get(i)?).ok()?;
                    classes.get(b)
                });
                MapPoint {
                    xyz: [x as f32, y as f32, 0.0],
                    probability: occupancy[i],
                    class: class.map_or(NO_CLASS, |c| c.id),
                    rgb: class.map_or(UNKNOWN_COLOR, |c| c.color),
                }
            })
            .collect();
        Self { points, classes: semantic.is_some() }
    }

    /// Lidar returns as points (`[output] points = "endpoints"`), each with the occupancy
    /// probability of the map cell it lands in (NaN outside the raster); no classes.
    pub fn endpoints(raster: &Raster, points: &[[f32; 2]]) -> Self {
        let occupancy = raster.occupancy();
        let res = raster.resolution;
        let cell = |v: f32, o: f64, n: usize| {
            let i = ((f64::from(v) - o) / res).floor();
            (i >= 0.0 && i < n as f64).then_some(i as usize)
        };
        let points = points
            .iter()
            .map(|&[x, y]| {
                let p = match (cell(x, raster.origin.x, raster.width), cell(y, raster.origin.y, raster.height)) {
                    (Some(c), Some(r)) => occupancy[r * raster.width + c],
                    _ => f32::NAN,
                };
                MapPoint { xyz: [x, y, 0.0], probability: p, class: NO_CLASS, rgb: UNKNOWN_COLOR }
            })
            .collect();
        Self { points, classes: false }
    }

    /// Bytes per `PointCloud2` record: x, y, z, probability, and with classes the class
    /// (2 bytes, then 2 of padding) and the colour — 16 or 24, so every field is aligned.
    pub fn point_step(&self) -> usize {
        if self.classes {
            24
        } else {
            16
        }
    }

    /// The `PointCloud2` records, little-endian, [`point_step`](Self::point_step) bytes
    /// each (the padding after `class` is zero).
    pub fn records(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.points.len() * self.point_step());
        for p in &self.points {
            self.pack(p, &mut out, true);
        }
        out
    }

    /// Appends `p`'s fields, with two zero bytes after `class` when `padded`.
    fn pack(&self, p: &MapPoint, out: &mut Vec<u8>, padded: bool) {
        for v in [p.xyz[0], p.xyz[1], p.xyz[2], p.probability] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        if self.classes {
            out.extend_from_slice(&p.class.to_le_bytes());
            if padded {
                out.extend_from_slice(&[0, 0]);
            }
            out.extend_from_slice(&packed_rgb(p.rgb).to_le_bytes());
        }
    }
}

/// PCL's packed colour: `0x00RRGGBB` as the bits of a `float32`.
fn packed_rgb([r, g, b]: [u8; 3]) -> f32 {
    f32::from_bits(u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b))
}

/// Writes `cloud` as a binary PCD v0.7 file. Binary PCD records are packed, fields back
/// to back as the header lists them (22 bytes a point with classes, 16 without).
pub fn write_pcd(path: &Path, cloud: &MapCloud) -> Result<()> {
    let n = cloud.points.len();
    let (names, sizes, types, counts) = if cloud.classes {
        ("x y z probability class rgb", "4 4 4 4 2 4", "F F F F U F", "1 1 1 1 1 1")
    } else {
        ("x y z probability", "4 4 4 4", "F F F F", "1 1 1 1")
    };
    let header = format!(
        "# .PCD v0.7 - Point Cloud Data file format\n# fusemap map: occupied cell centres, map frame, metres\n\
         VERSION 0.7\nFIELDS {names}\nSIZE {sizes}\nTYPE {types}\nCOUNT {counts}\nWIDTH {n}\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n"
    );
    let mut records = Vec::with_capacity(n * 22);
    for p in &cloud.points {
        cloud.pack(p, &mut records, false);
    }
    write_atomic(path, |w| {
        w.write_all(header.as_bytes())?;
        w.write_all(&records)
    })
}

/// Writes `cloud` as a binary little-endian PLY file: one `vertex` element.
pub fn write_ply(path: &Path, cloud: &MapCloud) -> Result<()> {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment fusemap map: occupied cell centres, map frame, metres\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float probability\n",
        cloud.points.len()
    );
    if cloud.classes {
        header.push_str("property ushort class\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    header.push_str("end_header\n");
    write_atomic(path, |w| {
        w.write_all(header.as_bytes())?;
        for p in &cloud.points {
            for v in [p.xyz[0], p.xyz[1], p.xyz[2], p.probability] {
                w.write_all(&v.to_le_bytes())?;
            }
            if cloud.classes {
                w.write_all(&p.class.to_le_bytes())?;
                w.write_all(&p.rgb)?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raster() -> Raster {
        // 3 × 2 cells of 0.5 m at (10, 20): occupied at (col 1, row 0) and (col 2, row 1).
        crate::testdata::raster_3x2([0.2, 0.9, 0.5, 0.3, 0.4, 0.95], [true; 6])
    }

    #[test]
    fn occupied_cells_become_their_centres() {
        let cloud = MapCloud::occupied_cells(&raster(), None);
        let xy: Vec<[f32; 3]> = cloud.points.iter().map(|p| p.xyz).collect();
        assert_eq!(xy, vec![[10.75, 20.25, 0.0], [11.25, 20.75, 0.0]]);
        assert!((cloud.points[0].probability - 0.9).abs() < 1e-6);
        assert_eq!(cloud.records().len(), 2 * 16);
    }

    #[test]
    fn classes_carry_their_id_and_colour() {
        let classes = [ClassInfo { id: 7, name: "wall".into(), color: [1, 2, 3] }];
        let best = [-1, 0, -1, -1, -1, -1];
        let cloud = MapCloud::occupied_cells(&raster(), Some((&best, &classes)));
        assert_eq!((cloud.points[0].class, cloud.points[0].rgb), (7, [1, 2, 3]));
        assert_eq!((cloud.points[1].class, cloud.points[1].rgb), (NO_CLASS, UNKNOWN_COLOR));
        let r = cloud.records();
        assert_eq!(r.len(), 48);
        assert_eq!(&r[16..20], &[7, 0, 0, 0]);
        assert_eq!(u32::from_le_bytes(r[20..24].try_into().unwrap()), 0x010203);
    }

    #[test]
    fn pcd_and_ply_headers_describe_their_records() {
        let dir = tempfile::tempdir().unwrap();
        let classes = [ClassInfo { id: 7, name: "wall".into(), color: [1, 2, 3] }];
        let best = [-1, 0, -1, -1, -1, -1];
        let cloud = MapCloud::occupied_cells(&raster(), Some((&best, &classes)));
        let (pcd, ply) = (dir.path().join("m.pcd"), dir.path().join("m.ply"));
        write_pcd(&pcd, &cloud).unwrap();
        write_ply(&ply, &cloud).unwrap();
        let bytes = std::fs::read(&pcd).unwrap();
        let at = bytes.windows(12).position(|w| w == b"DATA binary\n").unwrap() + 12;
        let head = String::from_utf8_lossy(&bytes[..at]);
        assert!(head.contains("POINTS 2\n") && head.contains("WIDTH 2\n"), "{head}");
        let sizes: usize = head
            .lines()
            .find_map(|l| l.strip_prefix("SIZE "))
            .unwrap()
            .split(' ')
            .zip(head.lines().find_map(|l| l.strip_prefix("COUNT ")).unwrap().split(' '))
            .map(|(s, c)| s.parse::<usize>().unwrap() * c.parse::<usize>().unwrap())
            .sum();
        assert_eq!(sizes, 22);
        assert_eq!(bytes.len() - at, 2 * sizes);
        assert_eq!(&bytes[at + 16..at + 18], &[7, 0]);
        let bytes = std::fs::read(&ply).unwrap();
        let at = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        // float ×4, ushort, uchar ×3 = 21 bytes a vertex, no padding.
        assert_eq!(bytes.len() - at, 2 * 21);
        assert_eq!(&bytes[at + 16..at + 21], &[7, 0, 1, 2, 3]);
    }
}
