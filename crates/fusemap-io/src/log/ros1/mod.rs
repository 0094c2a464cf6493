//! ROS 1 bags (format version 2.0) read as a stream of [`LogMessage`]s.
//!
//! [`BagReader`] walks the file from front to back, one record at a time, and decodes
//! the messages of each chunk in the order they are stored (what `rosbag play` calls
//! file order; the SLAM-benchmark bags keep the CARMEN line order, and downstream sorts
//! by stamp). It never needs the whole file in memory, only the current chunk, and
//! reads through [`std::io::Read`], so a bag can come from a file or from bytes.
//!
//! | connection `type` | becomes |
//! |---|---|
//! | `sensor_msgs/LaserScan` | [`LogMessage::Scan`] |
//! | `nav_msgs/Odometry` | [`LogMessage::Odometry`] (yaw from the quaternion) |
//! | `tf2_msgs/TFMessage`, `tf/tfMessage` | [`LogMessage::Tf`], static on `/tf_static` |
//! | `sensor_msgs/Imu` | [`LogMessage::Imu`] |
//! | `sensor_msgs/NavSatFix` | [`LogMessage::Gnss`] |
//! | `geometry_msgs/PoseWithCovarianceStamped` | [`LogMessage::Pose`] |
//! | `sensor_msgs/Image` | [`LogMessage::Image`] for the topics [`ReadOptions::images`] asks for, else [`LogMessage::ImageHeader`] (pixels not copied) |
//! | `sensor_msgs/CameraInfo` | [`LogMessage::CameraInfo`] |
//! | anything else | skipped, counted in [`ReadStats::skipped_by_type`] |
//!
//! Chunks may be stored uncompressed or compressed with `bz2` or `lz4` (the LZ4 frame
//! format, as ROS's `roslz4` writes it). A connection of one of the types above whose
//! `md5sum` is not that of the standard definition is refused: its layout may differ.
//!
//! Every problem is an [`Error::Format`] naming the file: at a byte offset
//! ([`Location::Offset`]) for the container (not a bag, a truncated record, an unknown
//! compression, a chunk that does not decompress to its stated size), at the message
//! ([`Location::Message`], 1-based among all message records of the file, with its
//! topic) for a payload that does not decode; the record was read whole, so such an
//! error is [skippable](Error::is_skippable) and the next call reads the message after
//! it. Any other error ends the read. A truncated file ends in an error, not a
//! silent short read: the bag header says where the index starts and how many chunks
//! it lists. Nothing in the input can make the reader panic, and memory follows what
//! the file holds: one record's bytes and one chunk's declared uncompressed size.
//!
//! ```no_run
//! use fusemap_io::log::{ros1::BagReader, LogMessage, LogReader};
//! # fn main() -> fusemap_io::Result<()> {
//! let mut bag = BagReader::open("intel.orig.bag")?;
//! while let Some(message) = bag.next_message() {
//!     if let LogMessage::Scan(scan) = message? {
//!         println!("{} beams at {:?}", scan.scan.ranges.len(), scan.scan.stamp);
//!     }
//! }
//! println!("skipped: {:?}", bag.stats().skipped_by_type);
//! # Ok(()) }
//! ```

mod cursor;
mod messages;
mod prefetch;
mod record;
#[cfg(test)]
mod tests;

use crate::log::ros2::KnownType;
use crate::log::{LogMessage, LogReader, ReadOptions, ReadStats};
use crate::{Error, Location, Result};
use cursor::{Cursor, Malformed};
use record::RecordHeader;
use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};

/// True when `first_bytes` (the start of a file) begin with the line every ROS 1 bag
/// of format version 2.0 starts with, `#ROSBAG V2.0\n`.
pub fn sniff(first_bytes: &[u8]) -> bool {
    first_bytes.starts_with(record::MAGIC)
}

/// A ROS 1 bag (v2.0) opened for reading; see the [module docs](self).
pub struct BagReader<R = BufReader<File>> {
    input: R,
    /// File offset of the next top-level record.
    pos: u64,
    /// Where the bag header says the index section starts (0: not indexed).
    index_pos: u64,
    /// How many chunks the bag header says the file has.
    chunk_count: Option<u32>,
    /// Chunk info records seen so far.
    chunk_infos: u64,
    /// The chunk being read.
    chunk: Chunk,
    /// The current top-level record's header.
    header_buf: Vec<u8>,
    /// The current top-level record's data (compressed chunk data, a connection, …).
    data_buf: Vec<u8>,
    decoder: Decoder,
    finished: bool,
    /// Compressed chunk records met so far.
    compressed_chunks: u64,
    /// The helper decompressing every second compressed chunk ([`BagReader::open`]).
    prefetch: Option<prefetch::Prefetch>,
}

/// The decompressed data of the chunk being read and where the next record in it is.
#[derive(Default)]
struct Chunk {
    data: Vec<u8>,
    next: usize,
    /// File offset of the chunk record.
    record_offset: u64,
    /// File offset of its data when stored uncompressed (so errors can name the byte).
    data_offset: Option<u64>,
}

/// The state shared by top-level and in-chunk records: connections and counts.
struct Decoder {
    path: PathBuf,
    connections: HashMap<u32, Connection>,
    /// Message data records seen so far, of any type.
    messages: u64,
    stats: ReadStats,
    /// Which images to decode in full.
    options: ReadOptions,
}

/// What a connection record said.
struct Connection {
    topic: String,
    ty: String,
    kind: Option<KnownType>,
}

/// Where a record is, for container errors.
#[derive(Clone, Copy, Debug)]
enum Place {
    /// A top-level record at this file offset.
    File(u64),
    /// A record at `offset` in the uncompressed data of the chunk record at `record`,
    /// whose data starts at file offset `data` when stored uncompressed.
    Chunk { record: u64, data: Option<u64>, offset: usize },
}

/// What one top-level record amounted to.
#[allow(clippy::large_enum_variant)] // returned by value once, never stored
enum Step {
    Message(LogMessage),
    Continue,
    End,
}

/// The size and position of a top-level record whose header is in `header_buf`.
struct Head {
    offset: u64,
    data_offset: u64,
    data_len: u32,
}

impl BagReader<BufReader<File>> {
    /// Opens the bag at `path` and reads its bag header.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::open_with(path, ReadOptions::default())
    }

    /// Opens the bag at `path` with `options` (which images to decode in full).
    pub fn open_with(path: impl AsRef<Path>, options: ReadOptions) -> Result<Self> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut reader = Self::from_reader(BufReader::with_capacity(1 << 16, file), path)?;
        reader.decoder.options = options;
        reader.prefetch = prefetch::Prefetch::spawn(path, reader.decoder.options.max_decompressed_bytes);
        Ok(reader)
    }
}

impl<R: Read> BagReader<R> {
    /// Reads a bag from `input` (positioned at its first byte); `path` names it in
    /// errors. Reads the magic line and the bag header record.
    pub fn from_reader(input: R, path: impl Into<PathBuf>) -> Result<Self> {
        let mut reader = BagReader {
            input,
            pos: 0,
            index_pos: 0,
            chunk_count: None,
            chunk_infos: 0,
            chunk: Chunk::default(),
            header_buf: Vec::new(),
            data_buf: Vec::new(),
            decoder: Decoder {
                path: path.into(),
                connections: HashMap::new(),
                messages: 0,
                stats: ReadStats::default(),
                options: ReadOptions::default(),
            },
            finished: false,
            compressed_chunks: 0,
            prefetch: None,
        };
        reader.read_preamble()?;
        Ok(reader)
    }

    /// Decodes the images `options` name in full from now on (see [`ReadOptions`]).
    pub fn set_options(&mut self, options: ReadOptions) {
        self.decoder.options = options;
    }

    /// The file name used in errors.
    pub fn path(&self) -> &Path {
        &self.decoder.path
    }

    fn error_at(&self, offset: u64, message: impl Into<String>) -> Error {
        Error::format(&self.decoder.path, Location::Offset(offset), message)
    }

    /// The file ends at `offset`, inside the record that starts there or before its index.
    fn truncated_at(&self, offset: u64, message: impl Into<String>) -> Error {
        Error::truncated(&self.decoder.path, Location::Offset(offset), message)
    }

    /// The magic line and the bag header record.
    fn read_preamble(&mut self) -> Result<()> {
        let mut magic = [0u8; record::MAGIC.len()];
        let n = read_full(&mut self.input, &mut magic).map_err(|e| self.io(e))?;
        let magic = magic.get(..n).unwrap_or_default();
        if magic != record::MAGIC {
            let mut message = String::from("not a ROS 1 bag (v2.0) file");
            if let Some(version) = magic.strip_prefix(b"#ROSBAG V") {
                let version = String::from_utf8_lossy(version);
                message += &format!(": it is a version {} bag, which fusemap does not read", version.trim_end());
            }
            return Err(self.error_at(0, message));
        }
        self.pos = record::MAGIC.len() as u64;
        let Some(head) = self.read_head()? else {
            return Err(self.error_at(self.pos, "the file ends after its first line"));
        };
        let header = record::parse_header(&self.header_buf)
            .map_err(|m| container_error(&self.decoder.path, Place::File(head.offset), m))?;
        if header.op != Some(record::OP_BAG_HEADER) {
            let what = match header.op {
                Some(op) => format!("op 0x{op:02x}"),
                None => "no op".into(),
            };
            return Err(self.error_at(head.offset, format!("the first record is not a bag header ({what})")));
        }
        self.index_pos = header.index_pos.unwrap_or(0);
        self.chunk_count = header.chunk_count;
        // The data block is padding.
        self.skip_data(&head)
    }

    /// Reads the length-prefixed header of the next top-level record into `header_buf`
    /// and the length of its data; `None` at a clean end of file.
    fn read_head(&mut self) -> Result<Option<Head>> {
        let offset = self.pos;
        let mut len = [0u8; 4];
        match read_full(&mut self.input, &mut len).map_err(|e| self.io(e))? {
            0 => return Ok(None),
            4 => {}
            n => {
                return Err(self
                    .truncated_at(offset, format!("truncated record: the file ends {n} bytes into its header length")))
            }
        }
        let header_len = u32::from_le_bytes(len);
        let got = read_into(&mut self.input, header_len, &mut self.header_buf).map_err(|e| self.io(e))?;
        if got < header_len as usize {
            return Err(self.truncated_at(
                offset,
                format!(
                    "truncated record: its header claims {header_len} bytes but the file \
                     ends after {got}"
                ),
            ));
        }
        let n = read_full(&mut self.input, &mut len).map_err(|e| self.io(e))?;
        if n < 4 {
            return Err(self.truncated_at(offset, "truncated record: the file ends in its data length"));
        }
        let data_len = u32::from_le_bytes(len);
        let data_offset = offset + 4 + u64::from(header_len) + 4;
        self.pos = data_offset + u64::from(data_len);
        Ok(Some(Head { offset, data_offset, data_len }))
    }

    /// Skips the data of the record `head`.
    fn skip_data(&mut self, head: &Head) -> Result<()> {
        let want = u64::from(head.data_len);
        let got = io::copy(&mut self.input.by_ref().take(want), &mut io::sink()).map_err(|e| self.io(e))?;
        if got < want {
            return Err(self.truncated_data(head, got));
        }
        Ok(())
    }

    fn truncated_data(&self, head: &Head, got: u64) -> Error {
        self.truncated_at(
            head.offset,
            format!("truncated record: its data claims {} bytes but the file ends after {got}", head.data_len),
        )
    }

    fn io(&self, e: io::Error) -> Error {
        Error::io(&self.decoder.path, e)
    }

    /// Reads and handles the next top-level record.
    fn next_top_level(&mut self) -> Result<Step> {
        let Some(head) = self.read_head()? else {
            return self.at_end();
        };
        let place = Place::File(head.offset);
        let header =
            record::parse_header(&self.header_buf).map_err(|m| container_error(&self.decoder.path, place, m))?;
        match header.op {
            Some(record::OP_CHUNK) => {
                let (compression, size) = match (header.compression, header.size) {
                    (Some(c), Some(s)) => (c.to_vec(), s),
                    _ => return Err(self.error_at(head.offset, "chunk record lacks its `compression` or `size` field")),
                };
                self.read_chunk(&head, place, &compression, size)?;
                Ok(Step::Continue)
            }
            Some(op @ (record::OP_INDEX_DATA | record::OP_CHUNK_INFO)) => {
                self.skip_data(&head)?;
                if op == record::OP_CHUNK_INFO {
                    self.chunk_infos += 1;
                }
                Ok(Step::Continue)
            }
            Some(record::OP_CONNECTION | record::OP_MESSAGE_DATA) => {
                let got = read_into(&mut self.input, head.data_len, &mut self.data_buf)
                    .map_err(|e| Error::io(&self.decoder.path, e))?;
                if got < head.data_len as usize {
                    return Err(self.truncated_data(&head, got as u64));
                }
                Ok(self.decoder.record(&header, &self.data_buf, place)?.map_or(Step::Continue, Step::Message))
            }
            Some(record::OP_BAG_HEADER) => Err(self.error_at(head.offset, "a second bag header record")),
            Some(op) => Err(self.error_at(head.offset, format!("unknown record op 0x{op:02x}"))),
            None => Err(self.error_at(head.offset, "record header has no `op` field")),
        }
    }

    /// Reads the chunk record at `head` (its `compression` and uncompressed `size` from its
    /// header) into the chunk buffer, inflating it when compressed; a prefetched chunk is
    /// taken when one is ready.
    fn read_chunk(&mut self, head: &Head, place: Place, compression: &[u8], size: u32) -> Result<()> {
        // Chunks lie before the index section the bag header points at: one that claims
        // to reach past it has a corrupt length, which is damage, not a cut file.
        if self.index_pos != 0 && head.data_offset + u64::from(head.data_len) > self.index_pos {
            let what = format!(
                "chunk claims {} bytes of data, reaching past the index section at byte {}: its length is corrupt",
                head.data_len, self.index_pos
            );
            return Err(self.error_at(head.offset, what));
        }
        let limit = self.decoder.options.max_decompressed_bytes;
        if u64::from(size) > limit {
            // Refused on its word, before a byte is read or inflated.
            let what = format!(
                "chunk says it holds {size} uncompressed bytes, over the limit of {limit} bytes \
                 (limits.decompressed_mib raises it)"
            );
            return Err(self.error_at(head.offset, &what));
        }
        self.chunk.next = 0;
        self.chunk.record_offset = head.offset;
        self.chunk.data_offset = None;
        let chunk = &mut self.chunk.data;
        if compression == b"none" {
            let got = read_into(&mut self.input, head.data_len, chunk).map_err(|e| Error::io(&self.decoder.path, e))?;
            if got < head.data_len as usize {
                chunk.clear();
                return Err(self.truncated_data(head, got as u64));
            }
            self.chunk.data_offset = Some(head.data_offset);
            record::check_size(chunk.len(), size)
        } else if compression == b"bz2" || compression == b"lz4" {
            let got = read_into(&mut self.input, head.data_len, &mut self.data_buf)
                .map_err(|e| Error::io(&self.decoder.path, e))?;
            if got < head.data_len as usize {
                chunk.clear();
                return Err(self.truncated_data(head, got as u64));
            }
            self.compressed_chunks += 1;
            let ready = match &mut self.prefetch {
                Some(p) if self.compressed_chunks.is_multiple_of(2) => p.take(head.offset),
                _ => None,
            };
            match ready {
                Some(data) if data.len() == size as usize => {
                    *chunk = data;
                    Ok(())
                }
                _ => record::decompress(compression, &self.data_buf, size, chunk),
            }
        } else {
            Err(record::unsupported_compression(compression))
        }
        .map_err(|m| {
            self.chunk.data.clear();
            container_error(&self.decoder.path, place, m)
        })?;
        Ok(())
    }

    /// The end of the file at a record boundary: clean unless the bag header promised
    /// more (an index further on, or more chunk info records).
    fn at_end(&self) -> Result<Step> {
        if self.index_pos != 0 {
            if self.pos < self.index_pos {
                return Err(self.truncated_at(
                    self.pos,
                    format!("the file ends before its index section at byte {}: it is truncated", self.index_pos),
                ));
            }
            if let Some(count) = self.chunk_count {
                if self.chunk_infos < u64::from(count) {
                    return Err(self.truncated_at(
                        self.pos,
                        format!(
                            "the file ends after {} of the {count} chunk info records its \
                             header announces: it is truncated",
                            self.chunk_infos
                        ),
                    ));
                }
            }
        }
        Ok(Step::End)
    }

    /// Reads and handles the next record of the current chunk.
    fn next_in_chunk(&mut self) -> Result<Option<LogMessage>> {
        let start = self.chunk.next;
        let place = Place::Chunk { record: self.chunk.record_offset, data: self.chunk.data_offset, offset: start };
        let mut c = Cursor::new(self.chunk.data.get(start..).unwrap_or_default());
        let inner = record::read_inner(&mut c).map_err(|m| container_error(&self.decoder.path, place, m))?;
        self.chunk.next = start + c.position();
        let header = record::parse_header(inner.header).map_err(|m| container_error(&self.decoder.path, place, m))?;
        match header.op {
            Some(record::OP_CONNECTION | record::OP_MESSAGE_DATA) => self.decoder.record(&header, inner.data, place),
            Some(op) => Err(container_error(
                &self.decoder.path,
                place,
                Malformed(format!("a record with op 0x{op:02x} inside a chunk")),
            )),
            None => {
                Err(container_error(&self.decoder.path, place, Malformed("record header has no `op` field".into())))
            }
        }
    }

    fn advance(&mut self) -> Result<Option<LogMessage>> {
        loop {
            if self.chunk.next < self.chunk.data.len() {
                if let Some(m) = self.next_in_chunk()? {
                    return Ok(Some(m));
                }
                continue;
            }
            match self.next_top_level()? {
                Step::Message(m) => return Ok(Some(m)),
                Step::Continue => {}
                Step::End => return Ok(None),
            }
        }
    }
}

impl Decoder {
    /// Handles a connection or message data record.
    fn record(&mut self, header: &RecordHeader<'_>, data: &[u8], place: Place) -> Result<Option<LogMessage>> {
        if header.op == Some(record::OP_CONNECTION) {
            self.connection(header, data).map_err(|m| container_error(&self.path, place, m))?;
            return Ok(None);
        }
        self.messages += 1;
        let (conn, receive) = match (header.conn, header.time) {
            (Some(c), Some(t)) => (c, t),
            _ => {
                return Err(container_error(
                    &self.path,
                    place,
                    Malformed("message data record lacks its `conn` or `time` field".into()),
                ))
            }
        };
        let Some(connection) = self.connections.get(&conn) else {
            return Err(container_error(
                &self.path,
                place,
                Malformed(format!(
                    "message data record refers to connection {conn}, which no connection \
                     record before it defines"
                )),
            ));
        };
        let Some(kind) = connection.kind else {
            self.stats.skip_type(&connection.ty);
            return Ok(None);
        };
        let pixels = self.options.images.wants(&connection.topic);
        let at = || Location::Message { index: self.messages, topic: connection.topic.clone() };
        let message = messages::decode(kind, &connection.topic, receive, data, pixels)
            .map_err(|m| Error::format(&self.path, at(), m.0))?;
        match self.options.over_limit(&message) {
            Some(why) => Err(Error::limit(&self.path, at(), why)),
            None => Ok(Some(message)),
        }
    }

    /// Registers a connection, refusing a known type with an unexpected MD5 sum.
    fn connection(&mut self, header: &RecordHeader<'_>, data: &[u8]) -> Result<(), Malformed> {
        let (Some(conn), Some(topic)) = (header.conn, header.topic) else {
            return Err(Malformed("connection record lacks its `conn` or `topic` field".into()));
        };
        let topic = String::from_utf8_lossy(topic).into_owned();
        let (ty, md5) = record::parse_connection_data(data)?;
        let ty = String::from_utf8_lossy(ty).into_owned();
        let kind = match messages::known_type(ty.as_bytes()) {
            Some((kind, expected)) if md5 == expected.as_bytes() => Some(kind),
            Some((_, expected)) => {
                return Err(Malformed(format!(
                    "connection {conn} on topic `{topic}` has type {ty} with md5sum {}, but \
                     the standard {ty} that fusemap decodes has md5sum {expected}: the \
                     message layout may differ, so it is not decoded",
                    String::from_utf8_lossy(md5)
                )))
            }
            None => None,
        };
        self.connections.insert(conn, Connection { topic, ty, kind });
        Ok(())
    }
}

impl<R: Read> LogReader for BagReader<R> {
    fn next_message(&mut self) -> Option<Result<LogMessage>> {
        if self.finished {
            return None;
        }
        match self.advance() {
            Ok(Some(m)) => Some(Ok(m)),
            Ok(None) => {
                self.finished = true;
                None
            }
            Err(e) => {
                // A message whose payload does not decode was consumed whole (its record
                // length was sound): the next record can still be read.
                self.finished = !e.is_skippable();
                Some(Err(e))
            }
        }
    }

    fn stats(&self) -> &ReadStats {
        &self.decoder.stats
    }
}

/// A container error at `place`.
fn container_error(path: &Path, place: Place, m: Malformed) -> Error {
    match place {
        Place::File(at) => Error::format(path, Location::Offset(at), m.0),
        Place::Chunk { data: Some(data), offset, .. } => {
            Error::format(path, Location::Offset(data + offset as u64), m.0)
        }
        Place::Chunk { record, data: None, offset } => Error::format(
            path,
            Location::Offset(record),
            format!("in the chunk's uncompressed data at offset {offset}: {}", m.0),
        ),
    }
}

/// Fills `buf` from `input` as far as the input goes; the number of bytes read.
fn read_full(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while let Some(rest) = buf.get_mut(n..).filter(|r| !r.is_empty()) {
        match input.read(rest) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Replaces `out` with the next `len` bytes of `input`, or as many as there are; the
/// number read. Memory grows with what is actually read, not with what `len` claims, by
/// fallible reservations ([`crate::bounded::read_to_end_bounded`]).
fn read_into(input: &mut impl Read, len: u32, out: &mut Vec<u8>) -> io::Result<usize> {
    crate::bounded::read_to_end_bounded(input.by_ref().take(u64::from(len)), u64::from(len), out)?;
    Ok(out.len())
}
