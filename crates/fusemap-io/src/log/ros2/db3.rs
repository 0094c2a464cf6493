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

/// One `.db3` file being read.
pub(crate) struct Db3Source {
    path: PathBuf,
    conn: Connection,
    topics: HashMap<i64, Topic>,
    /// Row ids in timestamp order.
    order: Vec<i64>,
    next: usize,
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

        Ok(Self { path: path.to_path_buf(), conn, topics, order, next: 0 })
    }

    /// Fetches row `id` and hands it to `visit`, its payload borrowed from SQLite.
    fn fetch(&mut self, index: u64, id: i64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<()> {
        let path = &self.path;
        let at = |topic: String, message: String| Error::format(path, Location::Message { index, topic }, message);
        let topics = &self.topics;
        // Ok(Err(topic_id)): the row names a topic `topics` does not list.
        let row = self.conn.prepare_cached("SELECT topic_id, timestamp, data FROM messages WHERE id = ?1").and_then(
            |mut stmt| {
                stmt.query_row([id], |row| {
                    let topic_id = row.get::<_, i64>(0)?;
                    let timestamp = row.get::<_, i64>(1)?;
                    let data = match row.get_ref(2)? {
                        rusqlite::types::ValueRef::Blob(b) => b,
                        rusqlite::types::ValueRef::Null => &[],
                        other => {
                            return Err(rusqlite::Error::FromSqlConversionFailure(
                                2,
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
            },
        );
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
