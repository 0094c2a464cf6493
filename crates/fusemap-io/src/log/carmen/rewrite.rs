//! A CARMEN log with its poses replaced: how a test bench turns a corrected log into a raw
//! one with odometry of a known error.
//!
//! A corrected log (GMapping's output written back, `PROVENANCE.md` §1) holds the
//! corrected pose in both pose fields of every `FLASER` line, odometry re-anchored to the
//! last corrected pose on its `ODOM` lines, and a `NEFF` line (GMapping's effective
//! particle count) after every scan. [`PoseLog::read`] collects those poses in file order;
//! [`PoseLog::write`] writes the log again with other poses in both fields of every scan
//! line and on every `ODOM` line, with the `NEFF` lines left out (they are what marks a log
//! as corrected), optionally with stamps that tell every message apart. Everything else,
//! the ranges above all, is copied as written.

use crate::bounded::read_to_end_bounded;
use crate::{Error, Location, Result};
use flate2::read::MultiGzDecoder;
use fusemap_core::geometry::Pose2;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// What a pose line is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseLineKind {
    /// A `FLASER` scan (pose and odometry fields).
    Scan,
    /// An `ODOM` line.
    Odometry,
}

/// One pose-carrying line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseLine {
    /// Index into the log's lines.
    pub line: usize,
    /// Scan or odometry.
    pub kind: PoseLineKind,
    /// The pose written on it (for a scan, the first pose field).
    pub pose: Pose2,
    /// Its IPC stamp as written, seconds.
    pub stamp_s: f64,
}

/// A CARMEN log's lines, and its pose lines in file order.
pub struct PoseLog {
    path: PathBuf,
    lines: Vec<String>,
    /// The pose lines, in file order.
    pub poses: Vec<PoseLine>,
}

/// Field positions of a pose line: the pose fields to replace, and the two stamps.
fn layout(fields: &[&str]) -> Option<(PoseLineKind, Vec<usize>, [usize; 2])> {
    match *fields.first()? {
        "FLASER" => {
            let n: usize = fields.get(1)?.parse().ok()?;
            let p = 2 + n;
            (fields.len() == p + 9).then(|| (PoseLineKind::Scan, (p..p + 6).collect(), [p + 6, p + 8]))
        }
        "ODOM" => (fields.len() == 10).then(|| (PoseLineKind::Odometry, vec![1, 2, 3], [7, 9])),
        _ => None,
    }
}

impl PoseLog {
    /// Reads a CARMEN log (plain or gzipped) of at most `limit_bytes` of text.
    pub fn read(path: &Path, limit_bytes: u64) -> Result<Self> {
        let io = |source| Error::Io { path: path.to_path_buf(), source };
        let file = std::fs::File::open(path).map_err(io)?;
        let mut raw = Vec::new();
        let mut head = [0u8; 2];
        let mut reader = std::io::BufReader::new(file);
        let n = reader.read(&mut head).map_err(io)?;
        let chained = std::io::Cursor::new(head[..n].to_vec()).chain(reader);
        let bounded = if head[..n] == [0x1f, 0x8b] {
            read_to_end_bounded(MultiGzDecoder::new(chained), limit_bytes, &mut raw)
        } else {
            read_to_end_bounded(chained, limit_bytes, &mut raw)
        }
        .map_err(io)?;
        let format = |location, message: String| Error::Format { path: path.to_path_buf(), location, message };
        if bounded == crate::bounded::Bounded::OverLimit {
            return Err(format(Location::File, format!("more than {limit_bytes} bytes of text")));
        }
        let text = String::from_utf8(raw).map_err(|e| format(Location::File, format!("not UTF-8 text: {e}")))?;
        let lines: Vec<String> = text.lines().map(str::to_owned).collect();
        let mut poses = Vec::new();
        for (i, l) in lines.iter().enumerate() {
            let fields: Vec<&str> = l.split_ascii_whitespace().collect();
            let Some((kind, at, [stamp, _])) = layout(&fields) else { continue };
            let number = |k: usize| fields[k].parse::<f64>().ok().filter(|v| v.is_finite());
            let (Some(x), Some(y), Some(theta), Some(stamp_s)) =
                (number(at[0]), number(at[1]), number(at[2]), number(stamp))
            else {
                return Err(format(Location::Line(i as u64 + 1), "a pose or stamp that is not a finite number".into()));
            };
            poses.push(PoseLine { line: i, kind, pose: Pose2::new(x, y, theta), stamp_s });
        }
        Ok(Self { path: path.to_path_buf(), lines, poses })
    }

    /// The file it was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the log to `out` with `poses[k]` on pose line `k` (both pose fields of a
    /// scan), no `NEFF` lines, and with `period_s` every pose line stamped `k × period_s`
    /// (IPC and logger stamps alike) instead of its own stamp.
    ///
    /// # Panics
    /// When `poses` is not one pose per pose line.
    pub fn write(&self, poses: &[Pose2], period_s: Option<f64>, out: &Path) -> Result<()> {
        assert_eq!(poses.len(), self.poses.len(), "one pose per pose line");
        let mut next = self.poses.iter().zip(poses).enumerate().peekable();
        let mut text = String::with_capacity(self.lines.iter().map(|l| l.len() + 1).sum());
        for (i, l) in self.lines.iter().enumerate() {
            if l.split_ascii_whitespace().next() == Some("NEFF") {
                continue;
            }
            let Some((k, (line, pose))) = next.next_if(|(_, (p, _))| p.line == i) else {
                text.push_str(l);
                text.push('\n');
                continue;
            };
            let mut fields: Vec<String> = l.split_ascii_whitespace().map(str::to_owned).collect();
            let (_, at, stamps) =
                layout(&fields.iter().map(String::as_str).collect::<Vec<_>>()).expect("a pose line when read");
            let values = [pose.x, pose.y, pose.theta];
            for (slot, &f) in at.iter().enumerate() {
                fields[f] = format!("{:.6}", values[slot % 3]);
            }
            if let Some(p) = period_s {
                stamps.iter().for_each(|&f| fields[f] = format!("{:.6}", k as f64 * p));
            }
            debug_assert_eq!(line.line, i);
            text.push_str(&fields.join(" "));
            text.push('\n');
        }
        let io = |source| Error::Io { path: out.to_path_buf(), source };
        let mut f = std::fs::File::create(out).map_err(io)?;
        f.write_all(text.as_bytes()).map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &str = "# comment\nPARAM robot_x 1\nFLASER 3 1.0 2.0 3.0 0.5 0.25 0.1 0.5 0.25 0.1 12.5 pippo 12.5\nODOM 0.5 0.25 0.1 0 0 0 12.6 pippo 12.6\nNEFF 15\nODOM 0.7 0.25 0.1 0 0 0 12.7 pippo 12.7\n";

    #[test]
    fn poses_are_replaced_neff_dropped_and_the_rest_kept() {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("in.log");
        std::fs::write(&src, LOG).unwrap();
        let log = PoseLog::read(&src, 1 << 20).unwrap();
        assert_eq!(log.poses.len(), 3);
        assert_eq!(log.poses[0].kind, PoseLineKind::Scan);
        assert_eq!(log.poses[0].pose, Pose2::new(0.5, 0.25, 0.1));
        assert_eq!(log.poses[2].stamp_s, 12.7);
        let out = dir.path().join("out.log");
        let new = [Pose2::new(9.0, 8.0, 0.5), Pose2::new(1.0, 2.0, 3.0), Pose2::new(-1.0, 0.0, 0.0)];
        log.write(&new, None, &out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(!text.contains("NEFF"));
        assert!(
            text.contains("FLASER 3 1.0 2.0 3.0 9.000000 8.000000 0.500000 9.000000 8.000000 0.500000 12.5 pippo 12.5")
        );
        assert!(text.contains("ODOM -1.000000 0.000000 0.000000 0 0 0 12.7 pippo 12.7"));
        assert!(text.starts_with("# comment\nPARAM robot_x 1\n"));
        log.write(&new, Some(0.1), &out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("ODOM -1.000000 0.000000 0.000000 0 0 0 0.200000 pippo 0.200000"), "{text}");
        // A pose that is not a number is an error naming the line.
        std::fs::write(&src, "ODOM x 0 0 0 0 0 1 h 1\n").unwrap();
        let e = PoseLog::read(&src, 1 << 20).err().unwrap().to_string();
        assert!(e.contains("in.log:1: a pose"), "{e}");
    }
}
