//! Tests of the ROS 1 bag reader: synthetic bags written byte by byte here, damaged in
//! every way the reader must survive, and the shared SLAM-benchmark bags.

use super::*;
use crate::log::{ScanMessage, TfMessage};
use crate::testdata;
use fusemap_core::geometry::Pose2;
use fusemap_core::time::Stamp;
use std::collections::BTreeMap;

mod bags;
mod camera;
mod pose_sensors;

use bags::*;

// ---------------------------------------------------------------------------------------
// Decoding.

#[test]
fn sniff_recognises_the_version_line() {
    assert!(sniff(b"#ROSBAG V2.0\n\x04\x00\x00\x00"));
    assert!(sniff(record::MAGIC));
    assert!(!sniff(b"#ROSBAG V1.2\n"));
    assert!(!sniff(b"#ROSBAG V2.0"));
    assert!(!sniff(b""));
    assert!(!sniff(b"\x89PNG\r\n\x1a\n"));
}

#[test]
fn decodes_every_field_of_an_uncompressed_chunk() {
    let bytes = bag(vec![(Compression::None, standard_records())]);
    let (messages, error, stats) = read_bytes(&bytes);
    assert!(error.is_none(), "{error:?}");
    assert_eq!(messages, standard_messages());
    assert_eq!(stats.skipped_by_type, BTreeMap::from([("std_msgs/String".to_string(), 1)]));
    assert_eq!(stats.malformed, 0);
}

#[test]
fn bz2_and_lz4_chunks_decode_like_uncompressed_ones() {
    for compression in [Compression::Bz2, Compression::Lz4] {
        let bytes = bag(vec![(compression, standard_records())]);
        let (messages, error, _) = read_bytes(&bytes);
        assert!(error.is_none(), "{compression:?}: {error:?}");
        assert_eq!(messages, standard_messages(), "{compression:?}");
    }
}

#[test]
fn messages_come_in_file_order_across_chunks_of_mixed_compression() {
    // Connections declared in one chunk serve the next ones; stamps go backwards on
    // purpose: the reader keeps file order.
    let odom = |i: u32| msg(ODOM, (50 - i, 0), odom_payload((50 - i, 0), f64::from(i), 0.0));
    let bytes = bag(vec![
        (Compression::Lz4, vec![Inner::Conn(ODOM), odom(0), odom(1)]),
        (Compression::None, vec![odom(2)]),
        (Compression::Bz2, vec![odom(3), Inner::Conn(ODOM), odom(4)]),
    ]);
    let (messages, error, _) = read_bytes(&bytes);
    assert!(error.is_none(), "{error:?}");
    let xs: Vec<f64> = messages
        .iter()
        .map(|m| match m {
            LogMessage::Odometry(o) => o.pose.x,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(xs, [0.0, 1.0, 2.0, 3.0, 4.0]);
}

#[test]
fn a_large_scan_decodes_exactly() {
    let ranges: Vec<f32> = (0..100_000).map(|i| i as f32 * 0.25).collect();
    let bytes =
        bag(vec![(Compression::Lz4, vec![Inner::Conn(SCAN), msg(SCAN, (1, 0), scan_payload((1, 0), &ranges, &[]))])]);
    let (messages, error, _) = read_bytes(&bytes);
    assert!(error.is_none(), "{error:?}");
    match messages.as_slice() {
        [LogMessage::Scan(s)] => assert_eq!(s.scan.ranges, ranges),
        other => panic!("{other:?}"),
    }
}

#[test]
fn open_reads_a_file_and_names_it() {
    let dir = crate::testdata::temp_dir("ros1-open");
    let path = dir.join("standard.bag");
    std::fs::write(&path, bag(vec![(Compression::Bz2, standard_records())])).unwrap();
    let mut reader = BagReader::open(&path).unwrap();
    assert_eq!(reader.path(), path);
    let mut messages = Vec::new();
    while let Some(m) = reader.next_message() {
        messages.push(m.unwrap());
    }
    assert_eq!(messages, standard_messages());
    std::fs::remove_dir_all(&dir).unwrap();

    match BagReader::open(dir.join("missing.bag")) {
        Err(Error::Io { path, .. }) => assert_eq!(path, dir.join("missing.bag")),
        other => panic!("{:?}", other.err()),
    }
}

// ---------------------------------------------------------------------------------------
// Bad input.

#[test]
fn not_a_bag_is_refused_at_byte_zero() {
    for (bytes, expected) in [
        (&b""[..], "not a ROS 1 bag (v2.0) file"),
        (b"hello world, this is text", "not a ROS 1 bag (v2.0) file"),
        (
            b"#ROSBAG V1.2\n\0\0\0\0",
            "not a ROS 1 bag (v2.0) file: it is a version 1.2 bag, which fusemap does not read",
        ),
    ] {
        let (location, message) = format_error(BagReader::from_reader(bytes, "test.bag").err());
        assert_eq!(location, Location::Offset(0));
        assert_eq!(message, expected);
    }
    let (location, message) = format_error(BagReader::from_reader(record::MAGIC, "test.bag").err());
    assert_eq!(location, Location::Offset(13));
    assert_eq!(message, "the file ends after its first line");
}

#[test]
fn every_truncation_is_an_error_and_keeps_a_correct_prefix() {
    for compression in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let bytes = bag(vec![
            (compression, standard_records()),
            (compression, vec![msg(SCAN, (200, 0), scan_payload((200, 0), &[4.0], &[]))]),
        ]);
        let (all, error, _) = read_bytes(&bytes);
        assert!(error.is_none());
        for cut in 0..bytes.len() {
            let (messages, error, _) = read_bytes(&bytes[..cut]);
            assert!(error.is_some(), "{compression:?}: cut at {cut} of {} ended cleanly", bytes.len());
            assert!(all.starts_with(&messages), "{compression:?}: cut at {cut} changed the messages before it");
            let (location, _) = format_error(error);
            assert!(matches!(location, Location::Offset(o) if o <= cut as u64));
        }
    }
}

#[test]
fn truncated_record_error_names_the_record() {
    let bytes = bag(vec![(Compression::None, standard_records())]);
    let cut = bytes.len() - 3;
    let (_, error, _) = read_bytes(&bytes[..cut]);
    assert!(error.as_ref().is_some_and(Error::is_truncation), "{error:?}");
    let (_, message) = format_error(error);
    assert!(message.starts_with("truncated record: its data claims"), "{message}");
}

/// A small deterministic generator (xorshift) for the corruption tests.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

#[test]
fn corrupted_bytes_never_panic() {
    for compression in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let bytes = bag(vec![(compression, standard_records())]);
        for i in 0..bytes.len() {
            for flip in [0xff, 0x01, 0x80] {
                let mut bad = bytes.clone();
                bad[i] ^= flip;
                let _ = read_bytes(&bad);
            }
        }
    }
    // Garbage after a valid start, and garbage lengths.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let start = bag(vec![(Compression::None, standard_records())]);
    for _ in 0..300 {
        let keep = 13 + rng.next() as usize % (start.len() - 13);
        let mut bad = start[..keep].to_vec();
        let extra = rng.next() as usize % 300;
        bad.extend((0..extra).map(|_| rng.next() as u8));
        let _ = read_bytes(&bad);
        let mut garbage = record::MAGIC.to_vec();
        garbage.extend((0..extra).map(|_| rng.next() as u8));
        let (_, error, _) = read_bytes(&garbage);
        assert!(error.is_some());
    }
}

#[test]
fn unknown_compression_is_refused_at_the_chunk() {
    let bytes = bag(vec![(Compression::Named("zstd"), standard_records())]);
    let chunk_offset = 13 + record_len(&bytes, 13);
    let (messages, error, _) = read_bytes(&bytes);
    assert!(messages.is_empty());
    let (location, message) = format_error(error);
    assert_eq!(location, Location::Offset(chunk_offset as u64));
    assert!(message.starts_with("chunk compression `zstd` is not supported"), "{message}");
}

/// The total length of the top-level record at `at`.
fn record_len(bytes: &[u8], at: usize) -> usize {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    let header = u32_at(at);
    4 + header + 4 + u32_at(at + 4 + header)
}

#[test]
fn unknown_types_are_counted_and_still_numbered() {
    let bytes = bag(vec![(
        Compression::None,
        vec![
            Inner::Conn(CHATTER),
            msg(CHATTER, (1, 0), string_payload("a")),
            msg(CHATTER, (2, 0), string_payload("b")),
            Inner::Conn(SCAN),
            msg(SCAN, (3, 0), vec![1, 2, 3]),
        ],
    )]);
    let (messages, error, stats) = read_bytes(&bytes);
    assert!(messages.is_empty());
    assert_eq!(stats.skipped_by_type["std_msgs/String"], 2);
    let (location, message) = format_error(error);
    assert_eq!(location, Location::Message { index: 3, topic: "/scan".into() });
    assert_eq!(message, "LaserScan: header.seq: needs 4 bytes but 3 remain");
}

#[test]
fn a_scan_whose_ranges_overflow_the_payload_is_a_message_error() {
    let mut payload = scan_payload((1, 0), &[], &[]);
    // Replace the two empty arrays by a ranges count of 1e9 followed by 12 bytes.
    payload.truncate(payload.len() - 8);
    payload.extend(1_000_000_000u32.to_le_bytes());
    payload.extend([0u8; 12]);
    let bytes = bag(vec![(
        Compression::Bz2,
        vec![Inner::Conn(SCAN), msg(SCAN, (1, 0), scan_payload((1, 0), &[1.0], &[])), msg(SCAN, (2, 0), payload)],
    )]);
    let (messages, error, _) = read_bytes(&bytes);
    assert_eq!(messages.len(), 1);
    let (location, message) = format_error(error);
    assert_eq!(location, Location::Message { index: 2, topic: "/scan".into() });
    assert_eq!(message, "LaserScan: ranges array claims 1000000000 elements but 12 bytes remain");
}

#[test]
fn malformed_payloads_name_the_field() {
    let mut short_intensities = scan_payload((1, 0), &[1.0], &[]);
    short_intensities.truncate(short_intensities.len() - 4);
    short_intensities.extend(2u32.to_le_bytes());
    short_intensities.extend([0; 4]);
    let mut trailing = scan_payload((1, 0), &[1.0], &[]);
    trailing.push(0);
    let mut short_odom = odom_payload((1, 0), 0.0, 0.0);
    short_odom.truncate(short_odom.len() - 8);
    let mut huge_tf = tf_payload(&[]);
    huge_tf[..4].copy_from_slice(&u32::MAX.to_le_bytes());
    let mut short_imu = imu_payload((1, 0));
    short_imu.pop();
    let identity = [0.0, 0.0, 0.0, 1.0];
    let mut short_tf = tf_payload(&[((1, 0), "a", "b", [0.0; 3], identity), ((1, 0), "a", "c", [0.0; 3], identity)]);
    short_tf.truncate(short_tf.len() - 8);
    let mut long_frame = Vec::new();
    ros_header(&mut long_frame, 0, (1, 0), "x");
    long_frame[12..16].copy_from_slice(&1000u32.to_le_bytes());
    let cases = [
        (SCAN, short_intensities, "LaserScan: intensities array claims 2 elements but 4 bytes remain"),
        (
            SCAN,
            trailing,
            "LaserScan: 1 bytes left over after the message's last field (the layout \
             differs from the standard definition)",
        ),
        (ODOM, short_odom, "Odometry: twist.covariance: needs 288 bytes but 280 remain"),
        (TF, huge_tf, "TFMessage: transforms array claims 4294967295 elements but 0 bytes remain"),
        (IMU, short_imu, "Imu: linear_acceleration_covariance: needs 72 bytes but 71 remain"),
        (TF, short_tf, "TFMessage: transforms[1].transform.rotation.w: needs 8 bytes but 0 remain"),
        (SCAN, long_frame, "LaserScan: header.frame_id: claims 1000 bytes but 1 remain"),
    ];
    for (conn, payload, expected) in cases {
        let bytes = bag(vec![(Compression::None, vec![Inner::Conn(conn), msg(conn, (1, 0), payload)])]);
        let (_, error, _) = read_bytes(&bytes);
        let (location, message) = format_error(error);
        assert_eq!(location, Location::Message { index: 1, topic: conn.topic.into() });
        assert_eq!(message, expected);
    }
}

#[test]
fn a_container_error_is_not_skippable() {
    let odd = Conn { md5: "0123456789abcdef0123456789abcdef", ..SCAN };
    let bytes = bag(vec![(Compression::None, vec![Inner::Conn(odd)])]);
    let (_, error, _) = read_bytes(&bytes);
    assert!(!error.unwrap().is_skippable());
}

#[test]
fn a_known_type_with_another_md5sum_is_refused() {
    let odd = Conn { md5: "0123456789abcdef0123456789abcdef", ..SCAN };
    let bytes = bag(vec![(Compression::None, vec![Inner::Conn(odd)])]);
    let (_, error, _) = read_bytes(&bytes);
    let (location, message) = format_error(error);
    assert!(matches!(location, Location::Offset(_)));
    assert!(message.contains("`/scan`"), "{message}");
    assert!(message.contains("0123456789abcdef0123456789abcdef"), "{message}");
    assert!(message.contains(SCAN_MD5), "{message}");
}

#[test]
fn a_chunk_of_the_wrong_size_is_an_error() {
    for compression in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let mut bytes = bag(vec![(compression, standard_records())]);
        // The chunk's `size` field is the last 4 bytes of its header.
        let chunk = 13 + record_len(&bytes, 13);
        let header_len = u32::from_le_bytes(bytes[chunk..chunk + 4].try_into().unwrap());
        let size_at = chunk + 4 + header_len as usize - 4;
        let size = u32::from_le_bytes(bytes[size_at..size_at + 4].try_into().unwrap());
        for wrong in [size - 1, size + 1] {
            bytes[size_at..size_at + 4].copy_from_slice(&wrong.to_le_bytes());
            let (messages, error, _) = read_bytes(&bytes);
            assert!(messages.is_empty());
            let (location, message) = format_error(error);
            assert_eq!(location, Location::Offset(chunk as u64));
            assert!(
                message.starts_with(&format!("chunk header says {wrong} uncompressed bytes")),
                "{compression:?}: {message}"
            );
        }
    }
}

#[test]
fn corrupt_compressed_data_is_a_decompression_error() {
    for (compression, name) in [(Compression::Bz2, "bz2"), (Compression::Lz4, "lz4")] {
        let mut bytes = bag(vec![(compression, standard_records())]);
        let chunk = 13 + record_len(&bytes, 13);
        let header_len = u32::from_le_bytes(bytes[chunk..chunk + 4].try_into().unwrap());
        let data = chunk + 4 + header_len as usize + 4;
        // Past the stream's own header: damage the compressed blocks.
        for b in &mut bytes[data + 12..data + 40] {
            *b = 0x55;
        }
        let (_, error, _) = read_bytes(&bytes);
        let (location, message) = format_error(error);
        assert_eq!(location, Location::Offset(chunk as u64));
        assert!(
            message.starts_with(&format!("{name} decompression of the chunk failed"))
                || message.starts_with("chunk header says"),
            "{message}"
        );
    }
}

#[test]
fn a_message_before_its_connection_is_an_error() {
    let bytes = bag(vec![(Compression::None, vec![msg(ODOM, (1, 0), odom_payload((1, 0), 0.0, 0.0))])]);
    let (_, error, _) = read_bytes(&bytes);
    let (location, message) = format_error(error);
    // Uncompressed chunk: the exact byte of the record.
    let chunk = 13 + record_len(&bytes, 13);
    let header_len = u32::from_le_bytes(bytes[chunk..chunk + 4].try_into().unwrap());
    let data = chunk + 4 + header_len as usize + 4;
    assert_eq!(location, Location::Offset(data as u64));
    assert_eq!(
        message,
        "message data record refers to connection 1, which no connection record before it \
         defines"
    );
}

#[test]
fn errors_in_compressed_chunks_give_the_chunk_and_the_offset_inside() {
    let bytes = bag(vec![(
        Compression::Lz4,
        vec![Inner::Conn(ODOM), msg(ODOM, (1, 0), odom_payload((1, 0), 0.0, 0.0)), msg(SCAN, (1, 0), vec![])],
    )]);
    let (messages, error, _) = read_bytes(&bytes);
    assert_eq!(messages.len(), 1);
    let (location, message) = format_error(error);
    assert_eq!(location, Location::Offset(13 + record_len(&bytes, 13) as u64));
    assert!(message.starts_with("in the chunk's uncompressed data at offset "), "{message}");
}

#[test]
fn an_unindexed_bag_reads_to_its_end() {
    // A bag whose recording stopped before the index was written: index_pos 0.
    let full = bag(vec![(Compression::None, standard_records())]);
    let header_len = 13 + record_len(&full, 13);
    let chunk_len = record_len(&full, header_len);
    let mut bytes = record::MAGIC.to_vec();
    bag_header(&mut bytes, 0, 0, 0);
    bytes.extend(&full[header_len..header_len + chunk_len]);
    let (messages, error, _) = read_bytes(&bytes);
    assert!(error.is_none(), "{error:?}");
    assert_eq!(messages, standard_messages());
}

// ---------------------------------------------------------------------------------------
// The shared SLAM-benchmark bags (PROVENANCE.md §4).

/// Per-topic message counts, the scans' beam counts, and the messages themselves.
struct BagSummary {
    counts: BTreeMap<String, usize>,
    beams: BTreeMap<usize, usize>,
    messages: Vec<LogMessage>,
    stats: ReadStats,
}

fn summarize(path: &Path) -> BagSummary {
    let mut reader = BagReader::open(path).unwrap();
    let mut s = BagSummary {
        counts: BTreeMap::new(),
        beams: BTreeMap::new(),
        messages: Vec::new(),
        stats: ReadStats::default(),
    };
    while let Some(m) = reader.next_message() {
        let m = m.unwrap();
        if let LogMessage::Scan(x) = &m {
            *s.beams.entry(x.scan.ranges.len()).or_default() += 1;
        }
        *s.counts.entry(m.topic().to_string()).or_default() += 1;
        s.messages.push(m);
    }
    s.stats = reader.stats().clone();
    s
}

fn counts(scan: usize, odom: usize) -> BTreeMap<String, usize> {
    BTreeMap::from([
        ("/scan".to_string(), scan),
        ("/odom".to_string(), odom),
        ("/tf".to_string(), odom),
        ("/tf_static".to_string(), 1),
    ])
}

fn scans(s: &BagSummary) -> impl Iterator<Item = &ScanMessage> {
    s.messages.iter().filter_map(|m| match m {
        LogMessage::Scan(x) => Some(x),
        _ => None,
    })
}

#[test]
fn intel_bag_matches_its_provenance() {
    let Some(path) = testdata::dataset("rosbag1-slam-benchmark/intel.orig.bag") else {
        return;
    };
    let s = summarize(&path);
    assert_eq!(s.counts, counts(13_631, 26_915));
    assert_eq!(s.beams, BTreeMap::from([(180, 13_631)]));
    assert_eq!(s.stats, ReadStats::default());

    let statics: Vec<&TfMessage> = s
        .messages
        .iter()
        .filter_map(|m| match m {
            LogMessage::Tf(t) if t.is_static => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(statics.len(), 1);
    assert_eq!(statics[0].topic, "/tf_static");
    let [t] = statics[0].transforms.as_slice() else {
        panic!("{:?}", statics[0]);
    };
    assert_eq!((t.parent.as_str(), t.child.as_str()), ("base_link", "laser"));

    let first = scans(&s).next().unwrap();
    // 976052857.34 in PROVENANCE.md; exact as stored.
    assert_eq!(first.scan.stamp, Stamp(976_052_857_337_530_017));
    assert_eq!(first.receive_stamp, Some(first.scan.stamp));
    assert_eq!(first.frame_id, "laser");
    assert_eq!(first.scan.angle_min, f64::from(-std::f32::consts::FRAC_PI_2));
    assert!((first.scan.angle_increment - 0.017551).abs() < 1e-6);
    assert_eq!((first.range_min, first.range_max), (0.1, 80.0));
    assert_eq!(&first.scan.ranges[..3], &[1.07, 1.07, 1.08]);
    let last = scans(&s).last().unwrap();
    assert!((last.scan.stamp.as_secs_f64() - 976_055_548.63).abs() < 0.006);
    let above_max: usize = scans(&s).map(|x| x.scan.ranges.iter().filter(|&&r| r > 80.0).count()).sum();
    assert_eq!(above_max, 68_313);

    for m in &s.messages {
        if let LogMessage::Odometry(o) = m {
            assert_eq!((o.frame_id.as_str(), o.child_frame_id.as_str()), ("odom", "base_link"));
            assert!(o.pose.theta.is_finite());
        }
    }
}

#[test]
fn mit_csail_bag_matches_its_provenance() {
    let Some(path) = testdata::dataset("rosbag1-slam-benchmark/mit-csail.orig.bag") else {
        return;
    };
    let s = summarize(&path);
    assert_eq!(s.counts, counts(1988, 1988));
    assert_eq!(s.beams, BTreeMap::from([(361, 1988)]));
    let first = scans(&s).next().unwrap();
    assert_eq!(first.scan.stamp, Stamp(1_134_864_629_895_181_894));
    assert!((first.scan.angle_increment - 0.008727).abs() < 1e-6);
}

#[test]
fn other_benchmark_bags_match_their_provenance() {
    for (file, scan_count, odom_count, beams) in [
        ("aces.orig.bag", 7374, 7375, 180),
        ("fr079.orig.bag", 4934, 8951, 360),
        ("mit-killian.clf2bag.bag", 17_480, 17_480, 180),
    ] {
        let Some(path) = testdata::dataset(&format!("rosbag1-slam-benchmark/{file}")) else {
            return;
        };
        let s = summarize(&path);
        assert_eq!(s.counts, counts(scan_count, odom_count), "{file}");
        assert_eq!(s.beams, BTreeMap::from([(beams, scan_count)]), "{file}");
    }
}

// ---------------------------------------------------------------------------------------
// The second-core chunk decompression of `open`.

/// Everything `BagReader::open` yields for `bytes` written to a file: messages before
/// the first error, and the error's text with the file named `test.bag`.
fn read_file(name: &str, bytes: &[u8]) -> (Vec<LogMessage>, Option<String>) {
    let dir = crate::testdata::temp_dir("ros1-prefetch");
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let mut out = (Vec::new(), None);
    match BagReader::open(&path) {
        Err(e) => out.1 = Some(e.to_string().replace(&path.display().to_string(), "test.bag")),
        Ok(mut reader) => {
            while let Some(m) = reader.next_message() {
                match m {
                    Ok(m) => out.0.push(m),
                    Err(e) => {
                        out.1 = Some(e.to_string().replace(&path.display().to_string(), "test.bag"));
                        break;
                    }
                }
            }
        }
    }
    std::fs::remove_file(&path).unwrap();
    out
}

fn many_chunks() -> Vec<u8> {
    let odom = |i: u32| msg(ODOM, (i, 0), odom_payload((i, 0), f64::from(i), 0.0));
    let mut chunks = vec![(Compression::Bz2, vec![Inner::Conn(ODOM), odom(0)])];
    for k in 1..9u32 {
        let c = [Compression::Bz2, Compression::Lz4, Compression::None][(k % 3) as usize];
        chunks.push((c, (0..5).map(|j| odom(10 * k + j)).collect()));
    }
    bag(chunks)
}

#[test]
fn open_with_a_second_core_reads_exactly_what_a_stream_reads() {
    let bytes = many_chunks();
    let (stream, error, _) = read_bytes(&bytes);
    assert!(error.is_none(), "{error:?}");
    let (file, error) = read_file("many.bag", &bytes);
    assert!(error.is_none(), "{error:?}");
    assert_eq!(file, stream);
    assert_eq!(file.len(), 41);
}

#[test]
fn open_with_a_second_core_fails_like_a_stream() {
    // Cut and corrupt the file at many places: `open` must give the same messages and the
    // same error text as reading the bytes as a stream (the helper only ever saves work).
    let bytes = many_chunks();
    let mut rng = Rng(0x5eed);
    for _ in 0..40 {
        let at = (rng.next() as usize) % bytes.len();
        let mut cut = bytes[..at].to_vec();
        let (stream, stream_err, _) = read_bytes(&cut);
        let (file, file_err) = read_file("cut.bag", &cut);
        // Debug text, not `==`: a flipped byte can make a NaN, which equals nothing.
        assert_eq!(format!("{file:?}"), format!("{stream:?}"), "cut at {at}");
        assert_eq!(file_err, stream_err.map(|e| e.to_string()), "cut at {at}");
        cut = bytes.clone();
        cut[at] ^= 0x5a;
        let (stream, stream_err, _) = read_bytes(&cut);
        let (file, file_err) = read_file("flip.bag", &cut);
        assert_eq!(format!("{file:?}"), format!("{stream:?}"), "flip at {at}");
        assert_eq!(file_err, stream_err.map(|e| e.to_string()), "flip at {at}");
    }
}

#[test]
fn open_reads_the_intel_bag_exactly_as_a_stream() {
    let Some(path) = crate::testdata::dataset("rosbag1-slam-benchmark/intel.orig.bag") else { return };
    let bytes = std::fs::read(&path).unwrap();
    let (stream, error, _) = read_bytes(&bytes);
    assert!(error.is_none());
    let mut reader = BagReader::open(&path).unwrap();
    let mut n = 0;
    while let Some(m) = reader.next_message() {
        assert_eq!(m.unwrap(), stream[n], "message {n}");
        n += 1;
    }
    assert_eq!(n, stream.len());
}

#[test]
fn a_chunk_past_the_decompression_limit_is_refused_on_its_word() {
    for compression in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let bytes = bag(vec![(compression, standard_records())]);
        let chunk = 13 + record_len(&bytes, 13);
        let header_len = u32::from_le_bytes(bytes[chunk..chunk + 4].try_into().unwrap());
        let size_at = chunk + 4 + header_len as usize - 4;
        let size = u32::from_le_bytes(bytes[size_at..size_at + 4].try_into().unwrap());
        let read = |limit: u64| {
            let mut reader = BagReader::from_reader(&bytes[..], "test.bag").unwrap();
            reader.set_options(ReadOptions { max_decompressed_bytes: limit, ..Default::default() });
            std::iter::from_fn(|| reader.next_message()).collect::<Vec<_>>()
        };
        // At the limit the chunk reads; one byte under it, the chunk is refused where it
        // stands, naming its size, the limit and the key.
        assert!(read(u64::from(size)).iter().all(|m| m.is_ok()), "{compression:?}");
        let got = read(u64::from(size) - 1);
        assert_eq!(got.len(), 1, "{compression:?}");
        let (location, message) = format_error(got.into_iter().next().unwrap().err());
        assert_eq!(location, Location::Offset(chunk as u64));
        for part in
            [format!("{size} uncompressed bytes"), format!("limit of {}", size - 1), "limits.decompressed_mib".into()]
        {
            assert!(message.contains(&part), "{compression:?}: `{part}` in {message}");
        }
    }
}

#[test]
fn a_chunk_length_reaching_past_the_index_is_damage_not_a_cut() {
    let mut bytes = bag(vec![(Compression::None, standard_records()), (Compression::None, standard_records())]);
    let chunk = 13 + record_len(&bytes, 13);
    let header_len = u32::from_le_bytes(bytes[chunk..chunk + 4].try_into().unwrap()) as usize;
    let data_len_at = chunk + 4 + header_len;
    let data_len = u32::from_le_bytes(bytes[data_len_at..data_len_at + 4].try_into().unwrap());
    bytes[data_len_at..data_len_at + 4].copy_from_slice(&(data_len + (1 << 24)).to_le_bytes());
    let (_, error, _) = read_bytes(&bytes);
    let error = error.expect("an error");
    assert!(!error.is_truncation(), "{error}");
    let (location, message) = format_error(Some(error));
    assert_eq!(location, Location::Offset(chunk as u64));
    assert!(message.contains("reaching past the index section"), "{message}");
}
