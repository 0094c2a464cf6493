//! Opening a log by its content, not its name.

use super::{LogReader, ReadOptions};
use crate::{Error, Location, Result};
use std::fmt;
use std::io::Read;
use std::path::Path;

/// The formats fusemap reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogFormat {
    /// A CARMEN text log, plain or gzipped.
    Carmen,
    /// A ROS 1 bag (v2.0).
    Ros1Bag,
    /// A bare MCAP file.
    Mcap,
    /// A rosbag2 directory (MCAP or SQLite storage), or one of its `.db3` files.
    Rosbag2,
}

impl fmt::Display for LogFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LogFormat::Carmen => "carmen",
            LogFormat::Ros1Bag => "ros1-bag",
            LogFormat::Mcap => "mcap",
            LogFormat::Rosbag2 => "rosbag2",
        })
    }
}

/// An opened log.
pub struct OpenedLog {
    /// What it was recognised as.
    pub format: LogFormat,
    /// Its messages.
    pub reader: Box<dyn LogReader>,
}

/// Recognises the format of `path` by content.
pub fn detect(path: &Path) -> Result<LogFormat> {
    crate::input_file::refuse_special_file(path)?;
    if path.is_dir() {
        if super::ros2::is_rosbag2_dir(path) {
            return Ok(LogFormat::Rosbag2);
        }
        return Err(Error::format(path, Location::File, "a directory, but not a rosbag2 one (no metadata.yaml)"));
    }
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path).and_then(|f| f.take(4096).read_to_end(&mut head)).map_err(|e| Error::io(path, e))?;
    if super::ros1::sniff(&head) {
        Ok(LogFormat::Ros1Bag)
    } else if super::ros2::sniff_mcap(&head) {
        Ok(LogFormat::Mcap)
    } else if head.starts_with(super::ros2::SQLITE_MAGIC) {
        // A rosbag2 `.db3` storage file given on its own.
        Ok(LogFormat::Rosbag2)
    } else if super::carmen::sniff(&head) {
        Ok(LogFormat::Carmen)
    } else if head.is_empty() {
        Err(Error::format(path, Location::File, "the file is empty"))
    } else {
        Err(Error::format(
            path,
            Location::File,
            "not a log fusemap reads (CARMEN text or .gz, ROS 1 bag v2.0, MCAP, or a rosbag2 directory)",
        ))
    }
}

/// Opens `path`, recognising the format by content, with the default
/// [`ReadOptions`]: images are read without their pixels.
pub fn open_log(path: &Path) -> Result<OpenedLog> {
    open_log_with(path, &ReadOptions::default())
}

/// Opens `path`, recognising the format by content; `options` say which images to decode
/// in full (CARMEN logs have none).
pub fn open_log_with(path: &Path, options: &ReadOptions) -> Result<OpenedLog> {
    let format = detect(path)?;
    let reader: Box<dyn LogReader> = match format {
        LogFormat::Carmen => {
            let carmen = super::carmen::CarmenOptions {
                max_line_bytes: Some(options.max_decompressed_bytes),
                max_beams: Some(options.max_scan_beams),
                ..Default::default()
            };
            Box::new(super::carmen::CarmenReader::open(path, carmen)?)
        }
        LogFormat::Ros1Bag => Box::new(super::ros1::BagReader::open_with(path, options.clone())?),
        LogFormat::Mcap | LogFormat::Rosbag2 => Box::new(super::ros2::Ros2Reader::open_with(path, options.clone())?),
    };
    Ok(OpenedLog { format, reader })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn detect_bytes(name: &str, bytes: &[u8]) -> Result<LogFormat> {
        let dir = crate::testdata::temp_dir("detect");
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        detect(&p)
    }

    #[test]
    fn formats_are_recognised_by_content_not_name() {
        assert_eq!(detect_bytes("a.txt", b"#ROSBAG V2.0\n").unwrap(), LogFormat::Ros1Bag);
        assert_eq!(detect_bytes("a.bag", b"\x89MCAP0\r\n").unwrap(), LogFormat::Mcap);
        assert_eq!(detect_bytes("a.mcap", b"SQLite format 3\0rest").unwrap(), LogFormat::Rosbag2);
        assert_eq!(detect_bytes("a.bin", b"ODOM 0 0 0 0 0 0 0 pippo 0\n").unwrap(), LogFormat::Carmen);
        assert!(detect_bytes("a.log", b"").unwrap_err().to_string().contains("empty"));
        assert!(detect_bytes("a.log", &[0xde, 0xad, 0xbe, 0xef]).unwrap_err().to_string().contains("not a log"));
    }
}
