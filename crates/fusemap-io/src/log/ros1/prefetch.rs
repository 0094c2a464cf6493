//! Decompressing every other chunk on a second core.
//!
//! bz2 decompression is nine tenths of reading a bz2 bag (the Intel bag: 0.32 s of
//! 0.35 s, as fast as C libbz2) and one chunk cannot be split, so two chunks are
//! decompressed at once: a helper thread with its own handle on the file walks the
//! top-level records and decompresses the 2nd, 4th, 6th … compressed chunk, while the
//! reader decompresses the others itself as it meets them. The reader still reads and
//! checks every record; the helper only saves it the decompression of its chunks. When
//! the helper cannot deliver a chunk (it met an error, the file changed, it is still
//! behind), the reader decompresses that chunk itself, so errors and results are the
//! same as without it.

use super::record;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::mpsc::{sync_channel, Receiver};

/// What the walk reads from: a file, or bytes in a test.
trait ReadSeek: Read + Seek {}
impl<T: Read + Seek> ReadSeek for T {}

/// The helper thread's side of the bag: chunks it decompressed, by record offset.
pub(super) struct Prefetch {
    chunks: Receiver<(u64, Vec<u8>)>,
    peeked: Option<(u64, Vec<u8>)>,
    closed: bool,
}

impl Prefetch {
    /// Starts the helper on a second handle on `path`; `None` if that cannot be had. It
    /// leaves chunks that say they inflate past `max_chunk` bytes to the reader, which
    /// refuses them.
    pub(super) fn spawn(path: &Path, max_chunk: u64) -> Option<Self> {
        let file = File::open(path).ok()?;
        let file_len = file.metadata().ok()?.len();
        // One chunk ready and one in the making: at most two decompressed chunks wait.
        let (tx, rx) = sync_channel(1);
        std::thread::Builder::new()
            .name("fusemap-bag-chunks".into())
            .spawn(move || {
                let mut input = BufReader::with_capacity(1 << 16, file);
                let _ = walk(&mut input, file_len, max_chunk, |offset, data| tx.send((offset, data)).is_ok());
            })
            .ok()?;
        Some(Self { chunks: rx, peeked: None, closed: false })
    }

    /// The decompressed data of the chunk record at `offset`, if the helper made it.
    /// Waits for the helper when it is still working towards that chunk.
    pub(super) fn take(&mut self, offset: u64) -> Option<Vec<u8>> {
        loop {
            match self.peeked.take() {
                Some((o, data)) if o == offset => return Some(data),
                Some(item) if item.0 > offset => {
                    self.peeked = Some(item);
                    return None;
                }
                // Stale (a chunk the reader has passed): drop it.
                Some(_) => {}
                None if self.closed => return None,
                None => match self.chunks.recv() {
                    Ok(item) => self.peeked = Some(item),
                    Err(_) => self.closed = true,
                },
            }
        }
    }
}

/// Walks the top-level records of a file of `file_len` bytes and hands every second
/// compressed chunk, decompressed, to `deliver` (which returns `false` to stop). Stops
/// quietly at the first problem: the reader meets and reports it itself. A length field
/// is checked against what is left of the file before anything is allocated for it, so a
/// corrupt one costs nothing.
fn walk(
    input: &mut impl ReadSeek,
    file_len: u64,
    max_chunk: u64,
    mut deliver: impl FnMut(u64, Vec<u8>) -> bool,
) -> Option<()> {
    let mut magic = [0u8; 13];
    input.read_exact(&mut magic).ok()?;
    if magic != record::MAGIC {
        return None;
    }
    let mut offset = record::MAGIC.len() as u64;
    let mut header = Vec::new();
    let mut data = Vec::new();
    let mut compressed = 0u64;
    loop {
        let mut len = [0u8; 4];
        input.read_exact(&mut len).ok()?;
        let header_len = u32::from_le_bytes(len) as usize;
        if offset + 4 + header_len as u64 > file_len {
            return None;
        }
        header.clear();
        header.try_reserve_exact(header_len).ok()?;
        header.resize(header_len, 0);
        input.read_exact(&mut header).ok()?;
        input.read_exact(&mut len).ok()?;
        let data_len = u32::from_le_bytes(len);
        if offset + 8 + header_len as u64 + u64::from(data_len) > file_len {
            return None;
        }
        let h = record::parse_header(&header).ok()?;
        let (is_chunk, compression, size) = (h.op == Some(record::OP_CHUNK), h.compression, h.size);
        let ours = match (is_chunk, compression) {
            (true, Some(c)) if c == b"bz2" || c == b"lz4" => {
                compressed += 1;
                compressed.is_multiple_of(2)
            }
            _ => false,
        };
        if ours && size.is_some_and(|s| u64::from(s) > max_chunk) {
            return None;
        }
        if ours {
            data.clear();
            data.try_reserve_exact(data_len as usize).ok()?;
            data.resize(data_len as usize, 0);
            input.read_exact(&mut data).ok()?;
            let mut out = Vec::new();
            record::decompress(compression?, &data, size?, &mut out).ok()?;
            if !deliver(offset, out) {
                return None;
            }
        } else {
            input.seek(SeekFrom::Current(i64::from(data_len))).ok()?;
        }
        offset += 4 + header_len as u64 + 4 + u64::from(data_len);
    }
}
