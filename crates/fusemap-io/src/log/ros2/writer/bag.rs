//! [`Rosbag2Writer`]: messages in, a rosbag2 directory with one MCAP file out.

use super::cdr_write::encode_cdr_into;
use super::message::OutMessage;
use super::metadata::{bag_info_yaml, metadata_yaml, BagInfo, QosProfile, TopicInfo};
use super::staging::StagingDir;
use crate::atomic::write_atomic;
use crate::error::{Error, Location, Result};
use fusemap_core::time::Stamp;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// How MCAP chunks are compressed. `rosbags`, `ros2 bag` (the `mcap` storage plugin),
/// Foxglove and fusemap's reader read both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ChunkCompression {
    /// Plain chunks.
    None,
    /// Zstandard chunks, what rosbag2's MCAP plugin writes by default: laser scans and
    /// odometry shrink to about a third.
    #[default]
    Zstd,
}

/// Choices for [`Rosbag2Writer::create_with`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rosbag2WriterOptions {
    /// Replace an existing non-empty directory (or file) at the target. Off by default:
    /// a bag is refused rather than written over.
    pub overwrite: bool,
    /// Chunk compression.
    pub compression: ChunkCompression,
    /// Uncompressed bytes per chunk; readers hold one chunk in memory at a time.
    pub chunk_size: u64,
}

impl Default for Rosbag2WriterOptions {
    fn default() -> Self {
        Self { overwrite: false, compression: ChunkCompression::Zstd, chunk_size: 1 << 20 }
    }
}

/// A topic being written.
struct TopicState {
    info: TopicInfo,
    channel_id: u16,
    /// For `tf2_msgs/msg/TFMessage` topics: whether they carry static transforms.
    static_tf: Option<bool>,
}

/// What a finished bag holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WrittenBag {
    /// The bag directory.
    pub dir: PathBuf,
    /// Its MCAP file, `<dir>/<dir name>_0.mcap`.
    pub storage_file: PathBuf,
    /// Messages written.
    pub message_count: u64,
    /// Earliest log time (0 when empty).
    pub starting_time: Stamp,
    /// Latest minus earliest log time.
    pub duration_ns: u64,
    /// The topics in the order they first appeared.
    pub topics: Vec<TopicInfo>,
}

/// Writes a rosbag2 bag (format version 5, MCAP storage, CDR messages) message by message:
/// each message is serialised and handed to the MCAP writer, which holds at most one chunk,
/// so memory does not grow with the log.
///
/// Topics are declared by their first message: the MCAP schema (encoding `ros2msg`, the
/// full concatenated `.msg` definition) and channel (encoding `cdr`, with the
/// `offered_qos_profiles` rosbag2 keeps in the channel metadata) are written then. A topic
/// keeps its type; writing another type on it is an error.
///
/// The directory appears when [`finish`](Self::finish) succeeds, all at once (see
/// the `staging` module); dropping the writer earlier leaves nothing behind.
pub struct Rosbag2Writer {
    // Declared before `staging` so it is dropped (and its file closed) first.
    mcap: Option<mcap::Writer<BufWriter<File>>>,
    staging: StagingDir,
    dir: PathBuf,
    storage_name: String,
    topics: Vec<TopicState>,
    by_name: HashMap<String, usize>,
    schema_ids: HashMap<&'static str, u16>,
    qos_overrides: HashMap<String, QosProfile>,
    scratch: Vec<u8>,
    log_range: Option<(u64, u64)>,
    message_count: u64,
    attempted: u64,
    failed: bool,
}

impl Rosbag2Writer {
    /// Starts a bag at `dir` (which must not exist, or be an empty directory), with zstd
    /// chunks.
    pub fn create(dir: &Path) -> Result<Self> {
        Self::create_with(dir, Rosbag2WriterOptions::default())
    }

    /// Starts a bag at `dir` with `options`.
    pub fn create_with(dir: &Path, options: Rosbag2WriterOptions) -> Result<Self> {
        let staging = StagingDir::create(dir, options.overwrite)?;
        let storage_name = format!("{}_0.mcap", staging.name());
        let storage_path = dir.join(&storage_name);
        let file = File::create(staging.path().join(&storage_name)).map_err(|e| Error::io(&storage_path, e))?;
        let compression = match options.compression {
            ChunkCompression::None => None,
            ChunkCompression::Zstd => Some(mcap::Compression::Zstd),
        };
        let mcap = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("fusemap ", env!("CARGO_PKG_VERSION")))
            .compression(compression)
            .chunk_size(Some(options.chunk_size.max(1)))
            .create(BufWriter::new(file))
            .map_err(|e| mcap_error(&storage_path, e))?;
        Ok(Self {
            mcap: Some(mcap),
            staging,
            dir: dir.to_path_buf(),
            storage_name,
            topics: Vec::new(),
            by_name: HashMap::new(),
            schema_ids: HashMap::new(),
            qos_overrides: HashMap::new(),
            scratch: Vec::new(),
            log_range: None,
            message_count: 0,
            attempted: 0,
            failed: false,
        })
    }

    /// Offers `topic` with `qos` instead of the default ([`QosProfile::LATCHED`] for static
    /// transforms and `/tf_static`, else [`QosProfile::DEFAULT`]). Must come before the
    /// topic's first message.
    pub fn set_topic_qos(&mut self, topic: &str, qos: QosProfile) -> Result<()> {
        if self.by_name.contains_key(topic) {
            return Err(self.message_error(
                topic,
                "the topic's QoS must be set before its first message (it is in the channel record)".into(),
            ));
        }
        self.qos_overrides.insert(topic.to_string(), qos);
        Ok(())
    }

    /// The bag directory being written.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Messages written so far.
    pub fn message_count(&self) -> u64 {
        self.message_count
    }

    /// Writes `msg` on `topic`, received (logged) at `log_time`.
    ///
    /// A message that cannot be stored (bad topic name, a log time before 1970, a header
    /// stamp outside `builtin_interfaces/Time`, a string with a NUL, a topic that already
    /// carries another type) is an [`Error::Format`] at [`Location::Message`] and nothing is
    /// written: the bag stays good and writing can go on. An I/O error ends the bag.
    pub fn write(&mut self, log_time: Stamp, topic: &str, msg: &OutMessage) -> Result<()> {
        if self.failed {
            return Err(self.broken());
        }
        self.attempted += 1;
        if let Err(why) = check_topic_name(topic) {
            return Err(self.message_error(topic, why));
        }
        let Ok(log_ns) = u64::try_from(log_time.0) else {
            return Err(self.message_error(
                topic,
                format!("log time {} ns is before 1970; MCAP log times are unsigned", log_time.0),
            ));
        };
        if let Err(e) = encode_cdr_into(msg, &mut self.scratch) {
            return Err(self.message_error(topic, format!("{}: {e}", msg.type_name())));
        }
        let index = self.topic_index(topic, msg)?;
        let header = mcap::records::MessageHeader {
            channel_id: self.topics[index].channel_id,
            // MCAP sequence numbers are u32 and may wrap; they are informational.
            sequence: self.topics[index].info.message_count as u32,
            log_time: log_ns,
            publish_time: log_ns,
        };
        let written = match self.mcap.as_mut() {
            Some(w) => w.write_to_known_channel(&header, &self.scratch),
            None => return Err(self.broken()),
        };
        if let Err(e) = written {
            self.failed = true;
            return Err(mcap_error(&self.storage_path(), e));
        }
        self.topics[index].info.message_count += 1;
        self.message_count += 1;
        self.log_range = Some(match self.log_range {
            None => (log_ns, log_ns),
            Some((lo, hi)) => (lo.min(log_ns), hi.max(log_ns)),
        });
        Ok(())
    }

    /// Finishes the MCAP file (summary, indexes), writes `metadata.yaml`, flushes both to
    /// disk and moves the directory into place.
    pub fn finish(mut self) -> Result<WrittenBag> {
        if self.failed {
            return Err(self.broken());
        }
        let storage_path = self.storage_path();
        let (start, end) = self.log_range.unwrap_or((0, 0));
        let topics: Vec<TopicInfo> = self.topics.iter().map(|t| t.info.clone()).collect();
        let info = BagInfo {
            storage_file: &self.storage_name,
            starting_time_ns: start,
            duration_ns: end - start,
            message_count: self.message_count,
            topics: &topics,
        };
        let mut mcap = self.mcap.take().ok_or_else(|| self.broken())?;
        // rosbag2's MCAP plugin keeps a copy of the metadata in the file, which
        // `ros2 bag reindex` and readers without metadata.yaml use.
        let record = mcap::records::Metadata {
            name: "rosbag2".into(),
            metadata: BTreeMap::from([("serialized_metadata".to_string(), bag_info_yaml(&info))]),
        };
        mcap.write_metadata(&record).map_err(|e| mcap_error(&storage_path, e))?;
        mcap.finish().map_err(|e| mcap_error(&storage_path, e))?;
        let mut file = mcap.into_inner();
        file.flush().map_err(|e| Error::io(&storage_path, e))?;
        let file = file.into_inner().map_err(|e| Error::io(&storage_path, e.into_error()))?;
        file.sync_all().map_err(|e| Error::io(&storage_path, e))?;
        drop(file);

        let yaml = metadata_yaml(&info);
        let meta_path = self.staging.path().join(crate::log::ros2::rosbag2::METADATA_FILE);
        write_atomic(&meta_path, |w| w.write_all(yaml.as_bytes())).map_err(|e| match e {
            Error::Io { source, .. } => Error::io(&self.dir.join(crate::log::ros2::rosbag2::METADATA_FILE), source),
            other => other,
        })?;
        let Rosbag2Writer { staging, dir, storage_name, message_count, .. } = self;
        staging.commit()?;
        Ok(WrittenBag {
            storage_file: dir.join(storage_name),
            dir,
            message_count,
            starting_time: Stamp(start as i64),
            duration_ns: end - start,
            topics,
        })
    }

    /// The topic's index, declaring its schema and channel on first use.
    fn topic_index(&mut self, topic: &str, msg: &OutMessage) -> Result<usize> {
        let type_name = msg.type_name();
        let tf_static = matches!(msg, OutMessage::Tf { .. }).then(|| msg.is_static_tf());
        if let Some(&i) = self.by_name.get(topic) {
            let t = &self.topics[i];
            if t.info.type_name != type_name {
                let why = format!("the topic carries {}; a {type_name} cannot share it", t.info.type_name);
                return Err(self.message_error(topic, why));
            }
            if t.static_tf != tf_static {
                let why = "static and non-static transforms on one topic (static ones are offered latched)";
                return Err(self.message_error(topic, why.into()));
            }
            return Ok(i);
        }
        let storage_path = self.storage_path();
        let Some(mcap) = self.mcap.as_mut() else { return Err(self.broken()) };
        let def = msg.definition();
        let schema_id = match self.schema_ids.get(def.name) {
            Some(&id) => id,
            None => {
                let id = mcap.add_schema(&type_name, "ros2msg", def.full_text().as_bytes());
                let id = id.map_err(|e| {
                    self.failed = true;
                    mcap_error(&storage_path, e)
                })?;
                self.schema_ids.insert(def.name, id);
                id
            }
        };
        // `/tf_static` is latched whatever the flag says: tf2 listeners subscribe to it
        // transient_local and would miss transforms published before they started.
        let latched = tf_static == Some(true) || (topic == "/tf_static" && tf_static.is_some());
        let qos = self.qos_overrides.get(topic).copied().unwrap_or(if latched {
            QosProfile::LATCHED
        } else {
            QosProfile::DEFAULT
        });
        let metadata = BTreeMap::from([("offered_qos_profiles".to_string(), qos.to_yaml())]);
        let channel_id = mcap.add_channel(schema_id, topic, "cdr", &metadata).map_err(|e| {
            self.failed = true;
            mcap_error(&storage_path, e)
        })?;
        self.topics.push(TopicState {
            info: TopicInfo { name: topic.to_string(), type_name, qos, message_count: 0 },
            channel_id,
            static_tf: tf_static,
        });
        self.by_name.insert(topic.to_string(), self.topics.len() - 1);
        Ok(self.topics.len() - 1)
    }

    fn storage_path(&self) -> PathBuf {
        self.dir.join(&self.storage_name)
    }

    fn message_error(&self, topic: &str, message: String) -> Error {
        Error::format(&self.dir, Location::Message { index: self.attempted, topic: topic.to_string() }, message)
    }

    fn broken(&self) -> Error {
        Error::format(&self.storage_path(), Location::File, "an earlier write failed; the bag cannot be finished")
    }
}

/// `Ok` for a fully qualified ROS 2 topic name (`/scan`, `/robot_1/odom`): a `/`, then
/// tokens of letters, digits and `_` that do not start with a digit, separated by single
/// `/`, no trailing `/`. (The rules of `rcl_validate_topic_name`, after expansion.)
pub fn check_topic_name(topic: &str) -> std::result::Result<(), String> {
    let Some(rest) = topic.strip_prefix('/') else {
        return Err(format!("topic `{topic}` is not fully qualified (it must start with `/`)"));
    };
    if rest.is_empty() {
        return Err("topic `/` names nothing".into());
    }
    for token in rest.split('/') {
        let ok = !token.is_empty()
            && !token.starts_with(|c: char| c.is_ascii_digit())
            && token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !ok {
            return Err(format!(
                "topic `{topic}` is not a valid ROS 2 name (tokens of letters, digits and `_`, not starting \
                 with a digit, separated by single `/`)"
            ));
        }
    }
    Ok(())
}

/// An MCAP writer error as fusemap's error on `path`.
fn mcap_error(path: &Path, e: mcap::McapError) -> Error {
    match e {
        mcap::McapError::Io(io) => Error::io(path, io),
        other => Error::format(path, Location::File, other.to_string()),
    }
}
