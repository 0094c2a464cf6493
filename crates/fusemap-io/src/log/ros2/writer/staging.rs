//! A bag directory that appears all at once.
//!
//! The files are written into a hidden sibling `.<name>.tmp-<pid>-<n>` (same parent, so
//! the same file system) and the directory is renamed to its name at the end: POSIX
//! `rename(2)` swaps the directory entry atomically, so a player or a `ros2 bag info`
//! running meanwhile sees no bag or the whole bag, never a bag without its
//! `metadata.yaml` or with a truncated MCAP file (the directory counterpart of
//! [`write_atomic`](crate::atomic::write_atomic)). A writer dropped before it finishes
//! removes the staging directory.
//!
//! An existing non-empty directory (or a file) at the target is refused unless
//! overwriting was asked for; then it is renamed aside, the new bag renamed in, and the
//! old one deleted — restored if the second rename fails.

use crate::error::{Error, Result};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The staging directory of one bag.
#[derive(Debug)]
pub(crate) struct StagingDir {
    target: PathBuf,
    parent: PathBuf,
    name: String,
    temp: PathBuf,
    overwrite: bool,
    committed: bool,
}

impl StagingDir {
    /// Checks the target and creates the staging directory beside it.
    pub(crate) fn create(target: &Path, overwrite: bool) -> Result<Self> {
        let name = match target.file_name().map(|n| n.to_str()) {
            Some(Some(n)) => n.to_string(),
            Some(None) => return Err(invalid(target, "the bag directory's name is not UTF-8")),
            None => return Err(invalid(target, "the path names no directory (it ends in `..` or is a root)")),
        };
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        check_target(target, overwrite)?;
        // Like `ros2 bag record -o a/b/run`, missing parent directories are made.
        std::fs::create_dir_all(&parent).map_err(|e| Error::io(target, e))?;
        let temp = sibling(&parent, &name, "tmp");
        std::fs::create_dir(&temp).map_err(|e| Error::io(target, e))?;
        Ok(Self { target: target.to_path_buf(), parent, name, temp, overwrite, committed: false })
    }

    /// Where the files go until [`commit`](Self::commit).
    pub(crate) fn path(&self) -> &Path {
        &self.temp
    }

    /// The bag directory's name (`run1` for `out/run1`).
    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    /// Renames the staging directory to the target.
    pub(crate) fn commit(mut self) -> Result<()> {
        check_target(&self.target, self.overwrite)?;
        let target = &self.target;
        match std::fs::symlink_metadata(target) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                std::fs::rename(&self.temp, target).map_err(|e| Error::io(target, e))?;
            }
            Err(e) => return Err(Error::io(target, e)),
            Ok(meta) if meta.is_dir() && is_empty_dir(target) => {
                // Linux renames over an empty directory; elsewhere remove it first.
                if std::fs::rename(&self.temp, target).is_err() {
                    std::fs::remove_dir(target).map_err(|e| Error::io(target, e))?;
                    std::fs::rename(&self.temp, target).map_err(|e| Error::io(target, e))?;
                }
            }
            Ok(meta) => {
                // Only reached with `overwrite` (check_target refused otherwise).
                let aside = sibling(&self.parent, &self.name, "old");
                std::fs::rename(target, &aside).map_err(|e| Error::io(target, e))?;
                if let Err(e) = std::fs::rename(&self.temp, target) {
                    let _ = std::fs::rename(&aside, target);
                    return Err(Error::io(target, e));
                }
                // The new bag is in place; failing to delete the old one is not an error
                // of this write, so it is best effort.
                let _ = if meta.is_dir() { std::fs::remove_dir_all(&aside) } else { std::fs::remove_file(&aside) };
            }
        }
        self.committed = true;
        sync_dir(&self.parent);
        Ok(())
    }
}

impl Drop for StagingDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.temp);
        }
    }
}

fn invalid(path: &Path, message: &str) -> Error {
    Error::io(path, io::Error::new(io::ErrorKind::InvalidInput, message))
}

/// `.<name>.<tag>-<pid>-<n>` in `parent`.
fn sibling(parent: &Path, name: &str, tag: &str) -> PathBuf {
    parent.join(format!(".{name}.{tag}-{}-{}", std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed)))
}

fn is_empty_dir(path: &Path) -> bool {
    std::fs::read_dir(path).is_ok_and(|mut entries| entries.next().is_none())
}

/// Nothing, an empty directory, or (with `overwrite`) anything.
fn check_target(target: &Path, overwrite: bool) -> Result<()> {
    match std::fs::symlink_metadata(target) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(target, e)),
        Ok(meta) if meta.is_dir() && is_empty_dir(target) => Ok(()),
        Ok(_) if overwrite => Ok(()),
        Ok(meta) => Err(Error::io(
            target,
            io::Error::new(
                io::ErrorKind::AlreadyExists,
                if meta.is_dir() {
                    "the directory exists and is not empty; refusing to overwrite it"
                } else {
                    "a file is in the way of the bag directory; refusing to overwrite it"
                },
            ),
        )),
    }
}

/// `fsync` of the parent makes the rename durable (best effort, as in [`crate::atomic`]).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn appears_at_commit_and_vanishes_when_dropped() {
        let d = crate::testdata::temp_dir("staging");
        let target = d.join("bag");
        let s = StagingDir::create(&target, false).unwrap();
        std::fs::write(s.path().join("x"), b"1").unwrap();
        assert!(!target.exists());
        assert_eq!(s.name(), "bag");
        s.commit().unwrap();
        assert_eq!(entries(&d), ["bag"]);
        assert_eq!(entries(&target), ["x"]);

        let other = d.join("other");
        let s = StagingDir::create(&other, false).unwrap();
        std::fs::write(s.path().join("x"), b"1").unwrap();
        drop(s);
        assert_eq!(entries(&d), ["bag"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn refuses_a_non_empty_target_unless_told() {
        let d = crate::testdata::temp_dir("staging-refuse");
        let target = d.join("bag");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("old"), b"keep").unwrap();
        let e = StagingDir::create(&target, false).unwrap_err();
        assert!(
            matches!(&e, Error::Io { path, source } if path == &target && source.kind() == io::ErrorKind::AlreadyExists),
            "{e}"
        );
        assert_eq!(entries(&d), ["bag"]);

        let s = StagingDir::create(&target, true).unwrap();
        std::fs::write(s.path().join("new"), b"1").unwrap();
        s.commit().unwrap();
        assert_eq!(entries(&target), ["new"]);
        assert_eq!(entries(&d), ["bag"], "no staging or old copy left behind");

        // An empty directory is taken without being told.
        let empty = d.join("empty");
        std::fs::create_dir(&empty).unwrap();
        let s = StagingDir::create(&empty, false).unwrap();
        std::fs::write(s.path().join("f"), b"1").unwrap();
        s.commit().unwrap();
        assert_eq!(entries(&empty), ["f"]);

        // Something that appears meanwhile is not overwritten at commit.
        let late = d.join("late");
        let s = StagingDir::create(&late, false).unwrap();
        std::fs::write(&late, b"someone else's").unwrap();
        assert!(s.commit().is_err());
        assert_eq!(std::fs::read(&late).unwrap(), b"someone else's");
        assert_eq!(entries(&d), ["bag", "empty", "late"]);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
