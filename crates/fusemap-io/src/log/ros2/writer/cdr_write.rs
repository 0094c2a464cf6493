//! Little-endian CDR out, the mirror of [`crate::log::ros2::cdr`].
//!
//! The layout is the one OMG CDR (DDS-XTypes 1.3, §7.4.3 "plain CDR") gives and ROS 2's
//! `rmw` layers write: a 4-byte encapsulation header `00 01 00 00` (plain CDR,
//! little-endian, no options), then each primitive aligned to its own size (at most 8)
//! *counted from the first byte after the header*, padding bytes zero. A `string` is a
//! `u32` byte count that includes a terminating NUL, then the bytes and the NUL; a
//! sequence (`T[]`) is a `u32` element count, then the elements; a fixed-size array
//! (`T[N]`) is its elements alone.
//!
//! The writer fails rather than writes something a reader would misread: a string with a
//! NUL inside (a C reader would cut it there), or a string or sequence longer than a
//! `u32` count can state.

use std::fmt;

/// The encapsulation header of plain little-endian CDR: representation `0x0001`, options 0.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a value cannot be written as CDR.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CdrWriteError {
    /// A string or sequence longer than its `u32` count can say.
    #[error("`{field}` has {len} elements, more than a CDR length (u32) can hold")]
    TooLong {
        /// The field.
        field: &'static str,
        /// Its length.
        len: usize,
    },
    /// A string with a NUL byte inside: CDR strings end at their NUL.
    #[error("`{field}` contains a NUL byte at {at}, which would end the CDR string early")]
    InteriorNul {
        /// The field.
        field: &'static str,
        /// Byte index of the first NUL.
        at: usize,
    },
    /// A stamp outside what `builtin_interfaces/Time` (an `int32` of seconds) can hold:
    /// before 1901-12-13 or after 2038-01-19 as Unix time.
    #[error("`{field}` = {nanoseconds} ns does not fit builtin_interfaces/Time (int32 seconds)")]
    StampOutOfRange {
        /// The field.
        field: &'static str,
        /// The stamp.
        nanoseconds: i64,
    },
}

/// A message type that can be written as little-endian CDR, fields in declaration order.
pub trait CdrEncode {
    /// Appends the fields to `w`.
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError>;
}

/// Serialises `value` into `buf` (cleared first), encapsulation header included, so one
/// buffer can be reused for a whole log.
pub fn encode_cdr_into<T: CdrEncode + ?Sized>(value: &T, buf: &mut Vec<u8>) -> Result<(), CdrWriteError> {
    buf.clear();
    let mut w = CdrWriter { buf: std::mem::take(buf) };
    w.buf.extend_from_slice(&CDR_LE_HEADER);
    let outcome = value.encode(&mut w);
    *buf = w.buf;
    outcome
}

/// Serialises `value` into a new buffer, encapsulation header included.
pub fn encode_cdr<T: CdrEncode + ?Sized>(value: &T) -> Result<Vec<u8>, CdrWriteError> {
    let mut buf = Vec::new();
    encode_cdr_into(value, &mut buf)?;
    Ok(buf)
}

/// An append-only little-endian CDR buffer that starts with the encapsulation header.
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl fmt::Debug for CdrWriter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CdrWriter").field("len", &self.buf.len()).finish()
    }
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A buffer holding just the encapsulation header.
    pub fn new() -> Self {
        Self { buf: CDR_LE_HEADER.to_vec() }
    }

    /// The payload so far, header included.
    pub fn as_bytes(&self) -> &[u8] {
        &self.buf
    }

    /// The payload, header included.
    pub fn into_bytes(self) -> Vec<u8> {
        self.buf
    }

    /// Zero padding up to a multiple of `n` bytes of the body (the header does not count).
    fn align(&mut self, n: usize) {
        let body = self.buf.len() - CDR_LE_HEADER.len();
        let pad = (n - body % n) % n;
        self.buf.resize(self.buf.len() + pad, 0);
    }

    /// A `bool` (one byte, 0 or 1).
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    /// A `uint8` (or `byte`/`char`).
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// An `int8`.
    pub fn i8(&mut self, v: i8) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint16`, aligned to 2.
    pub fn u16(&mut self, v: u16) {
        self.align(2);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An `int32`, aligned to 4.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint32`, aligned to 4.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`, aligned to 4, bit for bit (NaN payloads kept).
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`, aligned to 8, bit for bit.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A sequence or string count.
    fn count(&mut self, field: &'static str, len: usize) -> Result<(), CdrWriteError> {
        let n = u32::try_from(len).map_err(|_| CdrWriteError::TooLong { field, len })?;
        self.u32(n);
        Ok(())
    }

    /// A `string`: count (bytes + NUL), bytes, NUL.
    pub fn string(&mut self, field: &'static str, s: &str) -> Result<(), CdrWriteError> {
        if let Some(at) = s.bytes().position(|b| b == 0) {
            return Err(CdrWriteError::InteriorNul { field, at });
        }
        self.count(field, s.len() + 1)?;
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        Ok(())
    }

    /// A fixed-size `float64[N]` array: the elements, no count.
    pub fn f64_array(&mut self, v: &[f64]) {
        if !v.is_empty() {
            self.align(8);
        }
        for x in v {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// A `float64[]` sequence.
    pub fn f64_seq(&mut self, field: &'static str, v: &[f64]) -> Result<(), CdrWriteError> {
        self.count(field, v.len())?;
        self.f64_array(v);
        Ok(())
    }

    /// A `float32[]` sequence.
    pub fn f32_seq(&mut self, field: &'static str, v: &[f32]) -> Result<(), CdrWriteError> {
        self.count(field, v.len())?;
        for x in v {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
        Ok(())
    }

    /// A `uint8[]` sequence (image data): the count, then the bytes as they are.
    pub fn bytes(&mut self, field: &'static str, v: &[u8]) -> Result<(), CdrWriteError> {
        self.count(field, v.len())?;
        self.buf.extend_from_slice(v);
        Ok(())
    }

    /// An `int8[]` sequence (occupancy cells): the count, then the bytes.
    pub fn i8_seq(&mut self, field: &'static str, v: &[i8]) -> Result<(), CdrWriteError> {
        self.count(field, v.len())?;
        self.buf.extend(v.iter().map(|&x| x as u8));
        Ok(())
    }

    /// A sequence of structs: the count, then each element.
    pub fn seq<T: CdrEncode>(&mut self, field: &'static str, v: &[T]) -> Result<(), CdrWriteError> {
        self.count(field, v.len())?;
        v.iter().try_for_each(|x| x.encode(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::ros2::cdr::CdrReader;
    use crate::log::ros2::msgs::wire::FieldReader;
    use proptest::prelude::*;

    #[test]
    fn alignment_counts_from_the_body_and_pads_with_zeros() {
        let mut w = CdrWriter::new();
        w.u8(7);
        w.u16(0x0102);
        w.f64(1.5);
        let b = w.into_bytes();
        // header | u8 at 0 | pad at 1 | u16 at 2..4 | pad 4..8 | f64 at 8..16
        assert_eq!(&b[..4], &CDR_LE_HEADER);
        assert_eq!(&b[4..12], &[7, 0, 2, 1, 0, 0, 0, 0]);
        assert_eq!(&b[12..], &1.5f64.to_le_bytes());
    }

    #[test]
    fn strings_carry_their_nul_and_refuse_inner_nuls() {
        let mut w = CdrWriter::new();
        w.string("s", "ab").unwrap();
        assert_eq!(&w.as_bytes()[4..], &[3, 0, 0, 0, b'a', b'b', 0]);
        w.string("empty", "").unwrap();
        assert_eq!(&w.as_bytes()[11..], &[0, 1, 0, 0, 0, 0]);
        let e = CdrWriter::new().string("frame_id", "a\0b").unwrap_err();
        assert_eq!(e, CdrWriteError::InteriorNul { field: "frame_id", at: 1 });
        assert!(e.to_string().contains("frame_id"), "{e}");
    }

    #[test]
    fn empty_double_array_adds_no_padding() {
        let mut w = CdrWriter::new();
        w.u8(1);
        w.f64_array(&[]);
        assert_eq!(w.as_bytes().len(), 5);
        w.f64_seq("d", &[]).unwrap();
        assert_eq!(w.as_bytes().len(), 12);
    }

    proptest! {
        /// Whatever mix of fields is written, the project's reader gets the same values
        /// back in the same order, bit for bit, and consumes every byte.
        #[test]
        fn reader_reads_back_what_the_writer_wrote(
            fields in proptest::collection::vec((0u8..5, any::<u64>(), "[a-z_/]{0,12}"), 0..24),
        ) {
            let mut w = CdrWriter::new();
            for (kind, bits, text) in &fields {
                match kind {
                    0 => w.i32(*bits as i32),
                    1 => w.u32(*bits as u32),
                    2 => w.f32(f32::from_bits(*bits as u32)),
                    3 => w.f64(f64::from_bits(*bits)),
                    _ => w.string("s", text).unwrap(),
                }
            }
            let payload = w.into_bytes();
            let mut r = CdrReader::new(&payload[4..]);
            for (kind, bits, text) in &fields {
                match kind {
                    0 => prop_assert_eq!(r.i32("i").unwrap(), *bits as i32),
                    1 => prop_assert_eq!(r.u32("u").unwrap(), *bits as u32),
                    2 => prop_assert_eq!(r.f32("f").unwrap().to_bits(), *bits as u32),
                    3 => prop_assert_eq!(r.f64("d").unwrap().to_bits(), *bits),
                    _ => prop_assert_eq!(&r.string("s").unwrap(), text),
                }
            }
            prop_assert_eq!(r.remaining(), 0);
        }

        /// Sequences round-trip through the reader, whatever misalignment a string in front
        /// leaves.
        #[test]
        fn sequences_round_trip(lead in "[a-z]{0,9}", v in proptest::collection::vec(any::<u32>(), 0..40)) {
            let mut w = CdrWriter::new();
            w.string("lead", &lead).unwrap();
            let floats: Vec<f32> = v.iter().map(|b| f32::from_bits(*b)).collect();
            w.f32_seq("r", &floats).unwrap();
            let doubles: Vec<f64> = v.iter().map(|b| f64::from(*b) * 0.5).collect();
            w.f64_seq("d", &doubles).unwrap();
            let payload = w.into_bytes();
            let mut r = CdrReader::new(&payload[4..]);
            prop_assert_eq!(r.string("lead").unwrap(), lead);
            let got = r.f32_seq("r").unwrap();
            prop_assert_eq!(got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), v);
            let n = r.sequence_len("d", 8).unwrap();
            let back: Vec<f64> = (0..n).map(|_| r.f64("d").unwrap()).collect();
            prop_assert_eq!(back, doubles);
            prop_assert_eq!(r.remaining(), 0);
        }
    }
}
