//! The writer under an [`super::NpzWriter`]'s zip archive, quiet after its first error.
//!
//! The zip crate finalizes an unfinished archive when its writer is dropped, and prints to
//! stderr when that fails. Once a write has failed (a full disk, a file-size limit) the
//! archive is discarded anyway and the caller's error says why, so the finalization must
//! neither print a second, confusing message nor touch the file again: after the first
//! error this sink accepts and drops everything, keeping only a position for the seeks.

use std::io::{self, Seek, SeekFrom, Write};

pub(super) struct QuietAfterError<W> {
    pub(super) inner: W,
    /// The position the sink pretends to be at once it failed (`None` before).
    failed_at: Option<u64>,
}

impl<W: Write + Seek> QuietAfterError<W> {
    pub(super) fn new(inner: W) -> Self {
        Self { inner, failed_at: None }
    }

    fn fail<T>(&mut self, e: io::Error) -> io::Result<T> {
        self.failed_at = Some(self.inner.stream_position().unwrap_or(0));
        Err(e)
    }
}

impl<W: Write + Seek> Write for QuietAfterError<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if let Some(pos) = &mut self.failed_at {
            *pos = pos.saturating_add(buf.len() as u64);
            return Ok(buf.len());
        }
        match self.inner.write(buf) {
            Err(e) if e.kind() != io::ErrorKind::Interrupted => self.fail(e),
            other => other,
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        if self.failed_at.is_some() {
            return Ok(());
        }
        match self.inner.flush() {
            Err(e) => self.fail(e),
            ok => ok,
        }
    }
}

impl<W: Write + Seek> Seek for QuietAfterError<W> {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let Some(pos) = &mut self.failed_at else {
            return match self.inner.seek(to) {
                Err(e) => self.fail(e),
                ok => ok,
            };
        };
        *pos = match to {
            SeekFrom::Start(n) => n,
            SeekFrom::Current(d) | SeekFrom::End(d) => pos.saturating_add_signed(d),
        };
        Ok(*pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fails every write past `room` bytes, as a full disk does.
    struct Full {
        data: io::Cursor<Vec<u8>>,
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.data.get_ref().len() + buf.len() > self.room {
                return Err(io::Error::new(io::ErrorKind::StorageFull, "no space left"));
            }
            self.data.write(buf)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    impl Seek for Full {
        fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
            self.data.seek(to)
        }
    }

    #[test]
    fn after_the_first_error_nothing_reaches_the_file() {
        let mut sink = QuietAfterError::new(Full { data: io::Cursor::new(Vec::new()), room: 10 });
        sink.write_all(b"12345").unwrap();
        assert_eq!(sink.write_all(b"too long!").unwrap_err().kind(), io::ErrorKind::StorageFull);
        // Later writes, flushes and seeks succeed without touching the file.
        sink.write_all(b"more").unwrap();
        sink.flush().unwrap();
        assert_eq!(sink.seek(SeekFrom::Start(2)).unwrap(), 2);
        sink.write_all(b"xyz").unwrap();
        assert_eq!(sink.stream_position().unwrap(), 5);
        assert_eq!(sink.inner.data.get_ref(), b"12345");
    }

    #[test]
    fn a_full_disk_under_an_npz_gives_one_error_and_no_panic() {
        let array = super::super::NpyArray::new(&[64, 64], super::super::NpyData::U8(&[0u8; 4096])).unwrap();
        let mut npz = super::super::NpzWriter::new(Full { data: io::Cursor::new(Vec::new()), room: 1000 });
        assert_eq!(npz.add("big", &array).unwrap_err().kind(), io::ErrorKind::StorageFull);
        drop(npz); // the zip crate finalizes here; the sink keeps it quiet
    }
}
