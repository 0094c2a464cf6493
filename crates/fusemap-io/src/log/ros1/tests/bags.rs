//! A tiny ROS 1 bag writer for the reader's tests: connections, chunks (uncompressed, bz2,
//! lz4), index records and the message payloads of the types the reader decodes.

use super::super::*;
use crate::log::{ImuMessage, OdomMessage, ScanMessage, TfMessage, Transform};
use fusemap_core::geometry::Pose2;
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;
use std::collections::BTreeMap;
use std::io::Write;

// ---------------------------------------------------------------------------------------
// A tiny bag writer.

pub(super) const SCAN_MD5: &str = "90c7ef2dc6895d81024acba2ac42f369";
pub(super) const ODOM_MD5: &str = "cd5e73d190d741a2f92e81eda573aca7";
pub(super) const TF_MD5: &str = "94810edda583a504dfda3829e70d7eec";
pub(super) const IMU_MD5: &str = "6a62c6daae103f4ff57a132d6f95cec2";

/// A connection as a test declares it.
#[derive(Clone, Copy)]
pub(super) struct Conn {
    pub(super) id: u32,
    pub(super) topic: &'static str,
    pub(super) ty: &'static str,
    pub(super) md5: &'static str,
}

pub(super) const SCAN: Conn = Conn { id: 0, topic: "/scan", ty: "sensor_msgs/LaserScan", md5: SCAN_MD5 };
pub(super) const ODOM: Conn = Conn { id: 1, topic: "/odom", ty: "nav_msgs/Odometry", md5: ODOM_MD5 };
pub(super) const TF: Conn = Conn { id: 2, topic: "/tf", ty: "tf2_msgs/TFMessage", md5: TF_MD5 };
pub(super) const TF_STATIC: Conn = Conn { id: 3, topic: "/tf_static", ty: "tf/tfMessage", md5: TF_MD5 };
pub(super) const IMU: Conn = Conn { id: 4, topic: "/imu", ty: "sensor_msgs/Imu", md5: IMU_MD5 };
pub(super) const CHATTER: Conn =
    Conn { id: 5, topic: "/chatter", ty: "std_msgs/String", md5: "992ce8a1687cec8c8bd883ec73ca41d1" };

/// A record inside a chunk.
pub(super) enum Inner {
    Conn(Conn),
    Msg { conn: u32, time: (u32, u32), payload: Vec<u8> },
}

pub(super) fn msg(conn: Conn, time: (u32, u32), payload: Vec<u8>) -> Inner {
    Inner::Msg { conn: conn.id, time, payload }
}

pub(super) fn field(out: &mut Vec<u8>, name: &str, value: &[u8]) {
    out.extend(((name.len() + 1 + value.len()) as u32).to_le_bytes());
    out.extend(name.as_bytes());
    out.push(b'=');
    out.extend(value);
}

pub(super) fn record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
    let mut header = Vec::new();
    for (name, value) in fields {
        field(&mut header, name, value);
    }
    out.extend((header.len() as u32).to_le_bytes());
    out.extend(header);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
}

pub(super) fn connection_record(out: &mut Vec<u8>, c: Conn) {
    let mut data = Vec::new();
    field(&mut data, "topic", c.topic.as_bytes());
    field(&mut data, "type", c.ty.as_bytes());
    field(&mut data, "md5sum", c.md5.as_bytes());
    field(&mut data, "message_definition", b"(not needed to read)\n");
    record(
        out,
        &[("op", &[record::OP_CONNECTION]), ("conn", &c.id.to_le_bytes()), ("topic", c.topic.as_bytes())],
        &data,
    );
}

pub(super) fn time_bytes((sec, nsec): (u32, u32)) -> Vec<u8> {
    let mut t = sec.to_le_bytes().to_vec();
    t.extend(nsec.to_le_bytes());
    t
}

/// How a test chunk is stored.
#[derive(Clone, Copy, Debug)]
pub(super) enum Compression {
    None,
    Bz2,
    Lz4,
    /// Written as the given name with uncompressed data.
    Named(&'static str),
}

pub(super) fn compress(c: Compression, data: &[u8]) -> (&'static str, Vec<u8>) {
    match c {
        Compression::None => ("none", data.to_vec()),
        Compression::Bz2 => {
            let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::best());
            e.write_all(data).unwrap();
            ("bz2", e.finish().unwrap())
        }
        Compression::Lz4 => {
            // As roslz4 writes it: independent blocks, a content checksum, no block
            // checksums, no content size.
            let info = lz4_flex::frame::FrameInfo::new()
                .block_size(lz4_flex::frame::BlockSize::Max64KB)
                .block_mode(lz4_flex::frame::BlockMode::Independent)
                .content_checksum(true);
            let mut e = lz4_flex::frame::FrameEncoder::with_frame_info(info, Vec::new());
            e.write_all(data).unwrap();
            ("lz4", e.finish().unwrap())
        }
        Compression::Named(name) => (name, data.to_vec()),
    }
}

/// A complete indexed bag: magic, bag header, the chunks (each followed by index data
/// records), then the index section (connections and chunk infos), like `rosbag record`
/// writes it.
pub(super) fn bag(chunks: Vec<(Compression, Vec<Inner>)>) -> Vec<u8> {
    let mut out = record::MAGIC.to_vec();
    let header_at = out.len();
    let chunk_count = chunks.len() as u32;
    let mut conns = Vec::new();
    bag_header(&mut out, 0, 0, chunk_count);
    let mut chunk_infos = Vec::new();
    for (compression, records) in chunks {
        let mut data = Vec::new();
        let mut per_conn: BTreeMap<u32, Vec<u8>> = BTreeMap::new();
        for r in records {
            let offset = data.len() as u32;
            match r {
                Inner::Conn(c) => {
                    connection_record(&mut data, c);
                    conns.push(c);
                }
                Inner::Msg { conn, time, payload } => {
                    let t = time_bytes(time);
                    record(
                        &mut data,
                        &[("op", &[record::OP_MESSAGE_DATA]), ("conn", &conn.to_le_bytes()), ("time", &t)],
                        &payload,
                    );
                    let entry = per_conn.entry(conn).or_default();
                    entry.extend(&t);
                    entry.extend(offset.to_le_bytes());
                }
            }
        }
        let (name, stored) = compress(compression, &data);
        let chunk_pos = out.len() as u64;
        record(
            &mut out,
            &[
                ("op", &[record::OP_CHUNK]),
                ("compression", name.as_bytes()),
                ("size", &(data.len() as u32).to_le_bytes()),
            ],
            &stored,
        );
        for (conn, entries) in &per_conn {
            record(
                &mut out,
                &[
                    ("op", &[record::OP_INDEX_DATA]),
                    ("ver", &1u32.to_le_bytes()),
                    ("conn", &conn.to_le_bytes()),
                    ("count", &((entries.len() / 12) as u32).to_le_bytes()),
                ],
                entries,
            );
        }
        chunk_infos.push((chunk_pos, per_conn));
    }
    let index_pos = out.len() as u64;
    conns.sort_by_key(|c| c.id);
    conns.dedup_by_key(|c| c.id);
    for c in &conns {
        connection_record(&mut out, *c);
    }
    for (chunk_pos, per_conn) in chunk_infos {
        let mut data = Vec::new();
        for (conn, entries) in &per_conn {
            data.extend(conn.to_le_bytes());
            data.extend(((entries.len() / 12) as u32).to_le_bytes());
        }
        record(
            &mut out,
            &[
                ("op", &[record::OP_CHUNK_INFO]),
                ("ver", &1u32.to_le_bytes()),
                ("chunk_pos", &chunk_pos.to_le_bytes()),
                ("start_time", &[0; 8]),
                ("end_time", &[0; 8]),
                ("count", &(per_conn.len() as u32).to_le_bytes()),
            ],
            &data,
        );
    }
    // Rewrite the bag header now that the index position is known (same size).
    let mut header = Vec::new();
    bag_header(&mut header, index_pos, conns.len() as u32, chunk_count);
    out.splice(header_at..header_at + header.len(), header);
    out
}

pub(super) fn bag_header(out: &mut Vec<u8>, index_pos: u64, conn_count: u32, chunk_count: u32) {
    record(
        out,
        &[
            ("op", &[record::OP_BAG_HEADER]),
            ("index_pos", &index_pos.to_le_bytes()),
            ("conn_count", &conn_count.to_le_bytes()),
            ("chunk_count", &chunk_count.to_le_bytes()),
        ],
        &[b' '; 32],
    );
}

pub(super) fn ros_header(out: &mut Vec<u8>, seq: u32, stamp: (u32, u32), frame: &str) {
    out.extend(seq.to_le_bytes());
    out.extend(time_bytes(stamp));
    ros_string(out, frame);
}

pub(super) fn ros_string(out: &mut Vec<u8>, s: &str) {
    out.extend((s.len() as u32).to_le_bytes());
    out.extend(s.as_bytes());
}

pub(super) fn f32s(out: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        out.extend(v.to_le_bytes());
    }
}

pub(super) fn f64s(out: &mut Vec<u8>, values: &[f64]) {
    for v in values {
        out.extend(v.to_le_bytes());
    }
}

/// `sensor_msgs/LaserScan` with angle_min -1, angle_max 1, increment 0.5, time
/// increment 0.001, scan time 0.1, range 0.1..30.
pub(super) fn scan_payload(stamp: (u32, u32), ranges: &[f32], intensities: &[f32]) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 7, stamp, "laser");
    f32s(&mut p, &[-1.0, 1.0, 0.5, 0.001, 0.1, 0.1, 30.0]);
    p.extend((ranges.len() as u32).to_le_bytes());
    f32s(&mut p, ranges);
    p.extend((intensities.len() as u32).to_le_bytes());
    f32s(&mut p, intensities);
    p
}

/// `nav_msgs/Odometry` at (x, y) with yaw 90°, covariances and twist filled with junk.
pub(super) fn odom_payload(stamp: (u32, u32), x: f64, y: f64) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 1, stamp, "odom");
    ros_string(&mut p, "base_link");
    let h = std::f64::consts::FRAC_1_SQRT_2;
    f64s(&mut p, &[x, y, 0.5, 0.0, 0.0, h, h]);
    f64s(&mut p, &[9.0; 36 + 6 + 36]);
    p
}

/// One transform of a test TF message: stamp, parent, child, translation, rotation.
pub(super) type TestTransform<'a> = ((u32, u32), &'a str, &'a str, [f64; 3], [f64; 4]);

pub(super) fn tf_payload(transforms: &[TestTransform<'_>]) -> Vec<u8> {
    let mut p = (transforms.len() as u32).to_le_bytes().to_vec();
    for (i, (stamp, parent, child, t, q)) in transforms.iter().enumerate() {
        ros_header(&mut p, i as u32, *stamp, parent);
        ros_string(&mut p, child);
        f64s(&mut p, t);
        f64s(&mut p, q);
    }
    p
}

pub(super) fn imu_payload(stamp: (u32, u32)) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 3, stamp, "imu_link");
    f64s(&mut p, &[0.0, 0.0, 0.0, 1.0]);
    f64s(&mut p, &[-1.0; 9]);
    f64s(&mut p, &[0.1, 0.2, 0.3]);
    f64s(&mut p, &[-1.0; 9]);
    f64s(&mut p, &[1.0, 2.0, 9.81]);
    f64s(&mut p, &[-1.0; 9]);
    p
}

pub(super) fn string_payload(s: &str) -> Vec<u8> {
    let mut p = Vec::new();
    ros_string(&mut p, s);
    p
}

/// The records of the standard test chunk: every decoded type plus one skipped type.
pub(super) fn standard_records() -> Vec<Inner> {
    vec![
        Inner::Conn(TF_STATIC),
        msg(
            TF_STATIC,
            (100, 0),
            tf_payload(&[((100, 0), "base_link", "laser", [0.2, 0.0, 0.3], [0.0, 0.0, 0.0, 1.0])]),
        ),
        Inner::Conn(SCAN),
        Inner::Conn(ODOM),
        Inner::Conn(TF),
        Inner::Conn(IMU),
        Inner::Conn(CHATTER),
        msg(ODOM, (100, 5), odom_payload((100, 1), 1.5, -2.5)),
        msg(
            TF,
            (100, 6),
            tf_payload(&[
                ((100, 1), "odom", "base_link", [1.5, -2.5, 0.0], [0.0, 0.0, 0.5, 0.5]),
                ((100, 2), "map", "odom", [0.0; 3], [0.0, 0.0, 0.0, 1.0]),
            ]),
        ),
        msg(CHATTER, (100, 7), string_payload("hello")),
        msg(
            SCAN,
            (101, 999_999_999),
            scan_payload((101, 500_000_000), &[1.0, f32::INFINITY, 2.5, 0.0, 81.91], &[7.0; 5]),
        ),
        msg(IMU, (102, 0), imu_payload((101, 900_000_000))),
        msg(SCAN, (103, 0), scan_payload((102, 0), &[], &[])),
    ]
}

/// What [`standard_records`] must decode to.
pub(super) fn standard_messages() -> Vec<LogMessage> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let scan = |stamp, receive, ranges: Vec<f32>| {
        LogMessage::Scan(ScanMessage {
            topic: "/scan".into(),
            frame_id: "laser".into(),
            receive_stamp: Some(receive),
            scan: LaserScan { stamp, angle_min: -1.0, angle_increment: 0.5, ranges },
            angle_max: 1.0,
            time_increment: 0.001,
            scan_time: 0.1,
            range_min: 0.1,
            range_max: 30.0,
            pose: None,
            odom_pose: None,
            laser_pose: None,
        })
    };
    let yaw = fusemap_core::geometry::quaternion_yaw([0.0, 0.0, h, h]);
    assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    vec![
        LogMessage::Tf(TfMessage {
            topic: "/tf_static".into(),
            is_static: true,
            receive_stamp: Some(Stamp(100_000_000_000)),
            transforms: vec![Transform {
                stamp: Stamp(100_000_000_000),
                parent: "base_link".into(),
                child: "laser".into(),
                translation: [0.2, 0.0, 0.3],
                rotation: [0.0, 0.0, 0.0, 1.0],
            }],
        }),
        LogMessage::Odometry(OdomMessage {
            topic: "/odom".into(),
            stamp: Stamp(100_000_000_001),
            receive_stamp: Some(Stamp(100_000_000_005)),
            frame_id: "odom".into(),
            child_frame_id: "base_link".into(),
            pose: Pose2::new(1.5, -2.5, yaw),
            pose_covariance: [9.0; 36],
            twist: [9.0; 6],
            twist_covariance: [9.0; 36],
        }),
        LogMessage::Tf(TfMessage {
            topic: "/tf".into(),
            is_static: false,
            receive_stamp: Some(Stamp(100_000_000_006)),
            transforms: vec![
                Transform {
                    stamp: Stamp(100_000_000_001),
                    parent: "odom".into(),
                    child: "base_link".into(),
                    translation: [1.5, -2.5, 0.0],
                    rotation: [0.0, 0.0, 0.5, 0.5],
                },
                Transform {
                    stamp: Stamp(100_000_000_002),
                    parent: "map".into(),
                    child: "odom".into(),
                    translation: [0.0; 3],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                },
            ],
        }),
        scan(Stamp(101_500_000_000), Stamp(101_999_999_999), vec![1.0, f32::INFINITY, 2.5, 0.0, 81.91]),
        LogMessage::Imu(ImuMessage {
            topic: "/imu".into(),
            stamp: Stamp(101_900_000_000),
            receive_stamp: Some(Stamp(102_000_000_000)),
            frame_id: "imu_link".into(),
            orientation: [0.0, 0.0, 0.0, 1.0],
            angular_velocity: [0.1, 0.2, 0.3],
            linear_acceleration: [1.0, 2.0, 9.81],
            orientation_covariance: [-1.0; 9],
            angular_velocity_covariance: [-1.0; 9],
            linear_acceleration_covariance: [-1.0; 9],
        }),
        scan(Stamp(102_000_000_000), Stamp(103_000_000_000), vec![]),
    ]
}

/// Everything a bag yields: the messages before the first error, the error, and stats.
pub(super) fn read_bytes(bytes: &[u8]) -> (Vec<LogMessage>, Option<Error>, ReadStats) {
    let mut reader = match BagReader::from_reader(bytes, "test.bag") {
        Ok(r) => r,
        Err(e) => return (Vec::new(), Some(e), ReadStats::default()),
    };
    let mut messages = Vec::new();
    let mut error = None;
    while let Some(m) = reader.next_message() {
        match m {
            Ok(m) => messages.push(m),
            Err(e) => {
                // The reader stops after an error, unless only one message was bad.
                if !e.is_skippable() {
                    assert!(reader.next_message().is_none());
                }
                error = Some(e);
                break;
            }
        }
    }
    (messages, error, reader.stats().clone())
}

/// The location and message of a format error.
pub(super) fn format_error(e: Option<Error>) -> (Location, String) {
    match e {
        Some(Error::Format { path, location, message } | Error::Truncated { path, location, message }) => {
            assert_eq!(path, Path::new("test.bag"));
            (location, message)
        }
        other => panic!("expected a format error, got {other:?}"),
    }
}
