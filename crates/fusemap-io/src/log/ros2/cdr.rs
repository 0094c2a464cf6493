//! Little-endian CDR, the way ROS 2 serialises messages on the wire and in bags.
//!
//! A payload starts with a 4-byte encapsulation header: two bytes naming the
//! representation (`0x00 0x01` is plain CDR, little-endian) and two option bytes that
//! readers ignore. The message follows, each primitive aligned to its own size (at most 8)
//! *counted from the first byte after the header*. Strings are a `u32` byte count that
//! includes a terminating NUL, then the bytes; sequences are a `u32` element count, then
//! the elements; fixed-size arrays have no count.
//!
//! [`CdrReader`] is a bounds-checked cursor over such a payload: every read checks the
//! remaining length first, so a truncated or corrupt payload gives a [`CdrError`] naming
//! the field and the byte offset, never a panic. It is ROS 2's [`FieldReader`]: the
//! message structs ([`RosMsg`]) read themselves through it, and [`decode_cdr`] checks
//! the header and decodes one.

use crate::log::ros2::msgs::wire::{FieldPath, FieldReader, RosMsg};
use fusemap_core::time::Stamp;
use std::fmt;

/// Length of the encapsulation header in front of every CDR payload.
pub const ENCAPSULATION_HEADER_LEN: usize = 4;

/// The encapsulation bytes fusemap reads: plain CDR, little-endian.
pub const CDR_LE: [u8; 2] = [0x00, 0x01];

/// Why a CDR payload could not be decoded. Offsets count from the first byte of the
/// payload, encapsulation header included, so they match a hex dump of the message.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// Fewer than 4 bytes: not even an encapsulation header.
    #[error("payload is {len} bytes, shorter than the 4-byte CDR encapsulation header")]
    NoHeader {
        /// Payload length.
        len: usize,
    },
    /// `0x00 0x00`: the sender wrote big-endian CDR.
    #[error("CDR encapsulation is big-endian (0x0000); fusemap reads little-endian CDR (0x0001)")]
    BigEndian,
    /// Any representation other than plain little-endian CDR.
    #[error(
        "CDR encapsulation is {} (0x{:02x}{:02x}); fusemap reads little-endian CDR (0x0001)",
        representation_name(*.bytes),
        .bytes[0],
        .bytes[1]
    )]
    UnsupportedEncapsulation {
        /// The two representation bytes as found.
        bytes: [u8; 2],
    },
    /// The payload ends before a field does.
    #[error("truncated: `{field}` at byte {offset} needs {needed} bytes, {available} left")]
    Truncated {
        /// Dotted path of the field (`header.frame_id`, `transforms[2].transform`).
        field: String,
        /// Byte offset where the field starts.
        offset: usize,
        /// Bytes the field needs (alignment padding included).
        needed: usize,
        /// Bytes left in the payload.
        available: usize,
    },
    /// A field holds a value its type does not allow.
    #[error("`{field}` at byte {offset}: {what}")]
    Invalid {
        /// Dotted path of the field.
        field: String,
        /// Byte offset where the field starts.
        offset: usize,
        /// What is wrong.
        what: String,
    },
}

/// A readable name for the representation identifiers of the DDS-XTypes specification.
fn representation_name(bytes: [u8; 2]) -> &'static str {
    match u16::from_be_bytes(bytes) {
        0x0000 => "big-endian CDR",
        0x0001 => "little-endian CDR",
        0x0002 => "big-endian parameter-list CDR",
        0x0003 => "little-endian parameter-list CDR",
        0x0006 => "big-endian XCDR2",
        0x0007 => "little-endian XCDR2",
        0x0008 => "big-endian delimited XCDR2",
        0x0009 => "little-endian delimited XCDR2",
        0x000a => "big-endian parameter-list XCDR2",
        0x000b => "little-endian parameter-list XCDR2",
        _ => "an unknown representation",
    }
}

/// Checks the encapsulation header and returns the message body after it.
pub fn check_encapsulation(payload: &[u8]) -> Result<&[u8], CdrError> {
    if payload.len() < ENCAPSULATION_HEADER_LEN {
        return Err(CdrError::NoHeader { len: payload.len() });
    }
    match [payload[0], payload[1]] {
        CDR_LE => Ok(&payload[ENCAPSULATION_HEADER_LEN..]),
        [0x00, 0x00] => Err(CdrError::BigEndian),
        bytes => Err(CdrError::UnsupportedEncapsulation { bytes }),
    }
}

/// Decodes a whole payload (encapsulation header included) as a `T`.
///
/// Bytes after the message are ignored: writers may pad the payload to a multiple of 4.
pub fn decode_cdr<T: RosMsg>(payload: &[u8]) -> Result<T, CdrError> {
    let body = check_encapsulation(payload)?;
    let mut r = CdrReader::new(body);
    T::read(&mut r)
}

/// A bounds-checked little-endian CDR cursor over a message body (the bytes after the
/// encapsulation header): the [`FieldReader`] of ROS 2. It remembers the path of nested
/// fields being read, so errors name `transforms[1].header.frame_id` rather than just
/// `frame_id`.
pub struct CdrReader<'a> {
    body: &'a [u8],
    pos: usize,
    path: FieldPath,
}

impl<'a> CdrReader<'a> {
    /// A cursor at the start of `body`, which must *not* include the encapsulation header
    /// (alignment counts from its first byte).
    pub fn new(body: &'a [u8]) -> Self {
        Self { body, pos: 0, path: FieldPath::default() }
    }

    /// Bytes not yet consumed.
    pub fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// The error for `field` at the current position.
    pub fn invalid(&self, field: &str, what: impl fmt::Display) -> CdrError {
        CdrError::Invalid {
            field: self.path.to(field),
            offset: ENCAPSULATION_HEADER_LEN + self.pos,
            what: what.to_string(),
        }
    }

    /// Skips padding up to a multiple of `align`, then takes `n` bytes.
    fn take(&mut self, field: &str, align: usize, n: usize) -> Result<&'a [u8], CdrError> {
        let pad = (align - self.pos % align) % align;
        let needed = pad.checked_add(n);
        match needed {
            Some(needed) if needed <= self.remaining() => {
                let start = self.pos + pad;
                self.pos = start + n;
                Ok(&self.body[start..start + n])
            }
            _ => Err(CdrError::Truncated {
                field: self.path.to(field),
                offset: ENCAPSULATION_HEADER_LEN + self.pos,
                needed: needed.unwrap_or(usize::MAX),
                available: self.remaining(),
            }),
        }
    }

    /// `N` bytes aligned to `N`.
    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N], CdrError> {
        let bytes = self.take(field, N, N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &str) -> Result<i32, CdrError> {
        self.array(field).map(i32::from_le_bytes)
    }

    /// A sequence length, checked against the bytes left for elements of at least
    /// `min_element_size` bytes each, so a corrupt count never allocates.
    pub fn sequence_len(&mut self, field: &str, min_element_size: usize) -> Result<usize, CdrError> {
        let at = self.pos;
        let n = u32::from_le_bytes(self.array(field)?) as usize;
        let fits = n.checked_mul(min_element_size.max(1)).is_some_and(|bytes| bytes <= self.remaining());
        if fits {
            Ok(n)
        } else {
            Err(CdrError::Truncated {
                field: self.path.to(field),
                offset: ENCAPSULATION_HEADER_LEN + at,
                needed: n.saturating_mul(min_element_size.max(1)),
                available: self.remaining(),
            })
        }
    }
}

impl<'a> FieldReader<'a> for CdrReader<'a> {
    type Error = CdrError;

    /// ROS 2's header has no `seq`.
    fn header_seq(&mut self) -> Result<(), CdrError> {
        Ok(())
    }

    /// A `builtin_interfaces/Time`: `int32 sec`, `uint32 nanosec`.
    fn time(&mut self, field: &'static str) -> Result<Stamp, CdrError> {
        self.field(field, |r| {
            let sec = r.i32("sec")?;
            let nanosec = r.u32("nanosec")?;
            Ok(Stamp::from_sec_nsec(i64::from(sec), nanosec))
        })
    }

    /// An `int8` (no alignment).
    fn i8(&mut self, field: &'static str) -> Result<i8, CdrError> {
        self.array(field).map(i8::from_le_bytes)
    }

    /// A `uint8` (no alignment).
    fn u8(&mut self, field: &'static str) -> Result<u8, CdrError> {
        self.array(field).map(u8::from_le_bytes)
    }

    /// A `uint16` (aligned to 2).
    fn u16(&mut self, field: &'static str) -> Result<u16, CdrError> {
        self.array(field).map(u16::from_le_bytes)
    }

    /// A `uint32` (aligned to 4).
    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        self.array(field).map(u32::from_le_bytes)
    }

    /// A `float32` (aligned to 4).
    fn f32(&mut self, field: &'static str) -> Result<f32, CdrError> {
        self.array(field).map(f32::from_le_bytes)
    }

    /// A `float64` (aligned to 8).
    fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        self.array(field).map(f64::from_le_bytes)
    }

    fn f64_array<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        if N > 0 {
            let bytes = self.take(field, 8, N * 8)?;
            for (o, b) in out.iter_mut().zip(bytes.as_chunks::<8>().0) {
                *o = f64::from_le_bytes(*b);
            }
        }
        Ok(out)
    }

    /// A `float32[]` sequence, bit for bit.
    fn f32_seq(&mut self, field: &'static str) -> Result<Vec<f32>, CdrError> {
        let n = self.sequence_len(field, 4)?;
        let mut out = self.room_for(field, n)?;
        let bytes = self.take(field, 4, n * 4)?;
        out.extend(bytes.as_chunks::<4>().0.iter().map(|b| f32::from_le_bytes(*b)));
        Ok(out)
    }

    /// A `float64[]` sequence (the count, then elements aligned to 8).
    fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, CdrError> {
        let n = self.sequence_len(field, 8)?;
        let mut out = self.room_for(field, n)?;
        if n > 0 {
            let bytes = self.take(field, 8, n * 8)?;
            out.extend(bytes.as_chunks::<8>().0.iter().map(|b| f64::from_le_bytes(*b)));
        }
        Ok(out)
    }

    fn u8_seq(&mut self, field: &'static str) -> Result<&'a [u8], CdrError> {
        let n = self.sequence_len(field, 1)?;
        self.take(field, 1, n)
    }

    /// A `string`: `u32` length including the NUL terminator, the bytes, the NUL.
    /// A length of 0 (written by some encoders for the empty string) is accepted.
    fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let n = self.sequence_len(field, 1)?;
        let at = self.pos;
        let bytes = self.take(field, 1, n)?;
        let text = match bytes.split_last() {
            None => &[][..],
            Some((0, text)) => text,
            Some(_) => {
                self.pos = at;
                return Err(self.invalid(field, format!("string of {n} bytes does not end in NUL")));
            }
        };
        match std::str::from_utf8(text) {
            Ok(s) => Ok(s.to_owned()),
            Err(e) => {
                self.pos = at;
                Err(self.invalid(field, format!("string is not UTF-8 ({e})")))
            }
        }
    }

    fn path(&mut self) -> &mut FieldPath {
        &mut self.path
    }

    fn count(&mut self, field: &'static str, min_element_size: usize) -> Result<usize, CdrError> {
        self.sequence_len(field, min_element_size)
    }

    fn room_for<T>(&self, field: &'static str, n: usize) -> Result<Vec<T>, CdrError> {
        crate::bounded::vec_with_capacity(n)
            .map_err(|e| self.invalid(field, format!("no memory for its {n} elements ({e})")))
    }

    fn position(&self) -> usize {
        self.pos
    }

    fn invalid_at(&self, field: &'static str, position: usize, what: impl fmt::Display) -> CdrError {
        CdrError::Invalid {
            field: self.path.to(field),
            offset: ENCAPSULATION_HEADER_LEN + position,
            what: what.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_checked() {
        let r: Result<&[u8], _> = check_encapsulation(&[0, 1, 0, 0, 7]);
        assert_eq!(r, Ok(&[7u8][..]));
        assert_eq!(check_encapsulation(&[0, 1, 0]), Err(CdrError::NoHeader { len: 3 }));
        let be = check_encapsulation(&[0, 0, 0, 0]).unwrap_err();
        assert_eq!(
            be.to_string(),
            "CDR encapsulation is big-endian (0x0000); fusemap reads little-endian CDR (0x0001)"
        );
        let x2 = check_encapsulation(&[0, 7, 0, 0]).unwrap_err();
        assert_eq!(
            x2.to_string(),
            "CDR encapsulation is little-endian XCDR2 (0x0007); fusemap reads little-endian CDR (0x0001)"
        );
        let odd = check_encapsulation(&[0x12, 0x34, 0, 0]).unwrap_err();
        assert!(odd.to_string().contains("(0x1234)"), "{odd}");
    }

    #[test]
    fn alignment_counts_from_the_body() {
        // u8-sized string "ab\0" (len 3) leaves the cursor at 7; the double starts at 8.
        let mut body = Vec::new();
        body.extend_from_slice(&3u32.to_le_bytes());
        body.extend_from_slice(b"ab\0");
        body.push(0xEE); // padding
        body.extend_from_slice(&1.5f64.to_le_bytes());
        let mut r = CdrReader::new(&body);
        assert_eq!(r.string("s").unwrap(), "ab");
        assert_eq!(r.position(), 7);
        assert_eq!(r.f64("d").unwrap(), 1.5);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn errors_name_the_path_and_offset() {
        let body = [2u8, 0, 0, 0, 5, 0, 0, 0];
        let mut r = CdrReader::new(&body);
        let e = r.seq("items", 1, |r| r.field("inner", |r| r.u32("value"))).unwrap_err();
        assert_eq!(
            e,
            CdrError::Truncated { field: "items[1].inner.value".into(), offset: 12, needed: 4, available: 0 }
        );
    }

    #[test]
    fn huge_counts_do_not_allocate() {
        let body = u32::MAX.to_le_bytes();
        let e = CdrReader::new(&body).f32_seq("ranges").unwrap_err();
        assert!(matches!(e, CdrError::Truncated { ref field, offset: 4, .. } if field == "ranges"));
        let e = CdrReader::new(&body).string("frame_id").unwrap_err();
        assert!(matches!(e, CdrError::Truncated { .. }));
    }

    #[test]
    fn strings_need_their_nul_and_utf8() {
        let mut r = CdrReader::new(&[0, 0, 0, 0]);
        assert_eq!(r.string("empty").unwrap(), "");
        let mut r = CdrReader::new(&[1, 0, 0, 0, 0]);
        assert_eq!(r.string("empty").unwrap(), "");
        let e = CdrReader::new(&[2, 0, 0, 0, b'a', b'b']).string("s").unwrap_err();
        assert!(e.to_string().contains("does not end in NUL"), "{e}");
        let e = CdrReader::new(&[2, 0, 0, 0, 0xff, 0]).string("s").unwrap_err();
        assert!(e.to_string().contains("not UTF-8"), "{e}");
    }
}
