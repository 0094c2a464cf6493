//! Tests of the ROS 2 readers: CDR payloads written byte by byte here, and containers
//! written with the `mcap` crate's writer and plain SQL. (Fixtures from third-party ROS
//! tools are checked in `tests/ros2_fixtures.rs`.)

use super::cdr::{decode_cdr, CdrError};
use super::msgs::{nav_msgs, sensor_msgs, tf2_msgs};
use super::*;
use std::collections::BTreeMap;
use std::path::Path;

mod camera;
mod cdr_payloads;
mod db3;
mod pose_sensors;

/// A little-endian CDR writer for tests. Padding is 0xAA, so a decoder that reads
/// padding as data gets visibly wrong values.
struct W {
    buf: Vec<u8>,
}

impl W {
    fn new() -> Self {
        W { buf: vec![0x00, 0x01, 0x00, 0x00] }
    }
    fn align(&mut self, n: usize) {
        while !(self.buf.len() - 4).is_multiple_of(n) {
            self.buf.push(0xAA);
        }
    }
    fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f32(&mut self, v: f32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f64s(&mut self, v: &[f64]) -> &mut Self {
        for &x in v {
            self.f64(x);
        }
        self
    }
    fn string(&mut self, s: &str) -> &mut Self {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        self
    }
    fn f32_seq(&mut self, v: &[f32]) -> &mut Self {
        self.u32(v.len() as u32);
        for &x in v {
            self.f32(x);
        }
        self
    }
    fn header(&mut self, sec: i32, nanosec: u32, frame: &str) -> &mut Self {
        self.i32(sec).u32(nanosec).string(frame)
    }
    fn done(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.buf)
    }
}

fn scan_payload(sec: i32, nanosec: u32, frame: &str, ranges: &[f32]) -> Vec<u8> {
    W::new()
        .header(sec, nanosec, frame)
        .f32(-1.5)
        .f32(1.5)
        .f32(0.25)
        .f32(0.001)
        .f32(0.1)
        .f32(0.05)
        .f32(30.0)
        .f32_seq(ranges)
        .f32_seq(&[])
        .done()
}

fn yaw_quaternion(yaw: f64) -> [f64; 4] {
    [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()]
}

fn odom_payload(sec: i32, frame: &str, child: &str, x: f64, y: f64, yaw: f64) -> Vec<u8> {
    let mut w = W::new();
    w.header(sec, 7, frame).string(child);
    w.f64s(&[x, y, 0.0]).f64s(&yaw_quaternion(yaw)).f64s(&[0.5; 36]);
    w.f64s(&[0.1, 0.0, 0.0, 0.0, 0.0, 0.2]).f64s(&[0.25; 36]);
    w.done()
}

fn tf_payload(transforms: &[(&str, &str, [f64; 3])]) -> Vec<u8> {
    let mut w = W::new();
    w.u32(transforms.len() as u32);
    for (i, (parent, child, t)) in transforms.iter().enumerate() {
        w.header(100 + i as i32, 5, parent).string(child);
        w.f64s(t).f64s(&[0.0, 0.0, 0.0, 1.0]);
    }
    w.done()
}

fn imu_payload() -> Vec<u8> {
    let mut w = W::new();
    w.header(3, 4, "imu_link");
    w.f64s(&[0.0, 0.0, 0.0, 1.0]).f64s(&[0.01; 9]);
    w.f64s(&[0.1, 0.2, 0.3]).f64s(&[0.02; 9]);
    w.f64s(&[0.0, 0.0, 9.81]).f64s(&[0.03; 9]);
    w.done()
}

#[test]
fn type_names() {
    assert_eq!(KnownType::from_name("sensor_msgs/msg/LaserScan"), Some(KnownType::LaserScan));
    assert_eq!(KnownType::from_name("sensor_msgs/LaserScan"), Some(KnownType::LaserScan));
    assert_eq!(KnownType::from_name("sensor_msgs/msg/PointCloud2"), None);
    for k in KnownType::ALL {
        assert_eq!(KnownType::from_name(k.name()), Some(k));
    }
    assert_eq!(decode_message("std_msgs/msg/String", "/chatter", None, b"garbage"), Ok(None));
}

#[test]
fn readers_can_move_to_another_thread() {
    fn send<T: Send>() {}
    send::<Ros2Reader>();
}

#[test]
fn sniffing() {
    assert!(sniff_mcap(b"\x89MCAP0\r\n\x01\x02"));
    assert!(!sniff_mcap(b"\x89MCAP0\r"));
    assert!(!sniff_mcap(b"SQLite format 3\0"));
    let dir = tempfile::tempdir().unwrap();
    assert!(!is_rosbag2_dir(dir.path()));
    std::fs::write(dir.path().join("metadata.yaml"), "x").unwrap();
    assert!(is_rosbag2_dir(dir.path()));
    assert!(!is_rosbag2_dir(&dir.path().join("metadata.yaml")));
}

// --- containers -------------------------------------------------------------------

/// One message to store: topic, type, encoding, log time, payload.
type Msg<'a> = (&'a str, &'a str, &'a str, u64, Vec<u8>);

fn write_mcap(path: &Path, compression: Option<mcap::Compression>, msgs: &[Msg<'_>]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w =
        mcap::WriteOptions::new().compression(compression).chunk_size(Some(200)).profile("ros2").create(file).unwrap();
    let mut channels: BTreeMap<(String, String, String), u16> = BTreeMap::new();
    for (seq, (topic, ty, enc, t, data)) in msgs.iter().enumerate() {
        let key = (topic.to_string(), ty.to_string(), enc.to_string());
        let id = match channels.get(&key) {
            Some(&id) => id,
            None => {
                let schema = w.add_schema(ty, "ros2msg", b"# definition not needed here").unwrap();
                let id = w.add_channel(schema, topic, enc, &BTreeMap::new()).unwrap();
                channels.insert(key, id);
                id
            }
        };
        let header =
            mcap::records::MessageHeader { channel_id: id, sequence: seq as u32, log_time: *t, publish_time: *t };
        w.write_to_known_channel(&header, data).unwrap();
    }
    w.finish().unwrap();
}

fn write_db3(path: &Path, msgs: &[Msg<'_>], compress: bool) {
    let conn = rusqlite::Connection::open(path).unwrap();
    conn.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
                               timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    )
    .unwrap();
    let mut topics: BTreeMap<&str, i64> = BTreeMap::new();
    for (topic, ty, enc, t, data) in msgs {
        let next = topics.len() as i64 + 1;
        let id = *topics.entry(topic).or_insert_with(|| {
            conn.execute("INSERT INTO topics VALUES (?1, ?2, ?3, ?4, '')", rusqlite::params![next, topic, ty, enc])
                .unwrap();
            next
        });
        let data = if compress { zstd::encode_all(&data[..], 3).unwrap() } else { data.clone() };
        conn.execute(
            "INSERT INTO messages(topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
            rusqlite::params![id, *t as i64, data],
        )
        .unwrap();
    }
}

fn read_all(reader: &mut dyn LogReader) -> Vec<Result<LogMessage>> {
    std::iter::from_fn(|| reader.next_message()).collect()
}

fn sample_log() -> Vec<Msg<'static>> {
    vec![
        ("/tf_static", "tf2_msgs/msg/TFMessage", "cdr", 1_000, tf_payload(&[("base_link", "laser", [0.0; 3])])),
        ("/scan", "sensor_msgs/msg/LaserScan", "cdr", 2_000, scan_payload(1, 0, "laser", &[1.0, 2.0])),
        ("/chatter", "std_msgs/msg/String", "cdr", 2_500, vec![0, 1, 0, 0, 3, 0, 0, 0, b'h', b'i', 0]),
        ("/odom", "nav_msgs/msg/Odometry", "cdr", 3_000, odom_payload(1, "odom", "base_link", 1.0, 0.0, 0.0)),
        ("/chatter", "std_msgs/msg/String", "cdr", 3_500, vec![0, 1, 0, 0, 1, 0, 0, 0, 0]),
        ("/scan_json", "sensor_msgs/msg/LaserScan", "json", 3_700, b"{}".to_vec()),
        ("/imu", "sensor_msgs/msg/Imu", "cdr", 4_000, imu_payload()),
        ("/scan", "sensor_msgs/msg/LaserScan", "cdr", 5_000, scan_payload(2, 0, "laser", &[3.0])),
    ]
}

fn check_sample(messages: Vec<Result<LogMessage>>, stats: &ReadStats) {
    let messages: Vec<LogMessage> = messages.into_iter().map(|m| m.unwrap()).collect();
    let kinds: Vec<&str> = messages
        .iter()
        .map(|m| match m {
            LogMessage::Scan(_) => "scan",
            LogMessage::Odometry(_) => "odom",
            LogMessage::Tf(_) => "tf",
            LogMessage::Imu(_) => "imu",
            LogMessage::Gnss(_) => "gnss",
            LogMessage::Pose(_) => "pose",
            LogMessage::Image(_) | LogMessage::ImageHeader(_) => "image",
            LogMessage::CameraInfo(_) => "camera info",
        })
        .collect();
    assert_eq!(kinds, ["tf", "scan", "odom", "imu", "scan"]);
    let LogMessage::Tf(tf) = &messages[0] else { unreachable!() };
    assert!(tf.is_static);
    assert_eq!(tf.receive_stamp, Some(Stamp(1_000)));
    let LogMessage::Scan(scan) = &messages[4] else { unreachable!() };
    assert_eq!(scan.receive_stamp, Some(Stamp(5_000)));
    assert_eq!(scan.scan.stamp, Stamp(2_000_000_000));
    assert_eq!(scan.scan.ranges, [3.0]);
    assert_eq!(stats.skipped_by_type.get("std_msgs/msg/String"), Some(&2));
    assert_eq!(stats.skipped_by_type.get("sensor_msgs/msg/LaserScan (json encoding)"), Some(&1));
    assert_eq!(stats.skipped_by_type.len(), 2);
}

#[test]
fn mcap_uncompressed_zstd_and_lz4_chunks() {
    let dir = tempfile::tempdir().unwrap();
    for (name, compression) in
        [("plain", None), ("zstd", Some(mcap::Compression::Zstd)), ("lz4", Some(mcap::Compression::Lz4))]
    {
        let path = dir.path().join(format!("{name}.mcap"));
        write_mcap(&path, compression, &sample_log());
        let mut r = open_ros2(&path).unwrap();
        let messages = read_all(r.as_mut());
        check_sample(messages, r.stats());
    }
}

#[test]
fn rosbag2_directories_with_split_files_and_compression() {
    let log = sample_log();
    let (first, second) = log.split_at(3);
    let dir = tempfile::tempdir().unwrap();

    // MCAP storage split over two files, the metadata listing them in ruamel's style.
    let bag = dir.path().join("mcap_bag");
    std::fs::create_dir(&bag).unwrap();
    write_mcap(&bag.join("b_0.mcap"), Some(mcap::Compression::Zstd), first);
    write_mcap(&bag.join("b_1.mcap"), None, second);
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n  relative_file_paths:\n  - b_0.mcap\n  - b_1.mcap\n  compression_mode: ''\n",
    )
    .unwrap();
    assert!(is_rosbag2_dir(&bag));
    let mut r = open_ros2(&bag).unwrap();
    check_sample(read_all(r.as_mut()), r.stats());
    // The metadata file itself opens the bag too.
    let mut r = open_ros2(&bag.join("metadata.yaml")).unwrap();
    check_sample(read_all(r.as_mut()), r.stats());

    // SQLite storage with per-message zstd compression.
    let bag = dir.path().join("db3_bag");
    std::fs::create_dir(&bag).unwrap();
    write_db3(&bag.join("c_0.db3"), first, true);
    write_db3(&bag.join("c_1.db3"), second, true);
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  relative_file_paths:\n    - db3_bag/c_0.db3\n    - c_1.db3\n  compression_format: zstd\n  compression_mode: MESSAGE\n",
    )
    .unwrap();
    let mut r = open_ros2(&bag).unwrap();
    check_sample(read_all(r.as_mut()), r.stats());

    // MCAP storage with whole-file zstd compression.
    let bag = dir.path().join("file_bag");
    std::fs::create_dir(&bag).unwrap();
    let plain = dir.path().join("whole.mcap");
    write_mcap(&plain, None, &log);
    let compressed = zstd::encode_all(std::fs::File::open(&plain).unwrap(), 3).unwrap();
    std::fs::write(bag.join("d_0.mcap.zstd"), compressed).unwrap();
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: [d_0.mcap.zstd]\n  compression_format: zstd\n  compression_mode: FILE\n",
    )
    .unwrap();
    let mut r = open_ros2(&bag).unwrap();
    check_sample(read_all(r.as_mut()), r.stats());
}

#[test]
fn rosbag2_metadata_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let meta = dir.path().join("metadata.yaml");
    std::fs::write(&meta, "rosbag2_bagfile_information:\n  relative_file_paths:\n    - missing.mcap\n").unwrap();
    let e = open_ros2(dir.path()).err().unwrap();
    match &e {
        Error::Format { path, location: Location::Field(f), message } => {
            assert_eq!(path, &meta);
            assert_eq!(f, "relative_file_paths");
            assert!(message.contains("missing.mcap"), "{message}");
        }
        other => panic!("{other}"),
    }
    std::fs::write(&meta, "rosbag2_bagfile_information:\n  version: x\n  relative_file_paths: []\n").unwrap();
    let e = open_ros2(dir.path()).err().unwrap();
    assert!(matches!(e, Error::Format { location: Location::Line(2), .. }), "{e}");
}

#[test]
fn a_bad_payload_names_file_message_and_topic_and_reading_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    let mut be = scan_payload(1, 0, "laser", &[1.0]);
    be[1] = 0;
    let log: Vec<Msg<'_>> = vec![
        ("/chatter", "std_msgs/msg/String", "cdr", 1, vec![]),
        ("/scan", "sensor_msgs/msg/LaserScan", "cdr", 2, be),
        ("/odom", "nav_msgs/msg/Odometry", "cdr", 3, odom_payload(1, "odom", "b", 0.0, 0.0, 0.0)[..50].to_vec()),
        ("/scan", "sensor_msgs/msg/LaserScan", "cdr", 4, scan_payload(1, 0, "laser", &[1.0])),
    ];
    write_mcap(&path, None, &log);
    let mut r = open_ros2(&path).unwrap();
    let all = read_all(r.as_mut());
    assert_eq!(all.len(), 3);
    match &all[0] {
        Err(Error::Format { path: p, location, message }) => {
            assert_eq!(p, &path);
            assert_eq!(location, &Location::Message { index: 2, topic: "/scan".into() });
            assert_eq!(
                message,
                "sensor_msgs/msg/LaserScan: CDR encapsulation is big-endian (0x0000); fusemap reads little-endian CDR (0x0001)"
            );
        }
        other => panic!("{other:?}"),
    }
    match &all[1] {
        Err(e @ Error::Format { location, message, .. }) => {
            assert_eq!(location, &Location::Message { index: 3, topic: "/odom".into() });
            assert!(message.starts_with("nav_msgs/msg/Odometry: truncated: `pose.pose.position"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(&all[2], Ok(LogMessage::Scan(_))));
    assert_eq!(r.stats().skipped_by_type.get("std_msgs/msg/String"), Some(&1));
}

#[test]
fn truncated_mcap_files_end_in_an_error_not_a_panic() {
    let mut truncations = 0;
    let dir = tempfile::tempdir().unwrap();
    let full_path = dir.path().join("full.mcap");
    write_mcap(&full_path, Some(mcap::Compression::Zstd), &sample_log());
    let full = std::fs::read(&full_path).unwrap();
    let cut_path = dir.path().join("cut.mcap");
    let step = (full.len() / 97).max(1);
    for cut in (8..full.len()).step_by(step).chain([full.len() - 1]) {
        std::fs::write(&cut_path, &full[..cut]).unwrap();
        let mut r = open_ros2(&cut_path).unwrap();
        let all = read_all(r.as_mut());
        let last = all.last().expect("at least the error");
        // The file ending inside a record is a truncation (the messages before it are
        // sound); a cut that leaves a record's length pointing past a chunk is damage.
        match last {
            Err(Error::Format { location: Location::File, message, .. })
            | Err(Error::Truncated { location: Location::File, message, .. }) => {
                assert!(message.starts_with("MCAP: "), "{message}")
            }
            other => panic!("cut at {cut}: {other:?}"),
        }
        assert!(all[..all.len() - 1].iter().all(|m| m.is_ok()));
        truncations += usize::from(last.as_ref().is_err_and(Error::is_truncation));
    }
    assert!(truncations > 50, "{truncations} cuts read as truncations");
}

#[test]
fn unknown_files_are_refused_by_content() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.mcap");
    std::fs::write(&path, b"FLASER 0 0 0").unwrap();
    let e = open_ros2(&path).err().unwrap();
    assert!(e.to_string().contains("46 4c 41 53"), "{e}");
    assert!(matches!(open_ros2(&dir.path().join("nope.mcap")), Err(Error::Io { .. })));
    assert!(matches!(open_ros2(&dir.path().join("nope.db3")), Err(Error::Io { .. })));
    assert!(open_ros2(dir.path()).is_err());
}

#[test]
fn a_message_or_chunk_inflating_past_the_limit_is_refused_where_it_is_met() {
    let dir = tempfile::tempdir().unwrap();
    let log = sample_log();
    let read = |path: &Path, limit: u64| {
        let options = ReadOptions { max_decompressed_bytes: limit, ..Default::default() };
        let mut r = Ros2Reader::open_with(path, options).unwrap();
        read_all(&mut r)
    };
    // rosbag2 per-message zstd: the largest message inflates to `n`.
    let bag = dir.path().join("db3_bag");
    std::fs::create_dir(&bag).unwrap();
    write_db3(&bag.join("c_0.db3"), &log, true);
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths: [c_0.db3]\n  compression_format: zstd\n  compression_mode: MESSAGE\n",
    )
    .unwrap();
    let largest = log.iter().max_by_key(|m| m.4.len()).unwrap();
    let n = largest.4.len() as u64;
    assert!(read(&bag, n).iter().all(|m| m.is_ok()));
    let got = read(&bag, n - 1);
    let e = got.iter().find_map(|m| m.as_ref().err()).expect("the message past the limit is an error");
    let text = e.to_string();
    let topic = format!("`{}`", largest.0);
    for part in ["inflates past the limit", &format!("{} bytes", n - 1), "limits.decompressed_mib", &topic] {
        assert!(text.contains(part), "`{part}` in {text}");
    }
    assert!(!e.is_skippable(), "a broken budget ends the run: {e}");
    // A plain `.db3` message past the limit: refused by `length(data)`, before SQLite
    // hands over the blob.
    let plain = dir.path().join("plain.db3");
    write_db3(&plain, &log, false);
    assert!(read(&plain, n).iter().all(|m| m.is_ok()));
    let got = read(&plain, n - 1);
    let e = got.iter().find_map(|m| m.as_ref().err()).expect("the message past the limit is an error");
    assert!(matches!(e, Error::Limit { .. }), "{e}");
    let parts =
        [format!("holds {n} bytes"), format!("limit of {} bytes", n - 1), "limits.decompressed_mib".into(), topic];
    for part in parts {
        assert!(e.to_string().contains(&part), "`{part}` in {e}");
    }
    // An MCAP chunk whose records inflate past the limit: refused by its stated size.
    let path = dir.path().join("zstd.mcap");
    write_mcap(&path, Some(mcap::Compression::Zstd), &log);
    assert!(read(&path, 1 << 20).iter().all(|m| m.is_ok()));
    let got = read(&path, 64);
    let e = got.iter().find_map(|m| m.as_ref().err()).expect("the chunk past the limit is an error");
    assert!(e.to_string().contains("over the limit of 64 bytes (limits.decompressed_mib"), "{e}");
}

#[test]
fn a_corrupt_length_in_a_whole_mcap_is_damage_not_a_cut() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("full.mcap");
    write_mcap(&path, None, &sample_log());
    let mut bytes = std::fs::read(&path).unwrap();
    // The Header record follows the 8-byte magic: opcode, then its u64 length. Make it
    // claim the whole file, so the reader runs out of bytes inside it.
    let len = bytes.len() as u64;
    bytes[9..17].copy_from_slice(&len.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let mut r = open_ros2(&path).unwrap();
    let last = read_all(r.as_mut()).pop().unwrap().unwrap_err();
    assert!(!last.is_truncation(), "{last}");
    assert!(last.to_string().contains("the length is corrupt"), "{last}");
    // The same file cut short (no closing magic) is a cut.
    std::fs::write(&path, &bytes[..bytes.len() - 40]).unwrap();
    let mut r = open_ros2(&path).unwrap();
    let last = read_all(r.as_mut()).pop().unwrap().unwrap_err();
    assert!(last.is_truncation(), "{last}");
}
