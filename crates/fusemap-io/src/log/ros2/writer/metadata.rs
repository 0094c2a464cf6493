//! `metadata.yaml` and the QoS profiles rosbag2 stores per topic.
//!
//! The file is written by hand (as `map_server` YAML is elsewhere in fusemap): the keys
//! are fixed and the only free text (file names) is double-quoted. It has the layout
//! rosbag2's `YamlConverter<BagMetadata>` writes for format version 5 (Humble): version,
//! storage plugin, bag duration and start, message count, one `topic_metadata` per topic
//! with its `offered_qos_profiles`, compression, the storage files and per-file
//! statistics. Later rosbag2 versions read version 5 bags unchanged, and `rosbags` and
//! fusemap's own [`parse_metadata`](crate::log::ros2::rosbag2::parse_metadata) read it.
//!
//! Up to version 8, `offered_qos_profiles` is a YAML document *inside a string*, with the
//! `rmw_qos_*_policy_t` enum values as integers; the MCAP storage plugin also puts that
//! same string in each channel's metadata under `offered_qos_profiles`, which is where
//! `ros2 bag play` takes the QoS from.

use std::fmt::Write as _;

/// The QoS a topic is offered with when the bag is played back (`ros2 bag play` publishes
/// with the recorded profile). History is always `keep_last`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QosProfile {
    /// `keep_last` depth.
    pub depth: u32,
    /// `reliable` when true, else `best_effort`.
    pub reliable: bool,
    /// `transient_local` (late joiners get the last `depth` messages: a latched topic)
    /// when true, else `volatile`.
    pub transient_local: bool,
}

impl QosProfile {
    /// rclcpp's default publisher profile: keep_last 10, reliable, volatile. A reliable
    /// offer matches both reliable and best-effort subscribers (the DDS request/offer
    /// rule), so players reach every kind of consumer.
    pub const DEFAULT: QosProfile = QosProfile { depth: 10, reliable: true, transient_local: false };

    /// What `tf2_ros::StaticTransformBroadcaster` offers on `/tf_static`: keep_last 1,
    /// reliable, transient_local, so that a node started after playback began still
    /// receives the static transforms (the ROS 2 form of a latched topic).
    pub const LATCHED: QosProfile = QosProfile { depth: 1, reliable: true, transient_local: true };

    /// The profile as rosbag2 (format ≤ 8) stores it: a one-element YAML list, enums as
    /// `rmw` integers (history keep_last = 1; reliability reliable = 1, best_effort = 2;
    /// durability transient_local = 1, volatile = 2; liveliness automatic = 1), durations
    /// 0 s 0 ns (`RMW_DURATION_UNSPECIFIED`: no deadline, lifespan or lease).
    pub fn to_yaml(self) -> String {
        let reliability = if self.reliable { 1 } else { 2 };
        let durability = if self.transient_local { 1 } else { 2 };
        let zero = |key: &str| format!("  {key}:\n    sec: 0\n    nsec: 0\n");
        format!(
            "- history: 1\n  depth: {}\n  reliability: {reliability}\n  durability: {durability}\n{}{}  liveliness: 1\n{}  avoid_ros_namespace_conventions: false",
            self.depth,
            zero("deadline"),
            zero("lifespan"),
            zero("liveliness_lease_duration"),
        )
    }
}

/// A topic's line in the metadata.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicInfo {
    /// Topic name.
    pub name: String,
    /// ROS 2 type name (`sensor_msgs/msg/LaserScan`).
    pub type_name: String,
    /// Its QoS.
    pub qos: QosProfile,
    /// Messages written on it.
    pub message_count: u64,
}

/// Everything `metadata.yaml` states about a finished bag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct BagInfo<'a> {
    pub storage_file: &'a str,
    pub starting_time_ns: u64,
    pub duration_ns: u64,
    pub message_count: u64,
    pub topics: &'a [TopicInfo],
}

/// The rosbag2 format version written.
pub const FORMAT_VERSION: u32 = 5;

/// A YAML double-quoted scalar (escapes `\`, `"` and control characters).
pub(crate) fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The body of `rosbag2_bagfile_information` at indentation 0 (what the MCAP `rosbag2`
/// metadata record holds as `serialized_metadata`).
pub(crate) fn bag_info_yaml(info: &BagInfo<'_>) -> String {
    let file = quote(info.storage_file);
    let mut y = String::new();
    let _ = writeln!(y, "version: {FORMAT_VERSION}");
    y.push_str("storage_identifier: mcap\n");
    let _ = writeln!(y, "duration:\n  nanoseconds: {}", info.duration_ns);
    let _ = writeln!(y, "starting_time:\n  nanoseconds_since_epoch: {}", info.starting_time_ns);
    let _ = writeln!(y, "message_count: {}", info.message_count);
    if info.topics.is_empty() {
        y.push_str("topics_with_message_count: []\n");
    } else {
        y.push_str("topics_with_message_count:\n");
    }
    for t in info.topics {
        let _ = writeln!(y, "  - topic_metadata:");
        let _ = writeln!(y, "      name: {}", quote(&t.name));
        let _ = writeln!(y, "      type: {}", t.type_name);
        y.push_str("      serialization_format: cdr\n");
        let _ = writeln!(y, "      offered_qos_profiles: {}", quote(&t.qos.to_yaml()));
        let _ = writeln!(y, "    message_count: {}", t.message_count);
    }
    y.push_str("compression_format: \"\"\ncompression_mode: \"\"\n");
    let _ = writeln!(y, "relative_file_paths:\n  - {file}");
    let _ = writeln!(y, "files:\n  - path: {file}");
    let _ = writeln!(y, "    starting_time:\n      nanoseconds_since_epoch: {}", info.starting_time_ns);
    let _ = writeln!(y, "    duration:\n      nanoseconds: {}", info.duration_ns);
    let _ = writeln!(y, "    message_count: {}", info.message_count);
    y
}

/// The whole `metadata.yaml`.
pub(crate) fn metadata_yaml(info: &BagInfo<'_>) -> String {
    let mut out = String::from("rosbag2_bagfile_information:\n");
    for line in bag_info_yaml(info).lines() {
        out.push_str("  ");
        out.push_str(line);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::ros2::rosbag2::parse_metadata;

    #[test]
    fn fusemaps_reader_finds_the_keys_it_needs() {
        let topics = [
            TopicInfo {
                name: "/scan".into(),
                type_name: "sensor_msgs/msg/LaserScan".into(),
                qos: QosProfile::DEFAULT,
                message_count: 3,
            },
            TopicInfo {
                name: "/tf_static".into(),
                type_name: "tf2_msgs/msg/TFMessage".into(),
                qos: QosProfile::LATCHED,
                message_count: 1,
            },
        ];
        let info = BagInfo {
            storage_file: "my bag: 1_0.mcap",
            starting_time_ns: 5,
            duration_ns: 7,
            message_count: 4,
            topics: &topics,
        };
        let m = parse_metadata(&metadata_yaml(&info)).unwrap();
        assert_eq!(m.version, Some(FORMAT_VERSION));
        assert_eq!(m.storage_identifier, "mcap");
        assert_eq!(m.relative_file_paths, ["my bag: 1_0.mcap"]);
        assert_eq!((m.compression_mode.as_str(), m.compression_format.as_str()), ("", ""));
    }

    #[test]
    fn latched_profile_says_keep_last_1_reliable_transient_local() {
        let y = QosProfile::LATCHED.to_yaml();
        assert!(y.starts_with("- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n"), "{y}");
        let d = QosProfile::DEFAULT.to_yaml();
        assert!(d.contains("depth: 10\n") && d.contains("durability: 2\n"), "{d}");
        assert!(!y.ends_with('\n'));
    }

    #[test]
    fn quoting_escapes() {
        assert_eq!(quote("a\"b\\c\nd\u{1}"), "\"a\\\"b\\\\c\\nd\\x01\"");
    }
}
