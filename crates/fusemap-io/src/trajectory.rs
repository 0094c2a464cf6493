//! Trajectories in the TUM format (Sturm et al. 2012, the RGB-D benchmark; read by the
//! `evo` tool): one pose a line, `timestamp tx ty tz qx qy qz qw`, timestamp in seconds,
//! `#` comments. A planar pose is written with z = 0 and the rotation about z.

use crate::atomic::write_atomic;
use crate::input_file::read_text_within;
use crate::{Error, Location, Result};
use fusemap_core::geometry::{quaternion_yaw, Pose2};
use fusemap_core::time::Stamp;
use std::io::Write;
use std::path::Path;

/// Writes `poses` (`map_from_base`, time order) to `path` atomically.
pub fn write_tum(path: &Path, poses: &[(Stamp, Pose2)]) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "# timestamp tx ty tz qx qy qz qw (map_from_base, written by fusemap)")?;
        for (t, p) in poses {
            let (s, c) = (p.theta / 2.0).sin_cos();
            let (sign, a) = if t.0 < 0 { ("-", t.0.unsigned_abs()) } else { ("", t.0.unsigned_abs()) };
            // Nine decimals: the nanosecond stamp survives the round trip.
            writeln!(
                w,
                "{sign}{}.{:09} {:.6} {:.6} 0 0 0 {:.9} {:.9}",
                a / 1_000_000_000,
                a % 1_000_000_000,
                p.x,
                p.y,
                s,
                c
            )?;
        }
        Ok(())
    })
}

/// The largest TUM trajectory read, bytes: a day of poses at 100 Hz.
pub const MAX_TUM_BYTES: u64 = 1 << 30;

/// Reads a TUM trajectory as planar poses (yaw from the quaternion).
pub fn read_tum(path: &Path) -> Result<Vec<(Stamp, Pose2)>> {
    let text = read_text_within(path, MAX_TUM_BYTES, "a TUM trajectory")?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        let bad = |what: &str| Error::format(path, Location::Line(i as u64 + 1), what.to_string());
        if f.len() != 8 {
            return Err(bad(&format!("expected 8 fields (t x y z qx qy qz qw), got {}", f.len())));
        }
        let stamp =
            Stamp::parse_decimal(f[0]).ok_or_else(|| bad("the timestamp is not a decimal number of seconds"))?;
        let mut v = [0.0; 7];
        for (k, s) in f[1..].iter().enumerate() {
            v[k] = s.parse().map_err(|_| bad(&format!("field {} is not a number: `{s}`", k + 2)))?;
        }
        let yaw = quaternion_yaw([v[3], v[4], v[5], v[6]]);
        let p = Pose2::new(v[0], v[1], yaw);
        if !p.is_finite() {
            return Err(bad("the pose is not finite (NaN or a zero quaternion)"));
        }
        out.push((stamp, p));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_stamps_and_poses() {
        let dir = crate::testdata::temp_dir("tum");
        let p = dir.join("t.tum");
        let poses = vec![
            (Stamp(1_700_000_000_123_456_789), Pose2::new(1.5, -2.25, 3.0)),
            (Stamp(-500_000_000), Pose2::new(0.0, 0.0, -1.0)),
        ];
        write_tum(&p, &poses).unwrap();
        let back = read_tum(&p).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in poses.iter().zip(&back) {
            assert_eq!(a.0, b.0);
            assert!((a.1.x - b.1.x).abs() < 1e-6 && (a.1.y - b.1.y).abs() < 1e-6);
            assert!((a.1.theta - b.1.theta).abs() < 1e-8);
        }
        std::fs::write(&p, "1.0 0 0 0 0 0 0\n").unwrap();
        assert!(read_tum(&p).unwrap_err().to_string().contains(":1: expected 8 fields"));
    }
}
