//! ROS 2 logs in: bare `.mcap` files and rosbag2 directories (`metadata.yaml` beside
//! MCAP or SQLite `.db3` storage files), with CDR-encoded messages.
//!
//! The containers (MCAP files, SQLite `.db3` files, [`rosbag2`] directories of either)
//! yield raw messages with their topic, type name, encoding and log time; one
//! [`Ros2Reader`] decodes those fusemap uses (`sensor_msgs/msg/LaserScan`,
//! `nav_msgs/msg/Odometry`, `tf2_msgs/msg/TFMessage`, `sensor_msgs/msg/Imu`,
//! `sensor_msgs/msg/NavSatFix`, `geometry_msgs/msg/PoseWithCovarianceStamped`,
//! `sensor_msgs/msg/Image`, `sensor_msgs/msg/CameraInfo`; see [`cdr`] and [`msgs`]) into
//! [`LogMessage`]s and counts the rest in
//! [`ReadStats::skipped_by_type`]. A message whose payload does not decode is an
//! [`Error::Format`] at [`Location::Message`] (file, 1-based index in the log, topic),
//! and reading can go on with the next one ([`Error::is_skippable`]); a container error
//! (a truncated or corrupt file) ends the log.
//!
//! Every message gets its container's log time as `receive_stamp` (MCAP `log_time`,
//! `.db3` `timestamp`); the header stamp is passed on as written.
//!
//! Payloads are decoded where the container holds them (MCAP's chunk buffer, SQLite's
//! row), never copied first; an image's pixels are copied only for the topics
//! [`ReadOptions::images`] names, every other image is an [`ImageHeader`](crate::log::ImageHeader).
//!
//! ```no_run
//! use fusemap_io::log::ros2::open_ros2;
//! use fusemap_io::log::LogMessage;
//!
//! # fn main() -> fusemap_io::Result<()> {
//! let mut log = open_ros2("run1/".as_ref())?; // a rosbag2 directory or a .mcap file
//! while let Some(message) = log.next_message() {
//!     if let LogMessage::Scan(scan) = message? {
//!         println!("{} beams at {:?}", scan.scan.ranges.len(), scan.scan.stamp);
//!     }
//! }
//! println!("skipped: {:?}", log.stats().skipped_by_type);
//! # Ok(())
//! # }
//! ```

pub mod cdr;
mod db3;
mod decode;
mod mcap_reader;
pub mod msgs;
pub mod rosbag2;
pub mod writer;

use crate::error::{Error, Location, Result};
use crate::log::{LogMessage, LogReader, ReadOptions, ReadStats};
pub(crate) use decode::On;
pub use decode::{decode_known, decode_known_with, decode_message, KnownType};
use fusemap_core::time::Stamp;
use std::collections::VecDeque;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The 8 bytes every MCAP file starts (and ends) with.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// The 16 bytes every SQLite 3 database starts with.
pub const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// True when `first_bytes` (at least the first 8 bytes of a file) start with the MCAP magic.
pub fn sniff_mcap(first_bytes: &[u8]) -> bool {
    first_bytes.starts_with(MCAP_MAGIC)
}

/// True when `path` is a directory holding a `metadata.yaml` (a rosbag2 bag).
pub fn is_rosbag2_dir(path: &Path) -> bool {
    path.is_dir() && path.join(rosbag2::METADATA_FILE).is_file()
}

/// Opens a ROS 2 log: a rosbag2 directory (or its `metadata.yaml`), a bare `.mcap` file,
/// or a bare rosbag2 `.db3` file, told apart by their content rather than their names.
pub fn open_ros2(path: &Path) -> Result<Box<dyn LogReader>> {
    Ok(Box::new(Ros2Reader::open(path)?))
}

/// A topic as a container declares it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Topic {
    /// Topic name (`/scan`).
    pub name: String,
    /// ROS type name (`sensor_msgs/msg/LaserScan`), empty when the container has none.
    pub type_name: String,
    /// Serialisation (`cdr`).
    pub encoding: String,
}

/// One message as a container stores it.
pub(crate) struct RawMessage<'a> {
    /// The storage file it is in.
    pub path: &'a Path,
    pub topic: &'a Topic,
    pub log_time: Stamp,
    pub data: &'a [u8],
}

/// A storage file that yields raw messages in its order.
pub(crate) trait Source {
    /// Hands the next message to `visit`, its payload borrowed from where the container
    /// holds it (so an unwanted payload is never copied); `index` is its 1-based position
    /// in the whole log, for errors. `None` at the end of the storage, `Some(Err)` for an
    /// error of the container (which ends the log).
    fn next_raw(&mut self, index: u64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Option<Result<()>>;
}

/// Storage that is opened when the reader reaches it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum PendingFile {
    /// An MCAP file, whole-file zstd-compressed when `zstd` (rosbag2 `file` compression).
    Mcap { path: PathBuf, zstd: bool },
    /// A SQLite3 rosbag2 storage file.
    Db3 { path: PathBuf },
}

impl PendingFile {
    fn open(&self, max_record: u64) -> Result<Box<dyn Source + Send>> {
        Ok(match self {
            PendingFile::Mcap { path, zstd } => Box::new(mcap_reader::McapSource::open(path, *zstd, max_record)?),
            PendingFile::Db3 { path } => Box::new(db3::Db3Source::open(path, max_record)?),
        })
    }
}

/// Reads a ROS 2 log (one or more storage files) as [`LogMessage`]s in storage order:
/// MCAP files in file order, `.db3` files by timestamp, the files of a rosbag2 directory
/// one after another as `metadata.yaml` lists them.
pub struct Ros2Reader {
    pending: VecDeque<PendingFile>,
    current: Option<Box<dyn Source + Send>>,
    /// rosbag2 `message` compression: every payload is a zstd frame.
    zstd_messages: bool,
    index: u64,
    stats: ReadStats,
    finished: bool,
    scratch: Vec<u8>,
    options: ReadOptions,
}

impl Ros2Reader {
    /// Opens a rosbag2 directory (or its `metadata.yaml`), a `.mcap` or a `.db3` file.
    pub fn open(path: &Path) -> Result<Self> {
        Self::open_with(path, ReadOptions::default())
    }

    /// [`Ros2Reader::open`] with `options` (which images to decode in full).
    pub fn open_with(path: &Path, options: ReadOptions) -> Result<Self> {
        let mut reader = Self::open_any(path)?;
        reader.options = options;
        Ok(reader)
    }

    /// Decodes the images `options` name in full from now on (the decompression limit
    /// applies from the next storage file on).
    pub fn set_options(&mut self, options: ReadOptions) {
        self.options = options;
    }

    fn open_any(path: &Path) -> Result<Self> {
        if path.is_dir() {
            return Self::open_rosbag2(path);
        }
        if path.file_name().is_some_and(|n| n == rosbag2::METADATA_FILE) {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            return Self::open_rosbag2(dir);
        }
        let mut head = [0u8; 16];
        let n = read_head(path, &mut head)?;
        let head = &head[..n];
        if sniff_mcap(head) {
            Self::open_mcap(path)
        } else if head.starts_with(SQLITE_MAGIC) {
            Self::open_db3(path)
        } else {
            Err(Error::format(
                path,
                Location::File,
                format!(
                    "neither an MCAP file (which starts with \\x89MCAP0\\r\\n) nor a rosbag2 \
                     SQLite file; the first bytes are {}",
                    hex(head)
                ),
            ))
        }
    }

    /// Opens a bare MCAP file.
    pub fn open_mcap(path: &Path) -> Result<Self> {
        Self::from_files(vec![PendingFile::Mcap { path: path.to_path_buf(), zstd: false }], false)
    }

    /// Opens a bare rosbag2 SQLite storage file (its `topics` table names the types).
    pub fn open_db3(path: &Path) -> Result<Self> {
        Self::from_files(vec![PendingFile::Db3 { path: path.to_path_buf() }], false)
    }

    /// Opens a rosbag2 directory as its `metadata.yaml` describes it.
    pub fn open_rosbag2(dir: &Path) -> Result<Self> {
        let bag = rosbag2::Rosbag2Dir::open(dir)?;
        Self::from_files(bag.files, bag.zstd_messages)
    }

    /// Opens the first file now, so that a missing or unreadable log fails at open; it is
    /// read from a fresh handle, opened with the reader's final options, at the first
    /// message.
    fn from_files(files: Vec<PendingFile>, zstd_messages: bool) -> Result<Self> {
        let pending: VecDeque<PendingFile> = files.into();
        if let Some(f) = pending.front() {
            f.open(ReadOptions::default().max_decompressed_bytes)?;
        }
        Ok(Self {
            pending,
            current: None,
            zstd_messages,
            index: 0,
            stats: ReadStats::default(),
            finished: false,
            scratch: Vec::new(),
            options: ReadOptions::default(),
        })
    }

    fn next_inner(&mut self) -> Option<Result<LogMessage>> {
        loop {
            let source = match &mut self.current {
                Some(s) => s,
                None => {
                    let file = self.pending.pop_front()?;
                    match file.open(self.options.max_decompressed_bytes) {
                        Ok(s) => self.current.insert(s),
                        Err(e) => {
                            self.finished = true;
                            return Some(Err(e));
                        }
                    }
                }
            };
            let index = self.index + 1;
            let (stats, scratch, options, zstd_messages) =
                (&mut self.stats, &mut self.scratch, &self.options, self.zstd_messages);
            let mut out = None;
            let mut visit = |raw: RawMessage<'_>| out = decode_raw(raw, index, stats, scratch, options, zstd_messages);
            match source.next_raw(index, &mut visit) {
                None => {
                    self.current = None;
                    continue;
                }
                Some(Err(e)) => {
                    self.finished = true;
                    // A storage file cut short with more listed after it is a damaged bag,
                    // not a recording that stopped: the later files must not go unread.
                    let e = match e {
                        Error::Truncated { path, location, message } if !self.pending.is_empty() => Error::format(
                            &path,
                            location,
                            format!(
                                "{message}, and the bag lists {} more storage file(s) after it",
                                self.pending.len()
                            ),
                        ),
                        e => e,
                    };
                    return Some(Err(e));
                }
                Some(Ok(())) => {}
            }
            self.index = index;
            if let Some(message) = out {
                return Some(message);
            }
        }
    }
}

/// Decodes one raw message: `None` when its type is not one fusemap uses (counted in
/// `stats`).
fn decode_raw(
    raw: RawMessage<'_>,
    index: u64,
    stats: &mut ReadStats,
    scratch: &mut Vec<u8>,
    options: &ReadOptions,
    zstd_messages: bool,
) -> Option<Result<LogMessage>> {
    let topic = raw.topic;
    let Some(kind) = KnownType::from_name(&topic.type_name) else {
        let t = if topic.type_name.is_empty() { "(no schema)" } else { &topic.type_name };
        stats.skip_type(t);
        return None;
    };
    if !topic.encoding.eq_ignore_ascii_case("cdr") {
        stats.skip_type(&format!("{} ({} encoding)", topic.type_name, topic.encoding));
        return None;
    }
    let at = |message: String| Error::format(raw.path, Location::Message { index, topic: topic.name.clone() }, message);
    let mut payload = raw.data;
    if zstd_messages {
        scratch.clear();
        // One byte past the limit tells a message at the limit from one beyond it, which is
        // refused there (never cut short and decoded).
        let limit = options.max_decompressed_bytes;
        let decoded = zstd::stream::read::Decoder::new(payload)
            .and_then(|d| crate::bounded::read_to_end_bounded(d, limit, scratch));
        match decoded {
            Err(e) => {
                return Some(Err(at(format!(
                    "{}: the bag says messages are zstd-compressed, but: {e}",
                    topic.type_name
                ))))
            }
            Ok(crate::bounded::Bounded::OverLimit) => {
                scratch.clear();
                return Some(Err(Error::limit(
                    raw.path,
                    Location::Message { index, topic: topic.name.clone() },
                    format!(
                        "{}: the zstd-compressed message inflates past the limit of {limit} bytes \
                         (limits.decompressed_mib raises it)",
                        topic.type_name
                    ),
                )));
            }
            Ok(crate::bounded::Bounded::Complete) => {}
        }
        payload = scratch;
    }
    let pixels = options.images.wants(&topic.name);
    let message = match decode_known_with(kind, &topic.name, Some(raw.log_time), payload, pixels) {
        Ok(m) => m,
        Err(e) => return Some(Err(at(format!("{}: {e}", topic.type_name)))),
    };
    if let Some(why) = options.over_limit(&message) {
        let place = Location::Message { index, topic: topic.name.clone() };
        return Some(Err(Error::limit(raw.path, place, format!("{}: {why}", topic.type_name))));
    }
    Some(Ok(message))
}

impl LogReader for Ros2Reader {
    fn next_message(&mut self) -> Option<Result<LogMessage>> {
        if self.finished {
            return None;
        }
        let next = self.next_inner();
        if next.is_none() {
            self.finished = true;
        }
        next
    }

    fn stats(&self) -> &ReadStats {
        &self.stats
    }
}

/// Reads up to `buf.len()` bytes from the start of `path`.
fn read_head(path: &Path, buf: &mut [u8]) -> Result<usize> {
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::io(path, e)),
        }
    }
    Ok(n)
}

/// `de ad be ef` for error messages.
fn hex(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "(empty file)".into();
    }
    bytes.iter().map(|b| format!("{b:02x}")).collect::<Vec<_>>().join(" ")
}

pub(crate) use crate::text::error_chain;

#[cfg(test)]
mod tests;
