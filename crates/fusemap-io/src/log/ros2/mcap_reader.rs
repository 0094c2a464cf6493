//! MCAP storage: a file read front to back in bounded memory (the `mcap` crate's
//! sans-io linear reader, which decompresses zstd and lz4 chunks one at a time).
//!
//! Schema records give the ROS type name (`sensor_msgs/msg/LaserScan`), channel records
//! the topic and the message encoding (`cdr`), and each message's `log_time` becomes its
//! receive stamp. Messages come in file order.

use super::{error_chain, RawMessage, Source, Topic};
use crate::error::{Error, Location, Result};
use fusemap_core::time::Stamp;
use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// One MCAP file being read.
pub(crate) struct McapSource {
    path: PathBuf,
    input: Box<dyn Read + Send>,
    reader: LinearReader,
    /// Bytes of the (decompressed) file fed to the reader so far.
    bytes_read: u64,
    /// Schema id → (name, encoding).
    schemas: HashMap<u16, (String, String)>,
    channels: HashMap<u16, Topic>,
    /// The largest record or decompressed chunk accepted ([`ReadOptions::max_decompressed_bytes`](crate::log::ReadOptions::max_decompressed_bytes)).
    max_record: u64,
    /// The file ends with MCAP's closing magic: it was written to its end, so running out
    /// of bytes inside a record means a corrupt length, not a recording cut short.
    complete: bool,
}

/// True when the file at `file` (not compressed as a whole) ends with the closing magic.
fn ends_with_magic(file: &mut File) -> bool {
    use std::io::{Seek, SeekFrom};
    let magic = super::MCAP_MAGIC;
    let mut tail = [0u8; 8];
    let found = file.seek(SeekFrom::End(-(magic.len() as i64))).is_ok() && file.read_exact(&mut tail).is_ok();
    let rewound = file.seek(SeekFrom::Start(0)).is_ok();
    found && rewound && tail == *magic
}

impl McapSource {
    /// Opens `path`; with `zstd` the whole file is a zstd stream around the MCAP
    /// (rosbag2's `file` compression, `*.mcap.zstd`). A record, or a chunk once
    /// decompressed, larger than `max_record` bytes is an error when it is met, before it
    /// is read: a corrupt length or a decompression bomb costs no memory.
    pub(crate) fn open(path: &Path, zstd: bool, max_record: u64) -> Result<Self> {
        let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
        let complete = !zstd && ends_with_magic(&mut file);
        let input: Box<dyn Read + Send> = if zstd {
            Box::new(zstd::stream::read::Decoder::new(file).map_err(|e| Error::io(path, e))?)
        } else {
            Box::new(BufReader::with_capacity(1 << 16, file))
        };
        let limit = usize::try_from(max_record).unwrap_or(usize::MAX);
        let options = LinearReaderOptions::default().with_validate_chunk_crcs(true).with_record_length_limit(limit);
        Ok(Self {
            path: path.to_path_buf(),
            input,
            reader: LinearReader::new_with_options(options),
            bytes_read: 0,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            max_record,
            complete,
        })
    }

    fn container_error(&self, what: &str) -> Error {
        Error::format(
            &self.path,
            Location::File,
            format!("MCAP: {what} (found after reading {} bytes)", self.bytes_read),
        )
    }

    /// The error for a record the reader could not read: a length past the end of a file
    /// that is complete (corrupt), the end of a file that is not (truncated), or a record
    /// over the size limit.
    fn read_error(&self, e: mcap::McapError) -> Error {
        match e {
            mcap::McapError::UnexpectedEof if self.complete => {
                let what = format!(
                    "a record's length reaches past the end of the file after {} bytes, although the file ends \
                     with MCAP's closing magic: the length is corrupt",
                    self.bytes_read
                );
                self.container_error(&what)
            }
            mcap::McapError::UnexpectedEof => Error::truncated(
                &self.path,
                Location::File,
                format!("MCAP: the file ends after {} bytes, inside a record: it is truncated", self.bytes_read),
            ),
            e => {
                let mut what = error_chain(&e);
                if matches!(e, mcap::McapError::ChunkTooLarge(_) | mcap::McapError::RecordTooLarge { .. }) {
                    what +=
                        &format!(", over the limit of {} bytes (limits.decompressed_mib raises it)", self.max_record);
                }
                self.container_error(&what)
            }
        }
    }

    /// Reads up to `need` bytes of the file into the reader's buffer.
    fn fill(&mut self, need: usize) -> Result<()> {
        let buf = self.reader.insert(need);
        let n = loop {
            match self.input.read(buf) {
                Ok(n) => break n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::io(&self.path, e)),
            }
        };
        self.reader.notify_read(n);
        self.bytes_read += n as u64;
        Ok(())
    }

    /// Advances to the next message record, handling schema and channel records on the
    /// way, and hands it to `visit` where the reader holds it. `Ok(false)` at the end of
    /// the file.
    fn advance(&mut self, index: u64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<bool> {
        loop {
            let event = match self.reader.next_event() {
                None => return Ok(false),
                Some(Ok(event)) => event,
                Some(Err(e)) => return Err(self.read_error(e)),
            };
            match event {
                LinearReadEvent::ReadRequest(need) => self.fill(need)?,
                LinearReadEvent::Record { opcode, data } => {
                    // Only schemas, channels and messages matter here; the others (indexes,
                    // statistics, attachments, metadata) are not parsed at all.
                    if !matches!(opcode, SCHEMA | CHANNEL | MESSAGE) {
                        continue;
                    }
                    if let Err(what) = lengths_fit(opcode, data) {
                        let what = format!("record with opcode {opcode:#04x}: {what}");
                        return Err(self.container_error(&what));
                    }
                    let record = match mcap::parse_record(opcode, data) {
                        Ok(r) => r,
                        Err(e) => {
                            let what = format!("record with opcode {opcode:#04x}: {}", error_chain(&e));
                            return Err(self.container_error(&what));
                        }
                    };
                    match record {
                        Record::Schema { header, .. } => {
                            self.schemas.insert(header.id, (header.name, header.encoding));
                        }
                        Record::Channel(c) => {
                            let type_name = match self.schemas.get(&c.schema_id) {
                                Some((name, _)) => name.clone(),
                                None => String::new(),
                            };
                            self.channels
                                .insert(c.id, Topic { name: c.topic, type_name, encoding: c.message_encoding });
                        }
                        Record::Message { header, data } => {
                            let channel = header.channel_id;
                            let Ok(log_time) = i64::try_from(header.log_time) else {
                                let what = format!("log_time {} ns is beyond year 2262", header.log_time);
                                return Err(message_error(&self.path, &self.channels, index, channel, what));
                            };
                            let Some(topic) = self.channels.get(&channel) else {
                                let what = format!("message on channel {channel}, which no Channel record declared");
                                return Err(message_error(&self.path, &self.channels, index, channel, what));
                            };
                            visit(RawMessage { path: &self.path, topic, log_time: Stamp(log_time), data: &data });
                            return Ok(true);
                        }
                        _ => {}
                    }
                }
            }
        }
    }
}

/// A message error naming the message's topic (or its channel when undeclared).
/// MCAP opcodes of the records this reader parses.
const SCHEMA: u8 = 0x03;
const CHANNEL: u8 = 0x04;
const MESSAGE: u8 = 0x05;

/// Checks that every length-prefixed field of a Schema or Channel record (its strings,
/// its schema data, its metadata map and the strings inside it) fits in the record, before
/// the `mcap` crate parses it: that parser reserves memory by a field's stated length
/// first, so one corrupt length (found by fuzzing: a metadata string claiming 3.5 GB)
/// would cost that much memory, or abort the process under a memory limit.
fn lengths_fit(opcode: u8, data: &[u8]) -> std::result::Result<(), String> {
    /// Skips a field of `n` fixed bytes, or a u32-length-prefixed one (`n = None`).
    fn skip(data: &[u8], at: &mut usize, fixed: Option<usize>, what: &str) -> std::result::Result<usize, String> {
        let len = match fixed {
            Some(n) => n,
            None => {
                let bytes = data.get(*at..*at + 4).ok_or_else(|| format!("{what}: its length is cut off"))?;
                *at += 4;
                u32::from_le_bytes(bytes.try_into().expect("4 bytes")) as usize
            }
        };
        let left = data.len() - *at;
        if len > left {
            return Err(format!("{what} claims {len} bytes, but only {left} are left in the record"));
        }
        *at += len;
        Ok(len)
    }
    let mut at = 0;
    match opcode {
        SCHEMA => {
            skip(data, &mut at, Some(2), "the schema id")?;
            skip(data, &mut at, None, "the schema name")?;
            skip(data, &mut at, None, "the schema encoding")?;
            skip(data, &mut at, None, "the schema data")?;
        }
        CHANNEL => {
            skip(data, &mut at, Some(4), "the channel and schema ids")?;
            skip(data, &mut at, None, "the topic")?;
            skip(data, &mut at, None, "the message encoding")?;
            let map_start = at + 4;
            let map_len = skip(data, &mut at, None, "the metadata map")?;
            let map = &data[map_start..map_start + map_len];
            let mut in_map = 0;
            while in_map < map.len() {
                skip(map, &mut in_map, None, "a metadata key")?;
                skip(map, &mut in_map, None, "a metadata value")?;
            }
        }
        _ => {}
    }
    Ok(())
}

fn message_error(path: &Path, channels: &HashMap<u16, Topic>, index: u64, channel: u16, message: String) -> Error {
    let topic = match channels.get(&channel) {
        Some(t) => t.name.clone(),
        None => format!("(channel {channel})"),
    };
    Error::format(path, Location::Message { index, topic }, message)
}

impl Source for McapSource {
    fn next_raw(&mut self, index: u64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Option<Result<()>> {
        match self.advance(index, visit) {
            Ok(true) => Some(Ok(())),
            Ok(false) => None,
            Err(e) => Some(Err(e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn string(s: &str) -> Vec<u8> {
        let mut v = (s.len() as u32).to_le_bytes().to_vec();
        v.extend_from_slice(s.as_bytes());
        v
    }

    fn channel(metadata: &[u8]) -> Vec<u8> {
        let mut v = vec![1, 0, 1, 0];
        v.extend(string("/scan"));
        v.extend(string("cdr"));
        v.extend((metadata.len() as u32).to_le_bytes());
        v.extend_from_slice(metadata);
        v
    }

    #[test]
    fn fields_within_the_record_pass_and_a_length_past_it_is_named() {
        let pair = [string("key"), string("value")].concat();
        assert_eq!(lengths_fit(CHANNEL, &channel(&pair)), Ok(()));
        assert_eq!(lengths_fit(CHANNEL, &channel(&[])), Ok(()));
        // A metadata value claiming 3.5 GB (the fuzzer's find) is refused before parsing.
        let mut lying = pair.clone();
        lying[7..11].copy_from_slice(&0xd1aa_1f80u32.to_le_bytes());
        let e = lengths_fit(CHANNEL, &channel(&lying)).unwrap_err();
        assert!(e.contains("a metadata value claims 3517587328 bytes"), "{e}");
        // A topic reaching past the record, and a record cut inside a length.
        let mut c = channel(&pair);
        c[4..8].copy_from_slice(&1000u32.to_le_bytes());
        assert!(lengths_fit(CHANNEL, &c).unwrap_err().contains("the topic claims 1000 bytes"));
        assert!(lengths_fit(CHANNEL, &channel(&pair)[..6]).unwrap_err().contains("cut off"));
        let schema = [vec![1, 0], string("sensor_msgs/msg/LaserScan"), string("ros2msg"), string("...")].concat();
        assert_eq!(lengths_fit(SCHEMA, &schema), Ok(()));
        assert!(lengths_fit(SCHEMA, &schema[..schema.len() - 1]).unwrap_err().contains("the schema data claims"));
    }
}
