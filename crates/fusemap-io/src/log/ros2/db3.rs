//! rosbag2 SQLite3 storage (`.db3`): a `topics` table (`id, name, type,
//! serialization_format, …`) and a `messages` table (`id, topic_id, timestamp, data`),
//! read in timestamp order (ties by row id). The `timestamp` column, nanoseconds, becomes
//! each message's receive stamp.
//!
//! The order is taken once as a list of row ids (8 bytes a message); each payload is then
//! fetched by id and decoded where SQLite holds it (never copied out), so memory stays
//! small however large the bag, whether or not the file has rosbag2's index on
//! `timestamp`.
//!
//! A cut or damaged file (SQLite: "database disk image is malformed") is read as far as a
//! scan of `messages` in storage order reaches, and then ends with a truncation error
//! saying how many rows were intact, like a cut bag or MCAP.

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

/// A file-level SQLite error in words that name the file.
fn sql_error(path: &Path, what: &str, e: rusqlite::Error) -> Error {
    Error::format(path, Location::File, format!("SQLite: {what}: {}", error_chain(&e)))
}

/// Every statement's time budget: a crafted file must not run a query forever. SQLite's
/// progress handler stops the statement running once the deadline set by [`arm`] passes.
///
/// [`arm`]: QueryBudget::arm
struct QueryBudget {
    /// The running statement's deadline, nanoseconds after `started`.
    deadline: Arc<AtomicU64>,
    started: Instant,
}

impl QueryBudget {
    /// The budget, installed on `conn`.
    fn on(conn: &Connection) -> rusqlite::Result<Self> {
        let deadline = Arc::new(AtomicU64::new(0));
        let started = Instant::now();
        let shared = Arc::clone(&deadline);
        conn.progress_handler(
            PROGRESS_OPS,
            Some(move || started.elapsed().as_nanos() as u64 > shared.load(Ordering::Relaxed)),
        )?;
        Ok(Self { deadline, started })
    }

    /// Gives the next statement [`QUERY_BUDGET`] from now.
    fn arm(&self) {
        self.deadline.store((self.started.elapsed() + QUERY_BUDGET).as_nanos() as u64, Ordering::Relaxed);
    }
}

/// `table` is a table of the rosbag2 schema (a view can be any query, a virtual table any
/// code). The type is the one SQLite gave the object it loaded (`pragma_table_list`), not
/// the `type` column of `sqlite_master`, which a crafted file can set to `table` over a
/// `CREATE VIEW`.
fn check_table(conn: &Connection, path: &Path, table: &str) -> Result<()> {
    let query = || {
        conn.query_row("SELECT type FROM pragma_table_list WHERE schema = 'main' AND name = ?1", [table], |row| {
            row.get(0)
        })
        .optional()
    };
    let kind: Option<String> = match query() {
        // SQLite refuses a file shorter than its header says (a cut bag) as malformed
        // before reading anything, unless `writable_schema` is on; on a read-only
        // connection that only lifts this check, so the intact pages can be read (and a
        // damaged row is met as a truncation, in `read_order`).
        Err(e) if is_corrupt(&e) => {
            conn.pragma_update(None, "writable_schema", true)
                .map_err(|e| sql_error(path, "reading a damaged database", e))?;
            query()
        }
        other => other,
    }
    .map_err(|e| sql_error(path, "reading the schema", e))?;
    let why = match kind.as_deref() {
        Some("table") => return Ok(()),
        Some(other) => format!("`{table}` is a {other}, not a table: not a rosbag2 database"),
        None => format!("no table `{table}`: not a rosbag2 database"),
    };
    Err(Error::format(path, Location::File, why))
}

/// The `topics` table by id.
fn read_topics(conn: &Connection) -> rusqlite::Result<HashMap<i64, Topic>> {
    let mut stmt = conn.prepare("SELECT id, name, type, serialization_format FROM topics")?;
    let rows = stmt.query_map([], |row| {
        Ok((row.get::<_, i64>(0)?, Topic { name: row.get(1)?, type_name: row.get(2)?, encoding: row.get(3)? }))
    })?;
    rows.collect()
}

/// The message rows in timestamp order, and why the rest was lost when the file is cut
/// or damaged: rosbag2 writes rows in receive order, so the rows a scan of the table
/// reaches before the damage are the log's intact start.
fn read_order(conn: &Connection, path: &Path, budget: &QueryBudget) -> Result<(Vec<i64>, Option<String>)> {
    let e = match message_order(conn) {
        Ok(order) => return Ok((order, None)),
        Err(e) if is_corrupt(&e) => e,
        Err(e) => return Err(sql_error(path, "reading table `messages`", e)),
    };
    budget.arm();
    let (order, stop) = intact_rows(conn).map_err(|e| sql_error(path, "reading table `messages`", e))?;
    match stop {
        // The index was damaged, the table whole: every row is read.
        None => Ok((order, None)),
        Some(_) if order.is_empty() => Err(sql_error(path, "reading table `messages`", e)),
        Some(stop) => {
            let why = format!(
                "SQLite: the database is damaged after {} rows of table `messages` ({}): it is truncated or \
                 corrupt; those rows are read, the rest is lost",
                order.len(),
                error_chain(&stop)
            );
            Ok((order, Some(why)))
        }
    }
}

/// One `.db3` file being read.
pub(crate) struct Db3Source {
    path: PathBuf,
    conn: Connection,
    topics: HashMap<i64, Topic>,
    /// Row ids in timestamp order.
    order: Vec<i64>,
    next: usize,
    /// The running statement's time budget.
    budget: QueryBudget,
    /// The most bytes one message's `data` may hold (`limits.decompressed_mib`).
    max_message: u64,
    /// Why only part of `messages` could be read (a cut or damaged file), reported as a
    /// truncation after the intact rows.
    damaged: Option<String>,
}

/// Row ids of `messages` in timestamp order (ties by row id).
fn message_order(conn: &Connection) -> rusqlite::Result<Vec<i64>> {
    let mut stmt = conn.prepare("SELECT id FROM messages ORDER BY timestamp, id")?;
    let rows = stmt.query_map([], |row| row.get::<_, i64>(0))?;
    rows.collect()
}

/// True when SQLite says the file is damaged (a cut file reads as a malformed image).
fn is_corrupt(e: &rusqlite::Error) -> bool {
    matches!(e.sqlite_error_code(), Some(rusqlite::ErrorCode::DatabaseCorrupt))
}

/// The row ids a scan of `messages` in storage order reaches before the file's damage,
/// in timestamp order (ties by row id), and the damage met (`None` when the scan read the
/// whole table). Any other error (the time budget, say) is an error, not damage: reading part of the log because a query was interrupted
/// would give different logs on different runs. The scan reads the table itself (`NOT
/// INDEXED`): rosbag2's `timestamp` index covers both columns, so SQLite would otherwise
/// read the index, which is often the part a cut file lost.
fn intact_rows(conn: &Connection) -> rusqlite::Result<(Vec<i64>, Option<rusqlite::Error>)> {
    let mut rows: Vec<(i64, i64)> = Vec::new();
    let mut scan = || -> rusqlite::Result<()> {
        let mut stmt = conn.prepare("SELECT id, timestamp FROM messages NOT INDEXED")?;
        let mut it = stmt.query([])?;
        while let Some(row) = it.next()? {
            rows.push((row.get(1)?, row.get(0)?));
        }
        Ok(())
    };
    // A damaged page can also read as rows whose `id` or `timestamp` (both `NOT NULL`
    // integers in rosbag2's schema) is NULL: that too is where the intact part ends.
    let stop = match scan() {
        Ok(()) => None,
        Err(e) if is_corrupt(&e) || matches!(e, rusqlite::Error::InvalidColumnType(..)) => Some(e),
        Err(e) => return Err(e),
    };
    rows.sort_unstable();
    Ok((rows.into_iter().map(|(_, id)| id).collect(), stop))
}

impl Db3Source {
    /// Opens `path` read-only and reads its topics and message order; a message whose
    /// `data` holds more than `max_message` bytes is refused when it is reached.
    pub(crate) fn open(path: &Path, max_message: u64) -> Result<Self> {
        // SQLite would create a missing file; report it as the OS would.
        std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        // Read-only and immutable: SQLite then takes no locks and writes no `-wal`/`-shm`
        // file beside the input (which also lets a bag on read-only media be read).
        let uri = format!("file:{}?immutable=1", uri_path(path));
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_URI | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let conn = Connection::open_with_flags(uri, flags).map_err(|e| sql_error(path, "cannot open", e))?;
        let budget = QueryBudget::on(&conn).map_err(|e| sql_error(path, "setting a time budget", e))?;
        for table in ["topics", "messages"] {
            budget.arm();
            check_table(&conn, path, table)?;
        }
        budget.arm();
        let topics = read_topics(&conn).map_err(|e| sql_error(path, "reading table `topics`", e))?;
        budget.arm();
        let (order, damaged) = read_order(&conn, path, &budget)?;
        Ok(Self { path: path.to_path_buf(), conn, topics, order, next: 0, budget, max_message, damaged })
    }

    /// Fetches row `id` and hands it to `visit`, its payload borrowed from SQLite.
    fn fetch(&mut self, index: u64, id: i64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Result<()> {
        self.budget.arm();
        let path = &self.path;
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
        fetch_result(path, index, id, row)
    }
}

/// What fetching row `id` came to: done, or the error naming the row (`Ok(Err(topic_id))`:
/// the row names a topic `topics` does not list).
fn fetch_result(
    path: &Path,
    index: u64,
    id: i64,
    row: rusqlite::Result<Option<std::result::Result<(), i64>>>,
) -> Result<()> {
    let at = |topic: String, message: String| Error::format(path, Location::Message { index, topic }, message);
    match row {
        Ok(Some(Ok(()))) => Ok(()),
        Ok(Some(Err(topic_id))) => Err(at(
            format!("(topic id {topic_id})"),
            format!("row id {id} of table `messages` has topic_id {topic_id}, which table `topics` does not list"),
        )),
        // Listed when the order was read, gone when fetched: the file is immutable to
        // SQLite here, so the row's page is damaged (a cut file reads as empty pages).
        Ok(None) => Err(Error::truncated(
            path,
            Location::Message { index, topic: format!("(row id {id})") },
            format!(
                "row id {id} of table `messages` is listed but cannot be found: the database is truncated or \
                 corrupt; the messages before it are read"
            ),
        )),
        // The order came from the timestamp index, but the row lies in a damaged part
        // of the file: the log's intact part ends here.
        Err(e) if is_corrupt(&e) => Err(Error::truncated(
            path,
            Location::Message { index, topic: format!("(row id {id})") },
            format!(
                "SQLite: row id {id} of table `messages` lies in a damaged part of the database ({}): it is \
                 truncated or corrupt; the messages before it are read",
                error_chain(&e)
            ),
        )),
        Err(e) => {
            Err(at(format!("(row id {id})"), format!("SQLite: row id {id} of table `messages`: {}", error_chain(&e))))
        }
    }
}

impl Source for Db3Source {
    fn next_raw(&mut self, index: u64, visit: &mut dyn FnMut(RawMessage<'_>)) -> Option<Result<()>> {
        let Some(&id) = self.order.get(self.next) else {
            let why = self.damaged.take()?;
            return Some(Err(Error::truncated(&self.path, Location::File, why)));
        };
        self.next += 1;
        let fetched = self.fetch(index, id, visit);
        if fetched.as_ref().is_err_and(Error::is_truncation) {
            self.next = self.order.len(); // nothing after the damage is read
            self.damaged = None;
        }
        Some(fetched)
    }
}
