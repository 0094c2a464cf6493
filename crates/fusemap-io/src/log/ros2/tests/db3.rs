//! Tests of the rosbag2 SQLite storage: order, schema checks, read-only opening and cut
//! or damaged files.

use super::*;

#[test]
fn db3_is_read_in_timestamp_order() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bag_0.db3");
    let mut log = sample_log();
    log.reverse(); // inserted newest first: the reader must sort
    write_db3(&path, &log, false);
    let mut r = open_ros2(&path).unwrap();
    let messages = read_all(r.as_mut());
    check_sample(messages, r.stats());
}

#[test]
fn db3_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.db3");
    write_db3(&path, &sample_log(), false);
    let conn = rusqlite::Connection::open(&path).unwrap();
    conn.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (42, 4500, x'00')", []).unwrap();
    drop(conn);
    let mut r = open_ros2(&path).unwrap();
    let all = read_all(r.as_mut());
    let err = all.iter().find_map(|m| m.as_ref().err()).unwrap();
    match err {
        Error::Format { location: Location::Message { index: 8, topic }, message, .. } => {
            assert_eq!(topic, "(topic id 42)");
            assert!(message.contains("topic_id 42"), "{message}");
        }
        other => panic!("{other}"),
    }

    // A SQLite file that is not a bag.
    let other = dir.path().join("other.db3");
    rusqlite::Connection::open(&other).unwrap().execute_batch("CREATE TABLE t(x);").unwrap();
    let e = open_ros2(&other).err().unwrap();
    assert!(e.to_string().contains("table `topics`"), "{e}");
}

#[test]
fn db3_views_instead_of_tables_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    // `messages` as an endless recursive query: reading it would never end. Written as
    // SQLite writes it, and disguised as `type = 'table'` in `sqlite_master` (which the
    // reader meets once a cut file has it turn `writable_schema` on).
    let view = "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT,
                                    offered_qos_profiles TEXT);
                CREATE VIEW messages AS WITH RECURSIVE n(id) AS (SELECT 1 UNION ALL SELECT id + 1 FROM n)
                    SELECT id, 1 AS topic_id, id AS timestamp, x'00' AS data FROM n;";
    let disguise = "PRAGMA writable_schema = ON; UPDATE sqlite_master SET type = 'table' WHERE name = 'messages';";
    for (name, sql) in [("view.db3", view.to_string()), ("disguised.db3", format!("{view} {disguise}"))] {
        let path = dir.path().join(name);
        rusqlite::Connection::open(&path).unwrap().execute_batch(&sql).unwrap();
        let t0 = std::time::Instant::now();
        let e = open_ros2(&path).err().expect("refused");
        assert!(e.to_string().contains("`messages` is a view, not a table"), "{name}: {e}");
        assert!(t0.elapsed() < std::time::Duration::from_secs(1), "{name}");
    }
}

#[test]
fn db3_is_read_without_writing_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("wal.db3");
    write_db3(&path, &sample_log(), false);
    let conn = rusqlite::Connection::open(&path).unwrap();
    let mode: String = conn.query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0)).unwrap();
    assert_eq!(mode, "wal");
    drop(conn);
    let before: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    let mut r = open_ros2(&path).unwrap();
    let all = read_all(r.as_mut());
    assert!(!all.is_empty() && all.iter().all(|m| m.is_ok()));
    let after: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(before, after, "no -wal or -shm file beside the input");
}

/// A bag of `n` scans (90 beams each) with rosbag2's `timestamp` index, created with the
/// tables as rosbag2 does (`index_first`) or after the rows, as some tools do.
fn write_long_db3(path: &Path, n: usize, index_first: bool) {
    let conn = rusqlite::Connection::open(path).unwrap();
    let index = "CREATE INDEX timestamp_idx ON messages (timestamp ASC);";
    conn.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
                               timestamp INTEGER NOT NULL, data BLOB NOT NULL);
         INSERT INTO topics VALUES (1, '/scan', 'sensor_msgs/msg/LaserScan', 'cdr', '');",
    )
    .unwrap();
    if index_first {
        conn.execute_batch(index).unwrap();
    }
    for i in 0..n {
        let ranges = vec![1.0 + i as f32 * 1e-3; 90];
        let data = scan_payload(i as i32, 0, "laser", &ranges);
        conn.execute(
            "INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?1, ?2)",
            rusqlite::params![1_000 * (i as i64 + 1), data],
        )
        .unwrap();
    }
    if !index_first {
        conn.execute_batch(index).unwrap();
    }
}

#[test]
fn a_cut_db3_maps_its_intact_rows_and_says_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let n = 2_000;
    for index_first in [true, false] {
        let path = dir.path().join(format!("cut-{index_first}.db3"));
        write_long_db3(&path, n, index_first);
        let whole = read_all(open_ros2(&path).unwrap().as_mut());
        assert_eq!(whole.len(), n);
        assert!(whole.iter().all(|m| m.is_ok()));
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let mut r = open_ros2(&path).expect("a cut bag opens");
        let got = read_all(r.as_mut());
        let (last, read) = got.split_last().unwrap();
        let e = last.as_ref().expect_err("the read ends in an error");
        assert!(e.is_truncation(), "index first {index_first}: {e}");
        assert!(e.to_string().contains("truncated or corrupt"), "{e}");
        // The intact part is read, in order, and nothing past the damage.
        assert!(read.len() > n / 5 && read.len() < n, "index first {index_first}: {} of {n} read", read.len());
        let stamps: Vec<i64> = read
            .iter()
            .map(|m| match m.as_ref().unwrap() {
                LogMessage::Scan(s) => s.receive_stamp.unwrap().0,
                other => panic!("{other:?}"),
            })
            .collect();
        assert!(stamps.windows(2).all(|w| w[0] < w[1]));
        assert!(r.next_message().is_none(), "nothing after the truncation");
    }
}
