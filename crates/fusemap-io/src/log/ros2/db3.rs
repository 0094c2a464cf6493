//! rosbag2 SQLite3 storage (`.db3`): a `topics` table (`id, name, type,
//! serialization_format, …`) and a `messages` table (`id, topic_id, timestamp, data`),
//! read in timestamp order (ties by row id). The `timestamp` column, nanoseconds, becomes
//! each message's receive stamp.
//!
//! The order is taken once as a list of row ids (8 bytes a message); each payload is then
//! fetched by id and decoded where SQLite holds it (never copied out), so memory stays
//! small however large the bag, whether or not the file has rosbag2's index on
//! `timestamp`.

use super::{error_chain, RawMessage, Source, Topic};
use crate::error::{Error, Location, Result};
use fusemap_core::time::Stamp;
use rusqlite::{Connection, OpenFlags, OptionalExtension};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// SQLite virtual-machine steps between two looks at the statement's time budget.
const PROGRESS_OPS: i32 = 100_000;
/// The longest one statement may run: ordering the ids of a bag of millions of messages
/// takes seconds; a crafted file (a recursive query behind a table name) is stopped here.
const QUERY_BUDGET: Duration = Duration::from_secs(60);

/// `path` for an SQLite URI: bytes other than unreserved ones and `/` percent-encoded,
/// so `?`, `#` and `%` in a file name stay part of it.
fn uri_path(path: &Path) -> String {
    #[cfg(unix)]
    let bytes = std::os::unix::ffi::OsStrExt::as_bytes(path.as_os_str()).to_vec();
    #[cfg(not(unix))]
    let bytes = path.to_string_lossy().as_bytes().to_vec();
    let mut out = String::with_capacity(bytes.len());
    for b in bytes {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// One `.db3` file being read.
pub(crate) struct Db3Source {
    path: PathBuf,
    conn: Connection,
    topics: HashMap<i64, Topic>,
    /// Row ids in timestamp order.
    order: Vec<i64>,
    next: usize,
    /// The running statement's deadline, nanoseconds after `started`.
    deadline: Arc<AtomicU64>,
    started: Instant,
    /// The most bytes one message's `data` may hold (`limits.decompressed_mib`).
    max_message: u64,
}

impl Db3Source {
    /// Opens `path` read-only and reads its topics and message order; a message whose
    /// `data` holds more than `max_message` bytes is refused when it is reached.
    pub(crate) fn open(path: &Path, max_message: u64) -> Result<Self> {
        // SQLite would create a missing file; report it as the OS would.
        std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        let sql_error = |what: &str, e: rusqlite::Error| {
            Error::format(path, Location::File, format!("SQLite: {what}: {}", error_chain(&e)))
        };
        // Read-only and immutable: SQLite then takes no locks and writes no `-wal`/`-shm`
        // file beside the input (which also lets a bag on read-only media be read).
        let uri = format!("file:{}?immutable=1", uri_path(path));
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_URI | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let conn = Connection::open_with_flags(uri, flags).map_err(|e| sql_error("cannot open", e))?;
        // Every statement gets a time budget: a crafted file must not run a query forever.
        let deadline = Arc::new(AtomicU64::new(0));
        let started = Instant::now();
        {
            let deadline = Arc::clone(&deadline);
            conn.progress_handler(
                PROGRESS_OPS,
                Some(move || started.elapsed().as_nanos() as u64 > deadline.load(Ordering::Relaxed)),
            )
            .map_err(|e| sql_error("setting a time budget", e))?;
        }
        let arm = || deadline.store((started.elapsed() + QUERY_BUDGET).as_nanos() as u64, Ordering::Relaxed);
        // The rosbag2 schema: `topics` and `messages` are tables (a view can be any query).
        for table in ["topics", "messages"] {
            arm();
            let kind: Option<String> = conn
                .query_row("SELECT type FROM sqlite_master WHERE name = ?1", [table], |row| row.get(0))
                .optional()
                .map_err(|e| sql_error("reading the schema", e))?;
            match kind.as_deref() {
                Some("table") => {}
                Some(other) => {
                    return Err(Error::format(
                        path,
                        Location::File,
                        format!("`{table}` is a {other}, not a table: not a rosbag2 database"),
                    ))
                }
                None => {
                    return Err(Error::format(
                        path,
                        Location::File,
                        format!("no table `{table}`: not a rosbag2 database"),
                    ))
                }
            }
        }
        arm();

        let mut topics = HashMap::new();
        {
            let mut stmt = conn
                .prepare("SELECT id, name, type, serialization_format FROM topics")
                .map_err(|e| sql_error("reading table `topics`", e))?;
            let rows = stmt
                .query_map([], |row| {
                    Ok((
                        row.get::<_, i64>(0)?,
                        Topic { name: row.get(1)?, type_name: row.get(2)?, encoding: row.get(3)? },
                    ))
                })
                .map_err(|e| sql_error("reading table `topics`", e))?;
            for row in rows {
                let (id, topic) = row.map_err(|e| sql_error("reading table `topics`", e))?;
                topics.insert(id, topic);
            }
        }

        arm();
        let order = {
            let mut stmt = conn
                .prepare("SELECT id FROM messages ORDER BY timestamp, id")
                .map_err(|e| sql_error("reading table `messages`", e))?;
            let rows =
                stmt.query_map([], |row| row.get::<_, i64>(0)).map_err(|e| sql_error("reading table `messages`", e))?;
            rows.collect::<rusqlite::Result<Vec<i64>>>().map_err(|e| sql_error("reading table `messages`", e))?
        };

        Ok(Self { path: path.to_path_buf(), conn, topics, order, next: 0, deadline, started, max_message })
    }

    /// Fetches row `id` and hands it to `visit`, its payload borrowed from SQLite.
    fn fetch(&mut self, index: u64, id: i64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<()> {
        self.deadline.store((self.started.elapsed() + QUERY_BUDGET).as_nanos() as u64, Ordering::Relaxed);
        let path = &self.path;
        let at = |topic: String, message: String| Error::format(path, Location::Message { index, topic }, message);
        let topics = &self.topics;
        let max = i64::try_from(self.max_message).unwrap_or(i64::MAX);
        // Ok(Err(topic_id)): the row names a topic `topics` does not list. The payload is
        // fetched only when `length(data)` (which SQLite answers from the record header,
        // without reading the blob) is within the limit.
        let sql = "SELECT topic_id, timestamp, length(data), CASE WHEN length(data) <= ?2 THEN data END \
                   FROM messages WHERE id = ?1";
        let mut too_long = None;
        let row = self.conn.prepare_cached(sql).and_then(|mut stmt| {
            stmt.query_row([id, max], |row| {
                let topic_id = row.get::<_, i64>(0)?;
                let timestamp = row.get::<_, i64>(1)?;
                let length = row.get::<_, Option<i64>>(2)?.unwrap_or(0);
                if length > max {
                    too_long = Some((topics.get(&topic_id).map(|t| t.name.clone()), length));
                    return Ok(Ok(()));
                }
                let data = match row.get_ref(3)? {
                    rusqlite::types::ValueRef::Blob(b) => b,
                    rusqlite::types::ValueRef::Null => &[],
                    other => {
                        return Err(rusqlite::Error::FromSqlConversionFailure(
                            3,
                            other.data_type(),
                            "the `data` column is not a blob".into(),
                        ))
                    }
                };
                let Some(topic) = topics.get(&topic_id) else { return Ok(Err(topic_id)) };
                visit(RawMessage { path, topic, log_time: Stamp(timestamp), data });
                Ok(Ok(()))
            })
            .optional()
        });
        if let Some((topic, length)) = too_long {
            return Err(Error::limit(
                path,
                Location::Message { index, topic: topic.unwrap_or_else(|| format!("(row id {id})")) },
                format!(
                    "row id {id} of table `messages` holds {length} bytes, over the limit of {} bytes \
                     (limits.decompressed_mib raises it)",
                    self.max_message
                ),
            ));
        }
        match row {
            Ok(Some(Ok(()))) => Ok(()),
            Ok(Some(Err(topic_id))) => Err(at(
                format!("(topic id {topic_id})"),
                format!("row id {id} of table `messages` has topic_id {topic_id}, which table `topics` does not list"),
            )),
            Ok(None) => {
                Err(at(format!("(row id {id})"), format!("row id {id} of table `messages` vanished while reading")))
            }
            Err(e) => Err(at(
                format!("(row id {id})"),
                format!("SQLite: row id {id} of table `messages`: {}", error_chain(&e)),
            )),
        }
    }
}

impl Source for Db3Source {
    fn next_raw(&mut self, index: u64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Option<Result<()>> {
        let id = *self.order.get(self.next)?;
        self.next += 1;
        Some(self.fetch(index, id, visit))
    }
}
