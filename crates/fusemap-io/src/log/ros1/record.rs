//! The record layer of the ROS bag format v2.0.
//!
//! A bag is the line `#ROSBAG V2.0\n` followed by records. Each record is a header (a
//! `u32` length, then fields, each a `u32` length and `name=value` with a binary value)
//! and a data block (a `u32` length and bytes). The header's `op` field says what the
//! record is. Chunks hold connection and message-data records, optionally compressed.

use super::cursor::{Cursor, Malformed};
use crate::bounded::read_to_end_bounded;
use fusemap_core::time::Stamp;

/// The first line of every bag this reader accepts.
pub(super) const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// `op` of a message data record.
pub(super) const OP_MESSAGE_DATA: u8 = 0x02;
/// `op` of the bag header record.
pub(super) const OP_BAG_HEADER: u8 = 0x03;
/// `op` of an index data record.
pub(super) const OP_INDEX_DATA: u8 = 0x04;
/// `op` of a chunk record.
pub(super) const OP_CHUNK: u8 = 0x05;
/// `op` of a chunk info record.
pub(super) const OP_CHUNK_INFO: u8 = 0x06;
/// `op` of a connection record.
pub(super) const OP_CONNECTION: u8 = 0x07;

/// The fields of a record header this reader uses, whatever the record type; each is
/// checked for its size as it is parsed. Unknown fields are ignored, as the format asks.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct RecordHeader<'a> {
    /// Record type.
    pub op: Option<u8>,
    /// Connection id (connection, message data and index data records).
    pub conn: Option<u32>,
    /// Receive time (message data records).
    pub time: Option<Stamp>,
    /// Topic (connection records).
    pub topic: Option<&'a [u8]>,
    /// `none`, `bz2` or `lz4` (chunk records).
    pub compression: Option<&'a [u8]>,
    /// Uncompressed size of a chunk's data.
    pub size: Option<u32>,
    /// Offset of the index section (bag header).
    pub index_pos: Option<u64>,
    /// Number of chunks (bag header).
    pub chunk_count: Option<u32>,
}

/// Calls `f(name, value)` for each `name=value` field of a record header or connection
/// data block.
pub(super) fn for_each_field<'a>(
    bytes: &'a [u8],
    mut f: impl FnMut(&'a [u8], &'a [u8]) -> Result<(), Malformed>,
) -> Result<(), Malformed> {
    let mut c = Cursor::new(bytes);
    while !c.is_empty() {
        let at = c.position();
        let field = c.prefixed("header field")?;
        let Some(eq) = field.iter().position(|&b| b == b'=') else {
            return Err(Malformed(format!(
                "header field at offset {at} (`{}`) has no `=`",
                String::from_utf8_lossy(field.get(..40).unwrap_or(field))
            )));
        };
        let (name, value) = field.split_at(eq);
        f(name, value.get(1..).unwrap_or_default())?;
    }
    Ok(())
}

/// A fixed-size field value.
fn fixed<const N: usize>(name: &[u8], value: &[u8]) -> Result<[u8; N], Malformed> {
    <[u8; N]>::try_from(value).map_err(|_| {
        Malformed(format!("header field `{}` has {} bytes, not {N}", String::from_utf8_lossy(name), value.len()))
    })
}

/// Parses a record header.
pub(super) fn parse_header(bytes: &[u8]) -> Result<RecordHeader<'_>, Malformed> {
    let mut h = RecordHeader::default();
    for_each_field(bytes, |name, value| {
        match name {
            b"op" => h.op = Some(u8::from_le_bytes(fixed(name, value)?)),
            b"conn" => h.conn = Some(u32::from_le_bytes(fixed(name, value)?)),
            b"time" => {
                let [s0, s1, s2, s3, n0, n1, n2, n3] = fixed::<8>(name, value)?;
                h.time = Some(Stamp::from_sec_nsec(
                    i64::from(u32::from_le_bytes([s0, s1, s2, s3])),
                    u32::from_le_bytes([n0, n1, n2, n3]),
                ));
            }
            b"topic" => h.topic = Some(value),
            b"compression" => h.compression = Some(value),
            b"size" => h.size = Some(u32::from_le_bytes(fixed(name, value)?)),
            b"index_pos" => h.index_pos = Some(u64::from_le_bytes(fixed(name, value)?)),
            b"chunk_count" => h.chunk_count = Some(u32::from_le_bytes(fixed(name, value)?)),
            _ => {}
        }
        Ok(())
    })?;
    Ok(h)
}

/// The `type` and `md5sum` of a connection record's data block.
pub(super) fn parse_connection_data(bytes: &[u8]) -> Result<(&[u8], &[u8]), Malformed> {
    let (mut ty, mut md5) = (None, None);
    for_each_field(bytes, |name, value| {
        match name {
            b"type" => ty = Some(value),
            b"md5sum" => md5 = Some(value),
            _ => {}
        }
        Ok(())
    })?;
    match (ty, md5) {
        (Some(t), Some(m)) => Ok((t, m)),
        (None, _) => Err(Malformed("connection record has no `type` field".into())),
        (_, None) => Err(Malformed("connection record has no `md5sum` field".into())),
    }
}

/// One record inside a chunk's (uncompressed) data.
pub(super) struct InnerRecord<'a> {
    /// The raw header.
    pub header: &'a [u8],
    /// The data block.
    pub data: &'a [u8],
}

/// Reads the record at `c`'s position inside a chunk.
pub(super) fn read_inner<'a>(c: &mut Cursor<'a>) -> Result<InnerRecord<'a>, Malformed> {
    let header = c.prefixed("record header")?;
    let data = c.prefixed("record data")?;
    Ok(InnerRecord { header, data })
}

/// Decompresses a chunk's data into `out` (cleared first), checking that it comes to
/// exactly `size` bytes. `compression` is known to be `bz2` or `lz4`. The buffer grows
/// with what the stream yields, by fallible reservations, never past `size + 1` bytes
/// ([`read_to_end_bounded`]): a lying header costs no memory up front, and a chunk that
/// inflates past its stated size is refused there.
pub(super) fn decompress(compression: &[u8], input: &[u8], size: u32, out: &mut Vec<u8>) -> Result<(), Malformed> {
    let limit = u64::from(size);
    let (name, result) = match compression {
        b"bz2" => ("bz2", read_to_end_bounded(bzip2::read::BzDecoder::new(input), limit, out)),
        b"lz4" => ("lz4", read_to_end_bounded(lz4_flex::frame::FrameDecoder::new(input), limit, out)),
        other => return Err(unsupported_compression(other)),
    };
    if let Err(e) = result {
        return Err(Malformed(format!("{name} decompression of the chunk failed: {e}")));
    }
    check_size(out.len(), size)
}

/// The error for a chunk whose data comes to `len` bytes where its header said `size`.
pub(super) fn check_size(len: usize, size: u32) -> Result<(), Malformed> {
    if len == size as usize {
        Ok(())
    } else if len > size as usize {
        Err(Malformed(format!("chunk header says {size} uncompressed bytes but its data holds more")))
    } else {
        Err(Malformed(format!("chunk header says {size} uncompressed bytes but its data holds {len}")))
    }
}

/// The error for a compression this reader does not know.
pub(super) fn unsupported_compression(name: &[u8]) -> Malformed {
    Malformed(format!(
        "chunk compression `{}` is not supported (only none, bz2 and lz4)",
        String::from_utf8_lossy(name)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(out: &mut Vec<u8>, name: &str, value: &[u8]) {
        out.extend((name.len() as u32 + 1 + value.len() as u32).to_le_bytes());
        out.extend(name.as_bytes());
        out.push(b'=');
        out.extend(value);
    }

    #[test]
    fn header_fields_are_typed_and_size_checked() {
        let mut h = Vec::new();
        field(&mut h, "op", &[2]);
        field(&mut h, "conn", &7u32.to_le_bytes());
        field(&mut h, "time", &[1, 0, 0, 0, 2, 0, 0, 0]);
        field(&mut h, "unknown", b"a=b");
        let parsed = parse_header(&h).unwrap();
        assert_eq!(parsed.op, Some(OP_MESSAGE_DATA));
        assert_eq!(parsed.conn, Some(7));
        assert_eq!(parsed.time, Some(Stamp(1_000_000_002)));

        let mut bad = Vec::new();
        field(&mut bad, "op", &[2, 0]);
        assert_eq!(parse_header(&bad).unwrap_err().0, "header field `op` has 2 bytes, not 1");
        let mut no_eq = Vec::new();
        no_eq.extend(2u32.to_le_bytes());
        no_eq.extend(b"op");
        assert!(parse_header(&no_eq).unwrap_err().0.contains("has no `=`"));
        assert!(parse_header(&[5, 0, 0, 0, b'o']).is_err());
    }

    #[test]
    fn unknown_compression_is_named() {
        let mut out = Vec::new();
        assert_eq!(
            decompress(b"zstd", &[], 0, &mut out).unwrap_err().0,
            "chunk compression `zstd` is not supported (only none, bz2 and lz4)"
        );
    }
}
