//! Reading on a second thread: a [`Read`] whose bytes another thread produces ahead of
//! the consumer, so that decompressing a log (gzip) and parsing it run on two cores.

use std::io::{self, Read};
use std::sync::mpsc::{sync_channel, Receiver};
use std::thread;

/// Bytes read from an inner reader by a background thread, in blocks, a few blocks
/// ahead. Errors of the inner reader arrive, with their kind, at the point of the stream
/// where they happened; the thread ends at the inner reader's end, at its first error, or
/// when this reader is dropped.
pub struct ReadAhead {
    blocks: Receiver<io::Result<Vec<u8>>>,
    block: Vec<u8>,
    pos: usize,
    ended: bool,
}

impl ReadAhead {
    /// Starts reading `inner` on a new thread in blocks of `block_size` bytes, at most
    /// `depth` blocks ahead of the consumer.
    pub fn spawn<R: Read + Send + 'static>(mut inner: R, block_size: usize, depth: usize) -> io::Result<Self> {
        let (tx, rx) = sync_channel(depth.max(1));
        let block_size = block_size.max(1);
        thread::Builder::new().name("fusemap-read-ahead".into()).spawn(move || loop {
            let mut block = vec![0u8; block_size];
            let mut filled = 0;
            let result = loop {
                match inner.read(&mut block[filled..]) {
                    Ok(0) => break Ok(()),
                    Ok(n) => {
                        filled += n;
                        if filled == block.len() {
                            break Ok(());
                        }
                    }
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(e) => break Err(e),
                }
            };
            block.truncate(filled);
            let at_end = filled < block_size;
            if filled > 0 && tx.send(Ok(block)).is_err() {
                return;
            }
            if let Err(e) = result {
                let _ = tx.send(Err(e));
                return;
            }
            if at_end {
                return;
            }
        })?;
        Ok(Self { blocks: rx, block: Vec::new(), pos: 0, ended: false })
    }
}

impl Read for ReadAhead {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        if out.is_empty() {
            return Ok(0);
        }
        while self.pos == self.block.len() {
            if self.ended {
                return Ok(0);
            }
            match self.blocks.recv() {
                Ok(Ok(block)) => {
                    self.block = block;
                    self.pos = 0;
                }
                Ok(Err(e)) => {
                    self.ended = true;
                    return Err(e);
                }
                // The thread finished: the inner reader's end.
                Err(_) => {
                    self.ended = true;
                    return Ok(0);
                }
            }
        }
        let n = out.len().min(self.block.len() - self.pos);
        out[..n].copy_from_slice(&self.block[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Yields `data` in odd-sized pieces, then fails with `kind` if given.
    struct Pieces {
        data: Vec<u8>,
        at: usize,
        fail: Option<io::ErrorKind>,
    }

    impl Read for Pieces {
        fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
            if self.at == self.data.len() {
                return match self.fail {
                    Some(k) => Err(io::Error::new(k, "inner failure")),
                    None => Ok(0),
                };
            }
            let n = out.len().min(7).min(self.data.len() - self.at);
            out[..n].copy_from_slice(&self.data[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }

    #[test]
    fn same_bytes_in_the_same_order() {
        let data: Vec<u8> = (0..100_000u32).map(|i| (i * 31 % 251) as u8).collect();
        for block in [1, 10, 4096, 1 << 20] {
            let mut r = ReadAhead::spawn(Pieces { data: data.clone(), at: 0, fail: None }, block, 3).unwrap();
            let mut got = Vec::new();
            r.read_to_end(&mut got).unwrap();
            assert_eq!(got, data, "block {block}");
            assert_eq!(r.read(&mut [0u8; 8]).unwrap(), 0);
        }
    }

    #[test]
    fn errors_arrive_after_the_bytes_before_them() {
        let data = vec![7u8; 10_000];
        let mut r =
            ReadAhead::spawn(Pieces { data, at: 0, fail: Some(io::ErrorKind::UnexpectedEof) }, 4096, 2).unwrap();
        let mut got = Vec::new();
        let e = r.read_to_end(&mut got).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::UnexpectedEof);
        assert_eq!(got.len(), 10_000);
    }

    #[test]
    fn dropping_early_stops_the_thread() {
        // An endless inner reader: the thread must not block forever once we are gone.
        struct Endless;
        impl Read for Endless {
            fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
                out.fill(1);
                Ok(out.len())
            }
        }
        let mut r = ReadAhead::spawn(Endless, 1024, 2).unwrap();
        let mut b = [0u8; 10];
        r.read_exact(&mut b).unwrap();
        drop(r);
    }
}
