//! Writing output files safely: all or nothing, and never over an input.
//!
//! A map export that dies half-way (disk full, Ctrl-C, a bug in a writer) must not leave
//! a truncated `map.pgm` where a good one stood: a navigation stack that later loads it
//! would get a silently broken map. [`write_atomic`] therefore writes to a temporary file
//! in the target's own directory, flushes it to disk (`fsync`), and only then renames it
//! over the target. POSIX `rename(2)` replaces the directory entry atomically when both
//! names are on one file system, which the same directory guarantees: a reader sees either
//! the old file or the new one, never a mixture. On any error the temporary file is
//! removed and the target is left as it was.
//!
//! [`ensure_not_input`] guards the other classic accident: an output path that names one
//! of the run's inputs (`fusemap build run.bag -o run.bag`).

use crate::{Error, Location, Result};
use fusemap_core::grid::Raster;
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of one process (several outputs may be written at once
/// from different threads).
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `path` atomically: `write` fills a buffered temporary file in the same
/// directory, which is then flushed, `fsync`ed and renamed over `path`.
///
/// The temporary file is named `.<name>.tmp-<pid>-<counter>` and created with
/// `create_new`, so it can never clobber another file, even one of a concurrent run. The
/// writer is a [`BufWriter`] over a [`File`], which is also [`Seek`](std::io::Seek)able
/// (zip archives need that). When `write` fails, or flushing or renaming does, the
/// temporary file is removed, the target is untouched, and the error names `path`.
///
/// After the rename the directory itself is `fsync`ed (on Unix, best effort) so the new
/// entry survives a power cut as well as the data.
pub fn write_atomic<T>(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> io::Result<T>) -> Result<T> {
    let name = path
        .file_name()
        .ok_or_else(|| Error::io(path, io::Error::new(io::ErrorKind::InvalidInput, "the path names no file")))?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut temp_name = std::ffi::OsString::from(".");
    temp_name.push(name);
    temp_name.push(format!(".tmp-{}-{}", std::process::id(), TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)));
    let temp = dir.join(temp_name);
    let file = OpenOptions::new().write(true).create_new(true).open(&temp).map_err(|e| Error::io(path, e))?;

    let outcome = (|| {
        let mut w = BufWriter::new(file);
        let value = write(&mut w)?;
        let file = w.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&temp, path)?;
        Ok(value)
    })();
    match outcome {
        Ok(value) => {
            sync_dir(&dir);
            Ok(value)
        }
        Err(e) => {
            // Best effort: the original error is the one worth reporting.
            let _ = std::fs::remove_file(&temp);
            Err(Error::io(path, e))
        }
    }
}

/// `fsync` of a directory makes a rename in it durable. Not every platform or file
/// system supports it, and the data is already safe, so failures are ignored.
pub(crate) fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// Refuses an output path that is one of `inputs`, returning
/// [`Error::WouldOverwriteInput`].
///
/// Paths are compared after resolving symbolic links and `..` (`canonicalize`) where the
/// file exists; an output that does not exist yet is resolved through its existing parent
/// directory. On Unix two existing paths are also the same file when they share device
/// and inode (hard links). Inputs that do not exist are compared lexically after making
/// them absolute. Errors while resolving are not reported: the comparison then falls back
/// to the lexical form, and the write itself will report a real I/O problem.
pub fn ensure_not_input(output: &Path, inputs: &[PathBuf]) -> Result<()> {
    let out = resolve(output);
    for input in inputs {
        if resolve(input) == out || same_inode(output, input) {
            return Err(Error::WouldOverwriteInput { path: output.to_path_buf() });
        }
    }
    Ok(())
}

/// The canonical form of `p` if it exists, else its canonical parent joined with its
/// name, else its lexically normalised absolute form.
fn resolve(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let absolute = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let normal = normalize(&absolute);
    if let (Some(parent), Some(name)) = (normal.parent(), normal.file_name()) {
        if let Ok(c) = parent.canonicalize() {
            return c.join(name);
        }
    }
    normal
}

/// Removes `.` and resolves `..` lexically.
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

#[cfg(unix)]
fn same_inode(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_inode(_: &Path, _: &Path) -> bool {
    false
}

/// Checks that a raster's buffers match its size (and, with `nonempty`, that it has at
/// least one cell) before an exporter writes it, so no writer indexes out of bounds.
/// Errors name the output `path`.
pub(crate) fn check_raster(path: &Path, raster: &Raster, nonempty: bool) -> Result<()> {
    let cells = raster.width.checked_mul(raster.height).ok_or_else(|| {
        Error::format(path, Location::File, format!("the map's size {} × {} overflows", raster.width, raster.height))
    })?;
    if raster.log_odds.len() != cells || raster.known.len() != cells {
        return Err(Error::format(
            path,
            Location::File,
            format!(
                "the map is {} × {} = {cells} cells but holds {} log-odds and {} known flags",
                raster.width,
                raster.height,
                raster.log_odds.len(),
                raster.known.len()
            ),
        ));
    }
    if nonempty && cells == 0 {
        return Err(Error::format(
            path,
            Location::File,
            "the map is empty (no observed cells): this format cannot hold a 0-pixel image",
        ));
    }
    if !(raster.resolution.is_finite() && raster.resolution > 0.0 && raster.origin.is_finite()) {
        return Err(Error::format(
            path,
            Location::File,
            format!(
                "the map's resolution ({}) or origin ({}, {}) is not a finite placement",
                raster.resolution, raster.origin.x, raster.origin.y
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn temp_dir(tag: &str) -> crate::testdata::TestDir {
        crate::testdata::temp_dir(&format!("atomic-{tag}"))
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces() {
        let d = temp_dir("ok");
        let p = d.join("out.txt");
        std::fs::write(&p, b"old").unwrap();
        let n = write_atomic(&p, |w| {
            w.write_all(b"new content")?;
            Ok(42)
        })
        .unwrap();
        assert_eq!(n, 42);
        assert_eq!(std::fs::read(&p).unwrap(), b"new content");
        assert_eq!(entries(&d), ["out.txt"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn failure_keeps_the_old_file_and_removes_the_temp() {
        let d = temp_dir("fail");
        let p = d.join("out.txt");
        std::fs::write(&p, b"old").unwrap();
        let e = write_atomic(&p, |w| -> io::Result<()> {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path == &p), "{e}");
        assert!(e.to_string().contains("boom"));
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(entries(&d), ["out.txt"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn missing_directory_is_an_io_error_naming_the_target() {
        let d = temp_dir("nodir");
        let p = d.join("no/such/dir/out.txt");
        let e = write_atomic(&p, |_| Ok(())).unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path == &p));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn refuses_inputs() {
        let d = temp_dir("inputs");
        let input = d.join("run.bag");
        std::fs::write(&input, b"x").unwrap();
        let other = d.join("map.npz");
        assert!(ensure_not_input(&other, std::slice::from_ref(&input)).is_ok());
        assert!(matches!(
            ensure_not_input(&input, std::slice::from_ref(&input)),
            Err(Error::WouldOverwriteInput { .. })
        ));
        // The same file by another spelling.
        let dotted = d.join("sub/../run.bag");
        std::fs::create_dir(d.join("sub")).unwrap();
        assert!(ensure_not_input(&dotted, std::slice::from_ref(&input)).is_err());
        // An input that does not exist yet, named twice.
        let ghost = d.join("ghost.npz");
        assert!(ensure_not_input(&ghost, &[d.join("./ghost.npz")]).is_err());
        #[cfg(unix)]
        {
            let link = d.join("link.bag");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(ensure_not_input(&link, std::slice::from_ref(&input)).is_err());
            let hard = d.join("hard.bag");
            std::fs::hard_link(&input, &hard).unwrap();
            assert!(ensure_not_input(&hard, std::slice::from_ref(&input)).is_err());
        }
        std::fs::remove_dir_all(&d).unwrap();
    }
}
