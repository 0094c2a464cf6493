//! Reading a message's fields in declaration order, whatever the wire format.
//!
//! ROS 1 and ROS 2 serialise the same `.msg` definitions in the same field order; they
//! differ only below the field: ROS 1 packs little-endian values with no padding, gives
//! `std_msgs/Header` a `uint32 seq`, writes `time` as two `u32`s and strings without a
//! terminator, while CDR aligns each value to its size, drops `seq`, writes
//! `builtin_interfaces/Time` as `i32` + `u32` and ends strings with a NUL. So each message
//! struct says once, in [`RosMsg::read`], which fields it has in which order, and each
//! format supplies a [`FieldReader`] (the ROS 1 bag reader's and
//! [`CdrReader`](crate::log::ros2::cdr::CdrReader)) that knows how one field is laid out.
//! Both readers bound every length by the bytes left before allocating and name the
//! field's path in their errors (`transforms[1].header.frame_id`).

use fusemap_core::time::Stamp;
use std::fmt;

/// A message type made of fields a [`FieldReader`] can read.
pub trait RosMsg: Sized {
    /// Reads the fields in declaration order.
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error>;
}

/// A cursor over one serialised message that reads the primitive field types of the ROS
/// interface definition language.
pub trait FieldReader<'a>: Sized {
    /// What a malformed field gives.
    type Error;

    /// The `uint32 seq` that opens a ROS 1 `std_msgs/Header`, read past; ROS 2 has none.
    fn header_seq(&mut self) -> Result<(), Self::Error>;
    /// A point in time: ROS 1 `time` or ROS 2 `builtin_interfaces/Time`.
    fn time(&mut self, field: &'static str) -> Result<Stamp, Self::Error>;
    /// An `int8`.
    fn i8(&mut self, field: &'static str) -> Result<i8, Self::Error>;
    /// A `uint8` (also a `bool`).
    fn u8(&mut self, field: &'static str) -> Result<u8, Self::Error>;
    /// A `uint16`.
    fn u16(&mut self, field: &'static str) -> Result<u16, Self::Error>;
    /// A `uint32`.
    fn u32(&mut self, field: &'static str) -> Result<u32, Self::Error>;
    /// A `float32`.
    fn f32(&mut self, field: &'static str) -> Result<f32, Self::Error>;
    /// A `float64`.
    fn f64(&mut self, field: &'static str) -> Result<f64, Self::Error>;
    /// A fixed-size `float64[N]` (no length prefix).
    fn f64_array<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], Self::Error>;
    /// A variable-length `float32[]`.
    fn f32_seq(&mut self, field: &'static str) -> Result<Vec<f32>, Self::Error>;
    /// A variable-length `float64[]`.
    fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, Self::Error>;
    /// A variable-length `uint8[]`, borrowed from the payload (an image's pixels are
    /// copied only when wanted).
    fn u8_seq(&mut self, field: &'static str) -> Result<&'a [u8], Self::Error>;
    /// A `string`.
    fn string(&mut self, field: &'static str) -> Result<String, Self::Error>;
    /// The path of nested fields being read, for errors.
    fn path(&mut self) -> &mut FieldPath;
    /// The element count of a variable-length array `field`, bounded by the bytes left
    /// for elements of at least `min_element_size` bytes.
    fn count(&mut self, field: &'static str, min_element_size: usize) -> Result<usize, Self::Error>;
    /// An empty `Vec` with room for the `n` elements of `field`, reserved fallibly (an
    /// allocator that refuses is an error, not an abort).
    fn room_for<T>(&self, field: &'static str, n: usize) -> Result<Vec<T>, Self::Error>;

    /// A nested struct field: errors inside name it as `name.inner`.
    fn field<T>(
        &mut self,
        name: &'static str,
        read: impl FnOnce(&mut Self) -> Result<T, Self::Error>,
    ) -> Result<T, Self::Error> {
        self.path().push_field(name);
        let value = read(self)?;
        self.path().pop();
        Ok(value)
    }

    /// A variable-length array of structs, whose errors name `field[i]`; the count is
    /// bounded by the bytes left for elements of at least `min_element_size` bytes.
    fn seq<T>(
        &mut self,
        field: &'static str,
        min_element_size: usize,
        mut read: impl FnMut(&mut Self) -> Result<T, Self::Error>,
    ) -> Result<Vec<T>, Self::Error> {
        let n = self.count(field, min_element_size)?;
        let mut out = self.room_for(field, n)?;
        self.path().push_field(field);
        for i in 0..n {
            self.path().push_index(i);
            out.push(read(self)?);
            self.path().pop();
        }
        self.path().pop();
        Ok(out)
    }

    /// Bytes consumed so far.
    fn position(&self) -> usize;
    /// The error for `field`, which started at `position`, holding a value its type
    /// allows but the message does not (an image whose sizes do not fit its data).
    fn invalid_at(&self, field: &'static str, position: usize, what: impl fmt::Display) -> Self::Error;

    /// A nested message field.
    fn message<T: RosMsg>(&mut self, name: &'static str) -> Result<T, Self::Error> {
        self.field(name, T::read)
    }
}

/// One step of a field path: a field name or an array index.
#[derive(Clone, Copy, Debug)]
enum PathPart {
    Field(&'static str),
    Index(usize),
}

/// The path of nested fields a reader is inside, so an error names
/// `transforms[1].header.frame_id` rather than just `frame_id`. Readers keep one; the
/// message structs never see it.
#[derive(Clone, Debug, Default)]
pub struct FieldPath(Vec<PathPart>);

impl FieldPath {
    /// Enters the struct field `name`.
    pub fn push_field(&mut self, name: &'static str) {
        self.0.push(PathPart::Field(name));
    }

    /// Enters element `i` of the array just entered.
    pub fn push_index(&mut self, i: usize) {
        self.0.push(PathPart::Index(i));
    }

    /// Leaves the innermost field or element.
    pub fn pop(&mut self) {
        self.0.pop();
    }

    /// True at the message's top level.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The dotted path to `leaf` (which may be empty) from the top of the message.
    pub fn to(&self, leaf: &str) -> String {
        let mut s = String::new();
        for part in &self.0 {
            match part {
                PathPart::Field(f) => {
                    if !s.is_empty() {
                        s.push('.');
                    }
                    s.push_str(f);
                }
                PathPart::Index(i) => {
                    s.push('[');
                    s.push_str(&i.to_string());
                    s.push(']');
                }
            }
        }
        if !leaf.is_empty() {
            if !s.is_empty() {
                s.push('.');
            }
            s.push_str(leaf);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_join_fields_with_dots_and_indices_with_brackets() {
        let mut p = FieldPath::default();
        assert_eq!(p.to("x"), "x");
        p.push_field("transforms");
        p.push_index(2);
        p.push_field("header");
        assert_eq!(p.to("frame_id"), "transforms[2].header.frame_id");
        assert_eq!(p.to(""), "transforms[2].header");
        p.pop();
        p.pop();
        assert_eq!(p.to("x"), "transforms.x");
    }
}
