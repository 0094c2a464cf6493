//! Inputs are files: a FIFO, socket or device named as a log, config or world would block
//! a read forever or never end, so it is refused before it is opened. Text inputs read
//! whole (configs, worlds, scenarios, trajectories, YAML) are read within a size budget,
//! so a 2 GB file named as a config is one error, not an allocation of 2 GB.

use crate::error::{Error, Location, Result};
use std::path::Path;

/// The largest config, world or scenario file read, bytes: a hundred times the annotated
/// example config.
pub const MAX_DESCRIPTION_BYTES: u64 = 4 << 20;

/// Reads `path` as UTF-8 text of at most `max_bytes` (a special file refused first); a
/// larger file is a format error saying it is not `what`, invalid UTF-8 one at the line
/// where it starts.
pub fn read_text_within(path: &Path, max_bytes: u64, what: &str) -> Result<String> {
    refuse_special_file(path)?;
    let too_large = || {
        let mib = max_bytes as f64 / f64::from(1 << 20);
        Error::format(path, Location::File, format!("larger than {mib} MiB; not {what}"))
    };
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // The length first, so a huge regular file is refused without reading it; the bounded
    // read then holds for pipes and growing files too.
    if file.metadata().map_err(|e| Error::io(path, e))?.len() > max_bytes {
        return Err(too_large());
    }
    let mut bytes = Vec::new();
    let read = crate::bounded::read_to_end_bounded(file, max_bytes, &mut bytes).map_err(|e| Error::io(path, e))?;
    if read == crate::bounded::Bounded::OverLimit {
        return Err(too_large());
    }
    String::from_utf8(bytes).map_err(|e| {
        let line = line_of(e.as_bytes(), e.utf8_error().valid_up_to());
        Error::format(path, Location::Line(line), "the file is not valid UTF-8 text")
    })
}

/// An error when `path` is a FIFO, socket or device (after following symbolic links);
/// anything else, including a missing path, is left to the caller's own open.
pub fn refuse_special_file(path: &Path) -> Result<()> {
    let Ok(meta) = std::fs::metadata(path) else { return Ok(()) };
    let kind = special_kind(&meta.file_type());
    match kind {
        Some(kind) => Err(Error::format(
            path,
            Location::File,
            format!("is a {kind}, not a file: refused (fusemap reads logs, configs and worlds from files)"),
        )),
        None => Ok(()),
    }
}

/// The 1-based line holding byte `offset` of `text`.
pub(crate) fn line_of(text: &[u8], offset: usize) -> u64 {
    let end = offset.min(text.len());
    text[..end].iter().filter(|&&b| b == b'\n').count() as u64 + 1
}

#[cfg(unix)]
fn special_kind(t: &std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    if t.is_fifo() {
        Some("FIFO (named pipe)")
    } else if t.is_socket() {
        Some("socket")
    } else if t.is_char_device() {
        Some("character device")
    } else if t.is_block_device() {
        Some("block device")
    } else {
        None
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> Option<&'static str> {
    None
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn text_past_the_budget_or_not_utf8_is_refused() {
        let dir = crate::testdata::temp_dir("text-within");
        let big = dir.join("big.toml");
        // Sparse: 2 GB of nothing on disk.
        std::fs::File::create(&big).unwrap().set_len(2 << 30).unwrap();
        let e = read_text_within(&big, MAX_DESCRIPTION_BYTES, "a config").unwrap_err().to_string();
        assert!(e.contains("big.toml") && e.contains("larger than 4 MiB; not a config"), "{e}");
        let latin1 = dir.join("latin1.toml");
        std::fs::write(&latin1, b"a = 1\nb = \"caf\xe9\"\n").unwrap();
        let e = read_text_within(&latin1, 100, "a config").unwrap_err().to_string();
        assert!(e.contains("latin1.toml:2") && e.contains("UTF-8"), "{e}");
        assert!(read_text_within(&dir.join("missing"), 10, "x").unwrap_err().to_string().contains("missing"));
        let exact = dir.join("exact.toml");
        std::fs::write(&exact, "x = 1\n").unwrap();
        assert_eq!(read_text_within(&exact, 6, "a config").unwrap(), "x = 1\n");
        assert!(read_text_within(&exact, 5, "a config").is_err());
    }

    #[test]
    fn devices_and_fifos_are_refused_files_are_not() {
        let e = refuse_special_file(Path::new("/dev/null")).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let dir = crate::testdata::temp_dir("special-file");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false);
        if made {
            let e = refuse_special_file(&fifo).unwrap_err();
            assert!(e.to_string().contains("FIFO") && e.to_string().contains("pipe"), "{e}");
        }
        let file = dir.join("plain.toml");
        std::fs::write(&file, "").unwrap();
        assert!(refuse_special_file(&file).is_ok());
        assert!(refuse_special_file(&dir).is_ok());
        assert!(refuse_special_file(&dir.join("missing")).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
