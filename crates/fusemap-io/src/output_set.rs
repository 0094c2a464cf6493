//! A run's outputs as one set: all of them, or the previous run's, never a mixture.
//!
//! Writing each file atomically ([`write_atomic`]) keeps every file whole, but a run
//! that fails half-way (disk full after `map.npz`, a killed process) would still leave the
//! new `map.npz` beside the old `map.pgm`. An [`OutputSet`] therefore stages every file in
//! a private directory inside the output directory and moves them into place only when
//! all are written; `summary.json` comes last and lists each file with its size and
//! SHA-256, so a reader can tell a complete set, and check it.
//!
//! * **Failure leaves the old set.** Until [`OutputSet::commit`] nothing in the output
//!   directory changes; dropping the set uncommitted removes its staging directory.
//! * **One run at a time.** The set holds an exclusive lock on `DIR/.fusemap.lock`
//!   (`flock`, released by the kernel when the process ends, however it ends): a second
//!   run into the same directory is refused while the first is alive.
//! * **A killed run is cleaned up** by the next one, which holds the lock and so knows
//!   that any `.fusemap-staging-*` directory it finds is a dead run's.
//! * **Stale files go.** Known output names this run did not write are removed at commit,
//!   so no file of an earlier run lies beside a summary that does not list it.

use crate::atomic::{sync_dir, write_atomic};
use crate::{Error, Result};
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// The lock file inside an output directory.
pub const LOCK_FILE: &str = ".fusemap.lock";

/// The prefix of staging directories inside an output directory.
const STAGING_PREFIX: &str = ".fusemap-staging-";

/// One file of a committed set.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct OutputFile {
    /// Its name in the output directory.
    pub name: String,
    /// Its size, bytes.
    pub bytes: u64,
    /// SHA-256 of its content, lower-case hex.
    pub sha256: String,
}

/// A set of outputs being written into one directory (see the module docs).
#[derive(Debug)]
pub struct OutputSet {
    dir: PathBuf,
    staging: PathBuf,
    /// Held open for the lock; released on drop.
    _lock: File,
    committed: bool,
    /// The directories this set made, the output directory first and its new parents
    /// after it: an uncommitted set removes them again (the output directory with its
    /// lock file), so a run that fails on its input leaves nothing.
    created: Vec<PathBuf>,
}

impl OutputSet {
    /// Creates `dir` if needed, takes its lock, removes staging directories of dead runs
    /// and opens a fresh staging directory.
    pub fn begin(dir: &Path) -> Result<Self> {
        let created: Vec<PathBuf> =
            dir.ancestors().take_while(|d| !d.as_os_str().is_empty() && !d.exists()).map(Path::to_path_buf).collect();
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let lock_path = dir.join(LOCK_FILE);
        let lock = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(|e| Error::io(&lock_path, e))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                return Err(Error::io(
                    dir,
                    io::Error::new(
                        io::ErrorKind::WouldBlock,
                        format!(
                            "another fusemap run is writing into this directory (it holds {LOCK_FILE}); \
                             wait for it, or give another --out"
                        ),
                    ),
                ))
            }
            Err(TryLockError::Error(e)) => return Err(Error::io(&lock_path, e)),
        }
        // Holding the lock, every staging directory here is a dead run's.
        // A leftover that cannot be removed is only wasted space, not a wrong set: the
        // commit moves this run's own staging directory's files, never a dead run's.
        for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let e = e.map_err(|e| Error::io(dir, e))?;
            if e.file_name().to_string_lossy().starts_with(STAGING_PREFIX) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
        let staging = dir.join(format!("{STAGING_PREFIX}{}", std::process::id()));
        std::fs::create_dir(&staging).map_err(|e| Error::io(&staging, e))?;
        Ok(Self { dir: dir.to_path_buf(), staging, _lock: lock, committed: false, created })
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The staging directory the set's files are written into until the commit.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// Where a writer puts the file `name` of this set until the commit; `name` may name a
    /// subdirectory (`lidar/map.npz`), which the writer creates inside the staging
    /// directory and the commit recreates in the output directory.
    pub fn staged(&self, name: &str) -> PathBuf {
        self.staging.join(name)
    }

    /// Moves every staged file into the output directory, removes the files of `known`
    /// this set does not hold, and writes `summary_name` last with the bytes
    /// `summary(files)` makes of the list of files moved (name, size, SHA-256). A `known`
    /// entry ending in `/` names a directory the set owns: every file under it that the
    /// set does not hold is removed.
    ///
    /// Every destination is checked before anything in the output directory changes: a
    /// parent that is a symbolic link or not a directory, or a destination that is a
    /// directory, is an error while the previous set is still whole.
    pub fn commit(
        mut self,
        known: &[&str],
        summary_name: &str,
        summary: impl FnOnce(&[OutputFile]) -> Result<Vec<u8>>,
    ) -> Result<Vec<OutputFile>> {
        let mut names = Vec::new();
        list_files(&self.staging, "", &mut names)?;
        names.sort();
        let mut files = Vec::with_capacity(names.len());
        for name in &names {
            let path = self.staged(name);
            let (bytes, sha256) = digest(&path).map_err(|e| Error::io(&path, e))?;
            files.push(OutputFile { name: name.clone(), bytes, sha256 });
        }
        for name in &names {
            check_destination(&self.dir, name)?;
        }
        // The old summary goes first: should the commit stop half-way (a rename refused, the
        // process killed), the directory holds no summary that claims a complete set.
        let old_summary = self.dir.join(summary_name);
        match std::fs::remove_file(&old_summary) {
            Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(Error::io(&old_summary, e)),
            _ => sync_dir(&self.dir),
        }
        // Every file is whole on disk (each was fsynced by its writer); now the names.
        for name in &names {
            let to = self.dir.join(name);
            if let Some(parent) = Path::new(name).parent().filter(|p| !p.as_os_str().is_empty()) {
                let parent = self.dir.join(parent);
                std::fs::create_dir_all(&parent).map_err(|e| Error::io(&parent, e))?;
            }
            std::fs::rename(self.staged(name), &to).map_err(|e| Error::io(&to, e))?;
        }
        let mut known_files: Vec<String> = Vec::new();
        for k in known {
            match k.strip_suffix('/') {
                Some(sub) => {
                    let dir = self.dir.join(sub);
                    let is_dir = std::fs::symlink_metadata(&dir).is_ok_and(|m| m.is_dir());
                    if is_dir {
                        list_files(&dir, k, &mut known_files)?;
                    }
                }
                None => known_files.push(k.to_string()),
            }
        }
        for stale in known_files.iter().filter(|k| !names.iter().any(|n| n == *k) && *k != summary_name) {
            let path = self.dir.join(stale);
            match std::fs::remove_file(&path) {
                Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(Error::io(&path, e)),
                _ => {}
            }
        }
        sync_dir(&self.dir);
        let bytes = summary(&files)?;
        write_atomic(&self.dir.join(summary_name), |w| w.write_all(&bytes))?;
        self.committed = true;
        let _ = std::fs::remove_dir_all(&self.staging);
        Ok(files)
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            // A directory this run made and wrote nothing into goes again: only its lock
            // file is there. `remove_dir` (not `_all`) leaves it if anything else appeared.
            let only_lock = std::fs::read_dir(&self.dir)
                .map(|entries| entries.flatten().all(|e| e.file_name() == LOCK_FILE))
                .unwrap_or(false);
            if !self.created.is_empty() && only_lock && std::fs::remove_file(self.dir.join(LOCK_FILE)).is_ok() {
                // Leaf first; a parent that is not empty (anything else appeared) stays.
                for d in &self.created {
                    if std::fs::remove_dir(d).is_err() {
                        break;
                    }
                }
            }
        }
    }
}

/// Refuses to move `name` (a `/`-separated path) into `dir` when one of its parents there
/// is a symbolic link or not a directory, or when the destination is a directory: the
/// rename would fail half-way through the commit, or land outside `dir`.
fn check_destination(dir: &Path, name: &str) -> Result<()> {
    let mut at = dir.to_path_buf();
    let parts: Vec<&str> = name.split('/').collect();
    for (i, part) in parts.iter().enumerate() {
        at.push(part);
        let last = i + 1 == parts.len();
        let meta = match std::fs::symlink_metadata(&at) {
            Ok(m) => m,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(Error::io(&at, e)),
        };
        let what = if meta.file_type().is_symlink() && !last {
            "is a symbolic link; the set's files go only into directories of the output directory"
        } else if !last && !meta.is_dir() {
            "is not a directory, and this run writes files into it"
        } else if last && meta.is_dir() {
            "is a directory, and this run writes a file of that name"
        } else {
            continue;
        };
        return Err(Error::io(&at, io::Error::new(io::ErrorKind::AlreadyExists, what)));
    }
    Ok(())
}

/// Appends the files under `dir` to `names`, as paths relative to the staging directory
/// (`prefix` is `dir`'s) with `/` between components; names starting with `.` are
/// skipped. An entry that cannot be read is an error, not a file quietly left out of the
/// set.
fn list_files(dir: &Path, prefix: &str, names: &mut Vec<String>) -> Result<()> {
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let e = e.map_err(|e| Error::io(dir, e))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let rel = format!("{prefix}{name}");
        if e.file_type().map_err(|err| Error::io(&e.path(), err))?.is_dir() {
            list_files(&e.path(), &format!("{rel}/"), names)?;
        } else {
            names.push(rel);
        }
    }
    Ok(())
}

/// The size and SHA-256 (hex) of the file at `path`.
pub fn digest(path: &Path) -> io::Result<(u64, String)> {
    let mut f = File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut bytes = 0u64;
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        bytes += n as u64;
    }
    let hex = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok((bytes, hex))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn a_committed_set_replaces_the_old_one_and_lists_itself() {
        let dir = crate::testdata::temp_dir("output-set-commit");
        std::fs::write(dir.join("map.pgm"), b"old pgm").unwrap();
        std::fs::write(dir.join("slam.png"), b"old slam").unwrap();
        std::fs::write(dir.join("notes.txt"), b"the user's").unwrap();
        let set = OutputSet::begin(&dir).unwrap();
        std::fs::write(set.staged("map.pgm"), b"new pgm").unwrap();
        std::fs::write(set.staged("map.npz"), b"").unwrap();
        // Nothing moves before the commit.
        assert_eq!(std::fs::read(dir.join("map.pgm")).unwrap(), b"old pgm");
        let known = ["map.pgm", "map.npz", "slam.png", "summary.json"];
        let files = set
            .commit(&known, "summary.json", |files| {
                Ok(serde_json::to_vec(&files.iter().map(|f| &f.name).collect::<Vec<_>>()).unwrap())
            })
            .unwrap();
        assert_eq!(names(&dir), [".fusemap.lock", "map.npz", "map.pgm", "notes.txt", "summary.json"]);
        assert_eq!(std::fs::read(dir.join("map.pgm")).unwrap(), b"new pgm");
        assert_eq!(std::fs::read_to_string(dir.join("summary.json")).unwrap(), r#"["map.npz","map.pgm"]"#);
        assert_eq!(files[1].bytes, 7);
        // SHA-256 of the empty file and of "new pgm", as `sha256sum` prints them.
        assert_eq!(files[0].sha256, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
        assert_eq!(files[1].sha256, digest(&dir.join("map.pgm")).unwrap().1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn files_in_subdirectories_move_with_the_set_and_are_listed_by_their_paths() {
        let dir = crate::testdata::temp_dir("output-set-subdirs");
        std::fs::create_dir_all(dir.join("lidar")).unwrap();
        std::fs::write(dir.join("lidar/map.pgm"), b"old lidar").unwrap();
        std::fs::write(dir.join("lidar/mine.txt"), b"the user's").unwrap();
        let set = OutputSet::begin(&dir).unwrap();
        std::fs::create_dir_all(set.staged("lidar")).unwrap();
        std::fs::create_dir_all(set.staged("sim/bag")).unwrap();
        std::fs::write(set.staged("lidar/map.pgm"), b"new lidar").unwrap();
        std::fs::write(set.staged("sim/bag/metadata.yaml"), b"m").unwrap();
        std::fs::write(set.staged("map.pgm"), b"p").unwrap();
        let files = set.commit(&[], "summary.json", |_| Ok(Vec::new())).unwrap();
        let listed: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(listed, ["lidar/map.pgm", "map.pgm", "sim/bag/metadata.yaml"]);
        assert_eq!(std::fs::read(dir.join("lidar/map.pgm")).unwrap(), b"new lidar");
        assert_eq!(std::fs::read(dir.join("lidar/mine.txt")).unwrap(), b"the user's");
        assert_eq!(std::fs::read(dir.join("sim/bag/metadata.yaml")).unwrap(), b"m");
        assert_eq!(names(&dir), [".fusemap.lock", "lidar", "map.pgm", "sim", "summary.json"]);
        // A directory the set owns loses the files the next set does not write; a
        // directory it does not own keeps them.
        std::fs::write(dir.join("sim/bag/old.db3"), b"old").unwrap();
        let set = OutputSet::begin(&dir).unwrap();
        std::fs::create_dir_all(set.staged("sim/bag")).unwrap();
        std::fs::write(set.staged("sim/bag/metadata.yaml"), b"m2").unwrap();
        set.commit(&["sim/"], "summary.json", |_| Ok(Vec::new())).unwrap();
        assert!(!dir.join("sim/bag/old.db3").exists());
        assert!(dir.join("lidar/mine.txt").exists() && dir.join("lidar/map.pgm").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_destination_that_cannot_take_the_file_fails_before_the_old_set_changes() {
        let dir = crate::testdata::temp_dir("output-set-destinations");
        let elsewhere = crate::testdata::temp_dir("output-set-elsewhere");
        std::fs::write(dir.join("summary.json"), b"old summary").unwrap();
        std::fs::write(dir.join("lidar"), b"a file where a directory goes").unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&elsewhere, dir.join("sim")).unwrap();
        std::fs::create_dir(dir.join("map.png")).unwrap();
        let cases: &[&str] =
            if cfg!(unix) { &["lidar/map.pgm", "sim/bag.mcap", "map.png"] } else { &["lidar/map.pgm"] };
        for name in cases {
            let set = OutputSet::begin(&dir).unwrap();
            let staged = set.staged(name);
            std::fs::create_dir_all(staged.parent().unwrap()).unwrap();
            std::fs::write(&staged, b"new").unwrap();
            let e = set.commit(&[], "summary.json", |_| Ok(Vec::new())).unwrap_err().to_string();
            assert!(e.contains(name.split('/').next().unwrap()), "{name}: {e}");
            assert_eq!(std::fs::read(dir.join("summary.json")).unwrap(), b"old summary", "{name}");
        }
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0, "nothing moved through the link");
        std::fs::remove_dir_all(&dir).unwrap();
        std::fs::remove_dir_all(&elsewhere).unwrap();
    }

    #[test]
    fn an_uncommitted_set_leaves_the_old_one_whole() {
        let dir = crate::testdata::temp_dir("output-set-failed");
        std::fs::write(dir.join("map.pgm"), b"old pgm").unwrap();
        std::fs::write(dir.join("summary.json"), b"old summary").unwrap();
        {
            let set = OutputSet::begin(&dir).unwrap();
            std::fs::write(set.staged("map.pgm"), b"half a new").unwrap();
            // The run fails here: the set is dropped.
        }
        assert_eq!(names(&dir), [".fusemap.lock", "map.pgm", "summary.json"]);
        assert_eq!(std::fs::read(dir.join("map.pgm")).unwrap(), b"old pgm");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_uncommitted_set_removes_the_directory_it_made() {
        let parent = crate::testdata::temp_dir("output-set-made");
        let dir = parent.join("out/run");
        drop(OutputSet::begin(&dir).unwrap());
        // The run failed before writing anything: `run` goes, and so does the `out` it made.
        assert!(!dir.exists() && !parent.join("out").exists() && parent.is_dir());
        // Something else written there meanwhile keeps the directory.
        let set = OutputSet::begin(&dir).unwrap();
        std::fs::write(dir.join("mine.txt"), b"the user's").unwrap();
        drop(set);
        assert_eq!(names(&dir), [".fusemap.lock", "mine.txt"]);
        std::fs::remove_dir_all(&parent).unwrap();
    }

    #[test]
    fn a_second_run_is_refused_and_a_dead_runs_staging_is_cleaned() {
        let dir = crate::testdata::temp_dir("output-set-lock");
        // A killed run's leftovers: its staging directory (its lock died with it).
        std::fs::create_dir_all(dir.join(".fusemap-staging-999999")).unwrap();
        std::fs::write(dir.join(".fusemap-staging-999999/map.npz"), b"partial").unwrap();
        let first = OutputSet::begin(&dir).unwrap();
        assert!(!dir.join(".fusemap-staging-999999").exists());
        let e = OutputSet::begin(&dir).unwrap_err().to_string();
        assert!(e.contains("another fusemap run") && e.contains(&dir.display().to_string()), "{e}");
        drop(first);
        // Released with the first set: the next run goes ahead.
        let again = OutputSet::begin(&dir).unwrap();
        drop(again);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
