//! rosbag2 SQLite3 storage (`.db3`): a `topics` table (`id, name, type,
//! serialization_format, …`) and a `messages` table (`id, topic_id, timestamp, data`),
//! read in timestamp order (ties by row id). The `timestamp` column, nanoseconds, becomes
//! each message's receive stamp.
//!
//! The order is taken once as a list of row ids (8 bytes a message); each payload is then
//! fetched by id, so memory stays small however large the bag, whether or not the file
//! has rosbag2's index on `timestamp`.

use super::{error_chain, RawMessage, Source, Topic};
use crate::error::{Error, Location, Result};
use fusemap_core::time::Stamp;
use rusqlite::{Connection, OpenFlags, OptionalExtension};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One `.db3` file being read.
pub(crate) struct Db3Source {
    path: PathBuf,
    conn: Connection,
    topics: HashMap<i64, Topic>,
    /// Row ids in timestamp order.
    order: Vec<i64>,
    next: usize,
    /// The current message.
    topic_id: i64,
    log_time: Stamp,
    payload: Vec<u8>,
}

impl Db3Source {
    /// Opens `path` read-only and reads its topics and message order.
    pub(crate) fn open(path: &Path) -> Result<Self> {
        // SQLite would create a missing file; report it as the OS would.
        std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        let sql_error = |what: &str, e: rusqlite::Error| {
            Error::format(path, Location::File, format!("SQLite: {what}: {}", error_chain(&e)))
        };
        let conn =
            Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX)
                .map_err(|e| sql_error("cannot open", e))?;

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

        let order = {
            let mut stmt = conn
                .prepare("SELECT id FROM messages ORDER BY timestamp, id")
                .map_err(|e| sql_error("reading table `messages`", e))?;
            let rows =
                stmt.query_map([], |row| row.get::<_, i64>(0)).map_err(|e| sql_error("reading table `messages`", e))?;
            rows.collect::<rusqlite::Result<Vec<i64>>>().map_err(|e| sql_error("reading table `messages`", e))?
        };

        Ok(Self {
            path: path.to_path_buf(),
            conn,
            topics,
            order,
            next: 0,
            topic_id: 0,
            log_time: Stamp::ZERO,
            payload: Vec::new(),
        })
    }

    fn fetch(&mut self, index: u64, id: i64) -> Result<()> {
        let at =
            |topic: String, message: String| Error::format(&self.path, Location::Message { index, topic }, message);
        let row = self.conn.prepare_cached("SELECT topic_id, timestamp, data FROM messages WHERE id = ?1").and_then(
            |mut stmt| {
                stmt.query_row([id], |row| {
                    Ok((row.get::<_, i64>(0)?, row.get::<_, i64>(1)?, row.get::<_, Vec<u8>>(2)?))
                })
                .optional()
            },
        );
        let (topic_id, timestamp, data) = match row {
            Ok(Some(row)) => row,
            Ok(None) => {
                return Err(at(
                    format!("(row id {id})"),
                    format!("row id {id} of table `messages` vanished while reading"),
                ))
            }
            Err(e) => {
                return Err(at(
                    format!("(row id {id})"),
                    format!("SQLite: row id {id} of table `messages`: {}", error_chain(&e)),
                ))
            }
        };
        if !self.topics.contains_key(&topic_id) {
            return Err(at(
                format!("(topic id {topic_id})"),
                format!("row id {id} of table `messages` has topic_id {topic_id}, which table `topics` does not list"),
            ));
        }
        self.topic_id = topic_id;
        self.log_time = Stamp(timestamp);
        self.payload = data;
        Ok(())
    }
}

impl Source for Db3Source {
    fn next_raw(&mut self, index: u64) -> Option<Result<RawMessage<'_>>> {
        let id = *self.order.get(self.next)?;
        self.next += 1;
        if let Err(e) = self.fetch(index, id) {
            return Some(Err(e));
        }
        let topic = self.topics.get(&self.topic_id)?;
        Some(Ok(RawMessage { path: &self.path, topic, log_time: self.log_time, data: &self.payload }))
    }
}
