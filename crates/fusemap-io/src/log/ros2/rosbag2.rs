//! rosbag2 directories: `metadata.yaml` names the storage plugin (`mcap` or `sqlite3`),
//! the storage files in recording order, and the compression.
//!
//! Only five keys of `metadata.yaml` matter here, all direct children of
//! `rosbag2_bagfile_information`: `version`, `storage_identifier`,
//! `relative_file_paths`, `compression_mode` and `compression_format`. The file is parsed
//! as YAML ([`crate::yaml`]), so block, flow and JSON spellings of it read the same.

use super::PendingFile;
use crate::error::{Error, Location, Result};
use crate::yaml;
use std::path::{Path, PathBuf};

/// The file that makes a directory a rosbag2 bag.
pub const METADATA_FILE: &str = "metadata.yaml";

/// The keys of `metadata.yaml` that fusemap uses.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Metadata {
    /// Bag format version (1–9 so far), if given.
    pub version: Option<u32>,
    /// Storage plugin: `mcap` or `sqlite3` (empty when the file does not say).
    pub storage_identifier: String,
    /// Storage files relative to the bag directory, in recording order.
    pub relative_file_paths: Vec<String>,
    /// `""`, `file` or `message` (rosbag2 writes these in either case).
    pub compression_mode: String,
    /// `""` or `zstd`.
    pub compression_format: String,
}

/// A parse error: the 1-based line (0 for the file as a whole) and what is wrong.
pub type MetadataError = yaml::YamlError;

const ROOT_KEY: &str = "rosbag2_bagfile_information";

/// Reads the keys fusemap needs from the text of a `metadata.yaml`, in any YAML style:
/// block (as `ros2 bag record` writes it), flow, or JSON.
pub fn parse_metadata(text: &str) -> std::result::Result<Metadata, MetadataError> {
    let root = yaml::parse(text)?;
    let info = yaml::get(&root, ROOT_KEY)
        .ok_or_else(|| (0, format!("no `{ROOT_KEY}:` key at the top level; not rosbag2 metadata")))?;
    if !yaml::is_mapping(info) {
        return Err((yaml::line(info), format!("`{ROOT_KEY}` holds no keys")));
    }
    let text_of = |key: &str| -> std::result::Result<String, MetadataError> {
        yaml::get(info, key)
            .map_or(Ok(String::new()), |n| yaml::text(n).map_err(|m| (yaml::line(n), format!("`{key}`: {m}"))))
    };
    let version = match yaml::get(info, "version") {
        None => None,
        Some(n) => {
            let v = yaml::text(n).or_else(|_| yaml::number(n).map(|x| x.to_string())).unwrap_or_default();
            Some(v.parse().map_err(|_| (yaml::line(n), format!("`version: {v}` is not a whole number")))?)
        }
    };
    let paths = yaml::get(info, "relative_file_paths")
        .ok_or_else(|| (0, format!("no `relative_file_paths` under `{ROOT_KEY}`")))?;
    let relative_file_paths = match yaml::items(paths) {
        Some(items) => items
            .iter()
            .map(|n| yaml::text(n).map_err(|m| (yaml::line(n), format!("`relative_file_paths`: {m}"))))
            // An empty item (`~`, `""`) names no file, as the list's other spellings skip it.
            .filter(|p| p.as_ref().map_or(true, |s| !s.is_empty()))
            .collect::<std::result::Result<_, _>>()?,
        // `relative_file_paths:` with nothing after it: no files (refused by the caller).
        None if yaml::text(paths).is_ok_and(|s| s.is_empty()) => Vec::new(),
        None => {
            let what = yaml::text(paths).map_or_else(|_| "a mapping".to_string(), |s| format!("`{s}`"));
            return Err((yaml::line(paths), format!("`relative_file_paths` should be a list, not {what}")));
        }
    };
    Ok(Metadata {
        version,
        storage_identifier: text_of("storage_identifier")?,
        relative_file_paths,
        compression_mode: text_of("compression_mode")?,
        compression_format: text_of("compression_format")?,
    })
}

/// A rosbag2 directory resolved to its storage files.
pub(crate) struct Rosbag2Dir {
    pub files: Vec<PendingFile>,
    pub zstd_messages: bool,
}

impl Rosbag2Dir {
    pub(crate) fn open(dir: &Path) -> Result<Self> {
        let meta_path = dir.join(METADATA_FILE);
        let text = yaml::read_text(&meta_path)?;
        let meta = parse_metadata(&text).map_err(|(line, message)| {
            let location = if line == 0 { Location::File } else { Location::Line(line) };
            Error::format(&meta_path, location, message)
        })?;
        let field_error =
            |(key, message): (&str, String)| Error::format(&meta_path, Location::Field(key.into()), message);
        let (zstd_file, zstd_messages) = compression(&meta).map_err(field_error)?;
        if meta.relative_file_paths.is_empty() {
            return Err(field_error(("relative_file_paths", "the bag lists no storage files".into())));
        }
        let mut files = Vec::new();
        let mut seen: Vec<(PathBuf, &str)> = Vec::new();
        for rel in &meta.relative_file_paths {
            let path = storage_file(dir, rel, &mut seen).map_err(field_error)?;
            files.push(pending_file(&meta, path, rel, zstd_file).map_err(field_error)?);
        }
        Ok(Self { files, zstd_messages })
    }
}

/// A metadata key and why its value is refused.
type KeyError = (&'static str, String);

/// Whether the bag's files, or else its messages, are zstd-compressed.
fn compression(meta: &Metadata) -> std::result::Result<(bool, bool), KeyError> {
    let mode = meta.compression_mode.to_ascii_lowercase();
    let format = meta.compression_format.to_ascii_lowercase();
    match mode.as_str() {
        "" | "none" => Ok((false, false)),
        "file" | "message" if format != "zstd" => Err((
            "compression_format",
            format!("compression `{}` is not supported; fusemap reads zstd-compressed bags", meta.compression_format),
        )),
        "file" => Ok((true, false)),
        "message" => Ok((false, true)),
        _ => Err((
            "compression_mode",
            format!("unknown compression mode `{}` (expected file or message)", meta.compression_mode),
        )),
    }
}

/// The storage file `rel` names inside `dir`, refused when it lies outside the bag or
/// repeats one already listed (`seen`, canonical paths with their spellings).
fn storage_file<'a>(
    dir: &Path,
    rel: &'a str,
    seen: &mut Vec<(PathBuf, &'a str)>,
) -> std::result::Result<PathBuf, KeyError> {
    // The bag names its files relative to its own directory: an absolute path or a `..`
    // would let a bag someone sent make fusemap open any file.
    if !stays_inside(rel) {
        return Err((
            "relative_file_paths",
            format!("lists `{}`, which is outside the bag directory; refused", rel.escape_debug()),
        ));
    }
    let path = resolve(dir, rel)
        .ok_or_else(|| ("relative_file_paths", format!("lists `{rel}`, which is not in {}", dir.display())))?;
    // One file listed twice (or by two spellings) would be read, and mapped, twice.
    let canonical = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
    if let Some((_, first)) = seen.iter().find(|(p, _)| *p == canonical) {
        return Err((
            "relative_file_paths",
            format!(
                "lists the storage file `{}` twice (as `{}` and `{}`): every message would be read twice; remove \
                 the repeat",
                canonical.display(),
                first.escape_debug(),
                rel.escape_debug()
            ),
        ));
    }
    seen.push((canonical, rel));
    Ok(path)
}

/// The storage file at `path` (listed as `rel`) as the bag's storage plugin, or its name,
/// says to read it.
fn pending_file(
    meta: &Metadata,
    path: PathBuf,
    rel: &str,
    zstd_file: bool,
) -> std::result::Result<PendingFile, KeyError> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let compressed = zstd_file || name.ends_with(".zstd");
    let base = name.trim_end_matches(".zstd");
    let is_mcap = match meta.storage_identifier.to_ascii_lowercase().as_str() {
        "mcap" => true,
        "sqlite3" => false,
        _ if base.ends_with(".mcap") => true,
        _ if base.ends_with(".db3") => false,
        _ => {
            return Err((
                "storage_identifier",
                format!(
                    "storage `{}` is not supported (fusemap reads `mcap` and `sqlite3` bags)",
                    meta.storage_identifier
                ),
            ))
        }
    };
    if is_mcap {
        Ok(PendingFile::Mcap { path, zstd: compressed })
    } else if compressed {
        Err((
            "compression_mode",
            format!(
                "`{rel}` is a whole-file zstd-compressed SQLite bag; decompress it first (`zstd -d`, then list the \
                 .db3 in metadata.yaml) or convert the bag to MCAP"
            ),
        ))
    } else {
        Ok(PendingFile::Db3 { path })
    }
}

/// True when `rel` is a relative path without `..`: it cannot name a file outside the
/// bag directory (symbolic links inside it are the bag owner's choice).
fn stays_inside(rel: &str) -> bool {
    use std::path::Component;
    !rel.is_empty() && Path::new(rel).components().all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
}

/// The storage file `rel` names: relative to the bag directory, or (as early rosbag2
/// versions wrote it, with the directory name in front) just its file name there.
fn resolve(dir: &Path, rel: &str) -> Option<PathBuf> {
    let direct = dir.join(rel);
    if direct.is_file() {
        return Some(direct);
    }
    let by_name = dir.join(Path::new(rel).file_name()?);
    by_name.is_file().then_some(by_name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_paths_outside_the_bag_are_refused() {
        for rel in ["../../etc/passwd", "/etc/passwd", "a/../../b.db3", "..", ""] {
            assert!(!stays_inside(rel), "{rel}");
        }
        for rel in ["bag_0.db3", "./bag_0.mcap", "db3_bag/c_0.db3", "my bag: 1_0.mcap"] {
            assert!(stays_inside(rel), "{rel}");
        }
        let dir = crate::testdata::temp_dir("rosbag2-outside");
        std::fs::write(dir.join("secret.db3"), b"x").unwrap();
        let bag = dir.join("bag");
        std::fs::create_dir_all(&bag).unwrap();
        std::fs::write(
            bag.join(METADATA_FILE),
            "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths:\n    - ../secret.db3\n",
        )
        .unwrap();
        let e = Rosbag2Dir::open(&bag).err().expect("refused");
        let text = e.to_string();
        assert!(text.contains("outside the bag directory") && text.contains("metadata.yaml"), "{text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_storage_file_listed_twice_is_refused() {
        let dir = crate::testdata::temp_dir("rosbag2-twice");
        std::fs::write(dir.join("a_0.mcap"), b"x").unwrap();
        std::fs::write(dir.join("a_1.mcap"), b"x").unwrap();
        let list = |files: &str| {
            let meta =
                format!("rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: [{files}]\n");
            std::fs::write(dir.join(METADATA_FILE), meta).unwrap();
            Rosbag2Dir::open(&dir)
        };
        assert_eq!(list("a_0.mcap, a_1.mcap").unwrap().files.len(), 2);
        for twice in ["a_0.mcap, a_1.mcap, a_0.mcap", "a_0.mcap, ./a_0.mcap"] {
            let text = list(twice).err().expect("refused").to_string();
            assert!(text.contains("twice") && text.contains("a_0.mcap") && text.contains("metadata.yaml"), "{text}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_the_rosbag2_cli_layout() {
        let text = "\
rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  duration:
    nanoseconds: 120
  topics_with_message_count:
    - topic_metadata:
        name: /scan
        type: sensor_msgs/msg/LaserScan
        serialization_format: cdr
        offered_qos_profiles: \"- history: 3\\n  depth: 0\\n  storage_identifier: x\\n\"
      message_count: 3
  compression_format: \"\"
  compression_mode: \"\"
  relative_file_paths:
    - bag_0.db3
    - \"bag_1.db3\"
  files:
    - path: bag_0.db3
      message_count: 2
";
        let m = parse_metadata(text).unwrap();
        assert_eq!(m.version, Some(5));
        assert_eq!(m.storage_identifier, "sqlite3");
        assert_eq!(m.relative_file_paths, ["bag_0.db3", "bag_1.db3"]);
        assert_eq!(m.compression_mode, "");
    }

    #[test]
    fn reads_dash_at_key_indent_flow_lists_and_comments() {
        let text = "\
# written by hand
rosbag2_bagfile_information:
  storage_identifier: 'mcap'   # the plugin
  relative_file_paths:
  - a_0.mcap
  - a_1.mcap
  topics_with_message_count:
  - message_count: 1
    topic_metadata:
      name: /storage_identifier
  version: 9
";
        let m = parse_metadata(text).unwrap();
        assert_eq!(m.storage_identifier, "mcap");
        assert_eq!(m.relative_file_paths, ["a_0.mcap", "a_1.mcap"]);
        assert_eq!(m.version, Some(9));

        let flow = "rosbag2_bagfile_information:\n    relative_file_paths: [x.db3, \"y.db3\", ~]\n";
        assert_eq!(parse_metadata(flow).unwrap().relative_file_paths, ["x.db3", "y.db3"]);
        let float = "rosbag2_bagfile_information:\n  version: 5.5\n  relative_file_paths: []\n";
        assert!(parse_metadata(float).unwrap_err().1.contains("5.5"));
    }

    /// One bag's metadata as `ros2 bag record` writes it (block style), as PyYAML writes it
    /// with `default_flow_style=True` (flow style, wrapped over lines), and as JSON.
    #[test]
    fn block_flow_and_json_metadata_read_the_same() {
        let block = "\
rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  duration:
    nanoseconds: 29900000000
  message_count: 600
  topics_with_message_count:
    - topic_metadata:
        name: /scan
        type: sensor_msgs/msg/LaserScan
        serialization_format: cdr
        offered_qos_profiles: []
      message_count: 300
  compression_format: \"\"
  compression_mode: \"\"
  relative_file_paths:
    - bag_0.mcap
    - bag_1.mcap
  custom_data: ~
  ros_distro: jazzy
";
        let flow = "\
{rosbag2_bagfile_information: {compression_format: '', compression_mode: '', custom_data: null,
    duration: {nanoseconds: 29900000000}, message_count: 600, relative_file_paths: [
      bag_0.mcap, bag_1.mcap], ros_distro: jazzy, storage_identifier: mcap, topics_with_message_count: [
      {message_count: 300, topic_metadata: {name: /scan, offered_qos_profiles: [], serialization_format: cdr,
          type: sensor_msgs/msg/LaserScan}}], version: 9}}
";
        let json = r#"{
  "rosbag2_bagfile_information": {
    "version": 9, "storage_identifier": "mcap", "duration": {"nanoseconds": 29900000000},
    "message_count": 600,
    "topics_with_message_count": [{"topic_metadata": {"name": "/scan",
      "type": "sensor_msgs/msg/LaserScan", "serialization_format": "cdr",
      "offered_qos_profiles": []}, "message_count": 300}],
    "compression_format": "", "compression_mode": "",
    "relative_file_paths": ["bag_0.mcap", "bag_1.mcap"], "custom_data": null, "ros_distro": "jazzy"
  }
}"#;
        let expected = Metadata {
            version: Some(9),
            storage_identifier: "mcap".into(),
            relative_file_paths: vec!["bag_0.mcap".into(), "bag_1.mcap".into()],
            compression_mode: String::new(),
            compression_format: String::new(),
        };
        for (style, text) in [("block", block), ("flow", flow), ("JSON", json)] {
            assert_eq!(parse_metadata(text).as_ref(), Ok(&expected), "{style}");
        }
    }

    #[test]
    fn says_what_is_missing() {
        assert!(parse_metadata("foo: 1\n").unwrap_err().1.contains("rosbag2_bagfile_information"));
        assert!(parse_metadata("rosbag2_bagfile_information:\n  version: 5\n")
            .unwrap_err()
            .1
            .contains("relative_file_paths"));
        assert_eq!(
            parse_metadata("rosbag2_bagfile_information:\n  version: five\n  relative_file_paths: []\n").unwrap_err().0,
            2
        );
        assert!(parse_metadata("rosbag2_bagfile_information:\n").is_err());
    }
}
