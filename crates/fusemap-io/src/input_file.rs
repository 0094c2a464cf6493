//! Inputs are files: a FIFO, socket or device named as a log, config or world would block
//! a read forever or never end, so it is refused before it is opened.

use crate::error::{Error, Location, Result};
use std::path::Path;

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
