//! Reading a stream whose length nobody vouches for (a zstd frame, a decompressor's
//! output, a line of a gzipped log) into memory without letting it take more than a
//! budget: the buffer grows by fallible reservations, never past one byte over the limit,
//! so a decompression bomb is refused at the limit instead of by the allocator.
//! (`Vec`'s own growth doubles its capacity: a line one byte past a 512 MiB limit would
//! reserve 1 GiB before the limit was seen.)

use std::io::{self, BufRead, Read};

/// How much the buffer grows at a time at most (the first step is the smaller of this
/// and the budget).
const STEP: usize = 1 << 20;

/// What [`read_to_end_bounded`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounded {
    /// The whole stream fit in the budget; the buffer holds it.
    Complete,
    /// The stream holds more than the budget; the buffer holds `limit + 1` bytes of it.
    OverLimit,
}

/// Appends `reader`'s bytes to `buf` (cleared first) until its end or until it holds
/// `limit + 1` bytes, whichever comes first. Memory is reserved fallibly: a failed
/// reservation is an [`io::ErrorKind::OutOfMemory`] error, never an abort.
pub fn read_to_end_bounded(mut reader: impl Read, limit: u64, buf: &mut Vec<u8>) -> io::Result<Bounded> {
    buf.clear();
    let cap = usize::try_from(limit.saturating_add(1)).unwrap_or(usize::MAX);
    while buf.len() < cap {
        let room = cap - buf.len();
        if buf.len() == buf.capacity() {
            let grow = buf.capacity().clamp(STEP.min(room), STEP * 64).min(room);
            buf.try_reserve_exact(grow).map_err(|e| io::Error::new(io::ErrorKind::OutOfMemory, e))?;
        }
        // Exactly the spare capacity: `read_to_end` fills it without zeroing it first and,
        // meeting the `take`'s end, never grows the buffer itself.
        let want = (buf.capacity() - buf.len()).min(room);
        let n = (&mut reader).take(want as u64).read_to_end(buf)?;
        if n < want {
            break; // the stream's end
        }
    }
    Ok(if buf.len() as u64 > limit { Bounded::OverLimit } else { Bounded::Complete })
}

/// An empty `Vec` with room for `n` elements, or the allocator's refusal: for a count read
/// from a file (a sequence length, an image's rows, a header's size), where
/// `Vec::with_capacity` would abort the process instead of giving an error.
pub fn vec_with_capacity<T>(n: usize) -> Result<Vec<T>, std::collections::TryReserveError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)?;
    Ok(v)
}

/// Grows `buf` to hold `more` bytes past its length, at most to `max_len` bytes in all:
/// doubling (so appends stay amortised O(1)) but never past `max_len`, fallibly.
fn reserve(buf: &mut Vec<u8>, more: usize, max_len: usize) -> io::Result<()> {
    let need = buf.len() + more;
    if need <= buf.capacity() {
        return Ok(());
    }
    let target = buf.capacity().saturating_mul(2).max(need).min(max_len.max(need));
    buf.try_reserve_exact(target - buf.len()).map_err(|e| io::Error::new(io::ErrorKind::OutOfMemory, e))
}

/// [`BufRead::read_until`] that reads at most `limit + 1` bytes (appended to `buf`) and
/// grows `buf` by fallible reservations never past that: returns the bytes read, which
/// are `limit + 1` without a `delim` at the end when the record is longer than the limit.
pub fn read_until_bounded<R: BufRead + ?Sized>(
    reader: &mut R,
    delim: u8,
    limit: u64,
    buf: &mut Vec<u8>,
) -> io::Result<usize> {
    let cap = usize::try_from(limit.saturating_add(1)).unwrap_or(usize::MAX);
    let max_len = buf.len().saturating_add(cap);
    let mut read = 0usize;
    loop {
        let available = match reader.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            return Ok(read);
        }
        let window = &available[..available.len().min(cap - read)];
        let (used, done) = match memchr::memchr(delim, window) {
            Some(i) => (i + 1, true),
            None => (window.len(), read + window.len() == cap),
        };
        reserve(buf, used, max_len)?;
        buf.extend_from_slice(&window[..used]);
        reader.consume(used);
        read += used;
        if done {
            return Ok(read);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_within_the_budget_is_read_whole() {
        let data: Vec<u8> = (0..5000u32).map(|i| i as u8).collect();
        let mut buf = vec![9; 3];
        assert_eq!(read_to_end_bounded(&data[..], 5000, &mut buf).unwrap(), Bounded::Complete);
        assert_eq!(buf, data);
        assert_eq!(read_to_end_bounded(&data[..0], 0, &mut buf).unwrap(), Bounded::Complete);
        assert!(buf.is_empty());
    }

    #[test]
    fn one_byte_past_the_budget_is_over_and_no_more_is_read() {
        let data = vec![7u8; 5001];
        let mut buf = Vec::new();
        assert_eq!(read_to_end_bounded(&data[..], 5000, &mut buf).unwrap(), Bounded::OverLimit);
        assert_eq!(buf.len(), 5001);
        // An endless stream stops one byte past the limit, its buffer never larger.
        let endless = io::repeat(1);
        assert_eq!(read_to_end_bounded(endless, 3 << 20, &mut buf).unwrap(), Bounded::OverLimit);
        assert_eq!(buf.len(), (3 << 20) + 1);
        assert!(buf.capacity() <= (3 << 20) + 1, "{}", buf.capacity());
    }

    #[test]
    fn lines_are_read_as_read_until_reads_them_up_to_the_limit() {
        let text = b"one\ntwo two\n\nlast without newline";
        for limit in [0u64, 1, 3, 4, 7, 8, 100] {
            let mut ours = io::BufReader::with_capacity(5, &text[..]);
            let mut std_reader = &text[..];
            loop {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                let n = read_until_bounded(&mut ours, b'\n', limit, &mut a).unwrap();
                let m = (&mut std_reader).take(limit + 1).read_until(b'\n', &mut b).unwrap();
                assert_eq!((n, &a), (m, &b), "limit {limit}");
                assert!(a.capacity() as u64 <= limit + 1, "limit {limit}: capacity {}", a.capacity());
                if n == 0 {
                    break;
                }
            }
        }
    }

    #[test]
    fn an_endless_line_stops_one_byte_past_the_limit_without_doubling_past_it() {
        let mut endless = io::BufReader::new(io::repeat(b'a'));
        let mut buf = Vec::new();
        let limit = (5 << 20) + 3;
        assert_eq!(read_until_bounded(&mut endless, b'\n', limit, &mut buf).unwrap() as u64, limit + 1);
        assert_eq!(buf.capacity() as u64, limit + 1);
    }

    #[test]
    fn errors_of_the_stream_come_through() {
        struct Broken;
        impl Read for Broken {
            fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
                Err(io::Error::new(io::ErrorKind::InvalidData, "bad frame"))
            }
        }
        let e = read_to_end_bounded(Broken, 100, &mut Vec::new()).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
    }
}
