//! A bounds-checked little-endian reader over a byte slice.
//!
//! Every read of a record header, a chunk or a message payload goes through [`Cursor`],
//! so input that is short or lies about a length becomes a [`Malformed`] naming the
//! field, never a panic or a huge allocation.

use fusemap_core::time::Stamp;
use std::fmt;

/// What was wrong with a byte sequence, in plain words ("ranges array claims 1000000000
/// elements but 12 bytes remain").
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Malformed(pub String);

impl fmt::Display for Malformed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl Malformed {
    /// Puts `context: ` before the description.
    pub(super) fn context(self, context: impl fmt::Display) -> Malformed {
        Malformed(format!("{context}: {}", self.0))
    }
}

/// A read position in a byte slice; reads consume from the front.
#[derive(Clone, Debug)]
pub(super) struct Cursor<'a> {
    rest: &'a [u8],
    len: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `bytes`.
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        Self { rest: bytes, len: bytes.len() }
    }

    /// Bytes consumed so far.
    pub(super) fn position(&self) -> usize {
        self.len - self.rest.len()
    }

    /// Bytes not yet consumed.
    pub(super) fn remaining(&self) -> usize {
        self.rest.len()
    }

    /// True when everything was consumed.
    pub(super) fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }

    /// The next `n` bytes.
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], Malformed> {
        match self.rest.split_at_checked(n) {
            Some((head, tail)) => {
                self.rest = tail;
                Ok(head)
            }
            None => Err(Malformed(format!("{what}: needs {n} bytes but {} remain", self.rest.len()))),
        }
    }

    /// The next `N` bytes as an array.
    pub(super) fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], Malformed> {
        match self.rest.split_first_chunk::<N>() {
            Some((head, tail)) => {
                self.rest = tail;
                Ok(*head)
            }
            None => Err(Malformed(format!("{what}: needs {N} bytes but {} remain", self.rest.len()))),
        }
    }

    /// A little-endian `u32`.
    pub(super) fn u32(&mut self, what: &str) -> Result<u32, Malformed> {
        self.array::<4>(what).map(u32::from_le_bytes)
    }

    /// A little-endian `f32`.
    pub(super) fn f32(&mut self, what: &str) -> Result<f32, Malformed> {
        self.array::<4>(what).map(f32::from_le_bytes)
    }

    /// `N` little-endian `f64`s in a row (a fixed-size array or a small struct of them).
    pub(super) fn f64s<const N: usize>(&mut self, what: &str) -> Result<[f64; N], Malformed> {
        let bytes = self.take(N * 8, what)?;
        let mut out = [0.0; N];
        let (chunks, _) = bytes.as_chunks::<8>();
        for (o, c) in out.iter_mut().zip(chunks) {
            *o = f64::from_le_bytes(*c);
        }
        Ok(out)
    }

    /// A ROS 1 `time`: `u32` seconds then `u32` nanoseconds.
    pub(super) fn time(&mut self, what: &str) -> Result<Stamp, Malformed> {
        let [s0, s1, s2, s3, n0, n1, n2, n3] = self.array::<8>(what)?;
        let sec = u32::from_le_bytes([s0, s1, s2, s3]);
        let nsec = u32::from_le_bytes([n0, n1, n2, n3]);
        Ok(Stamp::from_sec_nsec(i64::from(sec), nsec))
    }

    /// A `u32` length then that many bytes (a ROS string, a record header or data block).
    pub(super) fn prefixed(&mut self, what: &str) -> Result<&'a [u8], Malformed> {
        let n = self.u32(what)?;
        let n = usize::try_from(n).unwrap_or(usize::MAX);
        if n > self.rest.len() {
            return Err(Malformed(format!("{what}: claims {n} bytes but {} remain", self.rest.len())));
        }
        self.take(n, what)
    }

    /// A ROS string, decoded as UTF-8 (invalid sequences replaced: frame names are
    /// compared, not trusted).
    pub(super) fn string(&mut self, what: &str) -> Result<String, Malformed> {
        self.prefixed(what).map(|b| String::from_utf8_lossy(b).into_owned())
    }

    /// The length prefix of a variable-length array whose elements take at least
    /// `min_element_size` bytes each, checked against what remains.
    pub(super) fn array_len(&mut self, min_element_size: usize, what: &str) -> Result<usize, Malformed> {
        let n = self.u32(what)?;
        let fits = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(min_element_size))
            .is_some_and(|bytes| bytes <= self.rest.len());
        if fits {
            Ok(n as usize)
        } else {
            Err(Malformed(format!("{what} array claims {n} elements but {} bytes remain", self.rest.len())))
        }
    }

    /// A variable-length `float32[]`, decoded in one pass.
    pub(super) fn f32_vec(&mut self, what: &str) -> Result<Vec<f32>, Malformed> {
        let n = self.array_len(4, what)?;
        let bytes = self.take(n * 4, what)?;
        let (chunks, _) = bytes.as_chunks::<4>();
        Ok(chunks.iter().map(|c| f32::from_le_bytes(*c)).collect())
    }

    /// A variable-length `float64[]`.
    pub(super) fn f64_vec(&mut self, what: &str) -> Result<Vec<f64>, Malformed> {
        let n = self.array_len(8, what)?;
        let bytes = self.take(n * 8, what)?;
        let (chunks, _) = bytes.as_chunks::<8>();
        Ok(chunks.iter().map(|c| f64::from_le_bytes(*c)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_little_endian_and_refuses_short_input() {
        let bytes = [1, 0, 0, 0, 0, 0, 0x80, 0x3f, 9];
        let mut c = Cursor::new(&bytes);
        assert_eq!(c.u32("a"), Ok(1));
        assert_eq!(c.f32("b"), Ok(1.0));
        assert_eq!(c.position(), 8);
        assert_eq!(c.u32("c"), Err(Malformed("c: needs 4 bytes but 1 remain".into())));
        // A failed read consumes nothing.
        assert_eq!(c.remaining(), 1);
    }

    #[test]
    fn lengths_are_checked_before_anything_is_allocated() {
        let mut bytes = 1_000_000_000u32.to_le_bytes().to_vec();
        bytes.extend([0; 12]);
        let e = Cursor::new(&bytes).f32_vec("ranges").unwrap_err();
        assert_eq!(e.0, "ranges array claims 1000000000 elements but 12 bytes remain");
        // u32::MAX elements of 4 bytes would overflow a 32-bit usize: still an error.
        let bytes = u32::MAX.to_le_bytes();
        assert!(Cursor::new(&bytes).f32_vec("ranges").is_err());
        assert!(Cursor::new(&bytes).string("frame_id").is_err());
    }

    #[test]
    fn floats_and_times() {
        let mut bytes = vec![3, 0, 0, 0];
        for v in [1.5f32, -2.0, f32::NAN] {
            bytes.extend(v.to_le_bytes());
        }
        bytes.extend(7u32.to_le_bytes());
        bytes.extend(5u32.to_le_bytes());
        bytes.extend(0.25f64.to_le_bytes());
        let mut c = Cursor::new(&bytes);
        let v = c.f32_vec("v").unwrap();
        assert_eq!(&v[..2], &[1.5, -2.0]);
        assert!(v[2].is_nan());
        assert_eq!(c.time("t"), Ok(Stamp(7_000_000_005)));
        assert_eq!(c.f64s::<1>("d"), Ok([0.25]));
        assert!(c.is_empty());
    }
}
