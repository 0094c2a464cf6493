//! ROS 1 message payloads fusemap uses, read into the shared message structs
//! ([`msgs`](crate::log::ros2::msgs)) and from them into its own types.
//!
//! ROS 1 serialisation is the fields in order, little-endian, with no padding; strings
//! and variable-length arrays start with a `u32` length; `time` is `u32` seconds and
//! `u32` nanoseconds; `std_msgs/Header` is `u32 seq`, `time stamp`, `string frame_id`.
//! [`Fields`] is that layout's [`FieldReader`]; the field order is each struct's own. A
//! layout is only valid for the definition it was written with, so each type carries the
//! MD5 sum ROS computes from its standard definition and connections whose sum differs
//! are refused.

use super::cursor::{Cursor, Malformed};
use crate::log::ros2::msgs::wire::{FieldPath, FieldReader};
use crate::log::ros2::{KnownType, On};
use crate::log::LogMessage;
use fusemap_core::time::Stamp;
use std::fmt;

/// The message type fusemap decodes for a connection's `type`, with the MD5 sum of the
/// standard definition (ROS's sum over the definition text with nested types replaced by
/// their sums; the values `rosmsg md5` prints). `tf/tfMessage` is the old name of
/// `tf2_msgs/TFMessage`'s definition.
pub(super) fn known_type(ty: &[u8]) -> Option<(KnownType, &'static str)> {
    Some(match ty {
        b"sensor_msgs/LaserScan" => (KnownType::LaserScan, "90c7ef2dc6895d81024acba2ac42f369"),
        b"nav_msgs/Odometry" => (KnownType::Odometry, "cd5e73d190d741a2f92e81eda573aca7"),
        b"tf2_msgs/TFMessage" | b"tf/tfMessage" => (KnownType::TfMessage, "94810edda583a504dfda3829e70d7eec"),
        b"sensor_msgs/Imu" => (KnownType::Imu, "6a62c6daae103f4ff57a132d6f95cec2"),
        b"sensor_msgs/NavSatFix" => (KnownType::NavSatFix, "2d3a8cd499b9b4a0249fb98fd05cfa48"),
        b"geometry_msgs/PoseWithCovarianceStamped" => {
            (KnownType::PoseWithCovarianceStamped, "953b798c0f514ff060a53a3498ce6246")
        }
        b"sensor_msgs/Image" => (KnownType::Image, "060021388200f6f0f447d0fcd9c64743"),
        b"sensor_msgs/CameraInfo" => (KnownType::CameraInfo, "c9a58c1b0b154e0e6da7578cb991d214"),
        _ => return None,
    })
}

/// Decodes one message payload of `kind` published on `topic` and logged at `receive`;
/// an image's pixels are copied only with `pixels` (else it is an
/// [`ImageHeader`](crate::log::ImageHeader)). Unlike CDR, a ROS 1 payload has no padding,
/// so bytes left after the last field mean the layout is not the standard one.
pub(super) fn decode(
    kind: KnownType,
    topic: &str,
    receive: Stamp,
    payload: &[u8],
    pixels: bool,
) -> Result<LogMessage, Malformed> {
    let name = kind.name().rsplit('/').next().unwrap_or_default();
    let mut fields = Fields { c: Cursor::new(payload), path: FieldPath::default() };
    let on = On { topic, receive_stamp: Some(receive) };
    let message = on.read(kind, &mut fields, pixels).map_err(|e| e.context(name))?;
    if !fields.c.is_empty() {
        return Err(Malformed(format!(
            "{name}: {} bytes left over after the message's last field (the layout differs \
             from the standard definition)",
            fields.c.remaining()
        )));
    }
    Ok(message)
}

/// ROS 1's [`FieldReader`]: a [`Cursor`] and the path of the fields it is inside.
struct Fields<'a> {
    c: Cursor<'a>,
    path: FieldPath,
}

impl Fields<'_> {
    /// `e`, about a field inside the current path, named by its full path. Errors are
    /// only rare, so the path is spelt out only for them.
    fn at(&self, e: Malformed) -> Malformed {
        if self.path.is_empty() {
            e
        } else {
            Malformed(format!("{}.{}", self.path.to(""), e.0))
        }
    }
}

impl<'a> FieldReader<'a> for Fields<'a> {
    type Error = Malformed;

    fn header_seq(&mut self) -> Result<(), Malformed> {
        self.c.u32("seq").map(drop).map_err(|e| self.at(e))
    }

    fn time(&mut self, field: &'static str) -> Result<Stamp, Malformed> {
        self.c.time(field).map_err(|e| self.at(e))
    }

    fn i8(&mut self, field: &'static str) -> Result<i8, Malformed> {
        self.c.array::<1>(field).map(i8::from_le_bytes).map_err(|e| self.at(e))
    }

    fn u8(&mut self, field: &'static str) -> Result<u8, Malformed> {
        self.c.array::<1>(field).map(u8::from_le_bytes).map_err(|e| self.at(e))
    }

    fn u16(&mut self, field: &'static str) -> Result<u16, Malformed> {
        self.c.array::<2>(field).map(u16::from_le_bytes).map_err(|e| self.at(e))
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, Malformed> {
        self.c.u32(field).map_err(|e| self.at(e))
    }

    fn f32(&mut self, field: &'static str) -> Result<f32, Malformed> {
        self.c.f32(field).map_err(|e| self.at(e))
    }

    fn f64(&mut self, field: &'static str) -> Result<f64, Malformed> {
        self.c.f64s::<1>(field).map(|[v]| v).map_err(|e| self.at(e))
    }

    fn f64_array<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], Malformed> {
        self.c.f64s::<N>(field).map_err(|e| self.at(e))
    }

    fn f32_seq(&mut self, field: &'static str) -> Result<Vec<f32>, Malformed> {
        self.c.f32_vec(field).map_err(|e| self.at(e))
    }

    fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, Malformed> {
        self.c.f64_vec(field).map_err(|e| self.at(e))
    }

    fn u8_seq(&mut self, field: &'static str) -> Result<&'a [u8], Malformed> {
        self.c.prefixed(field).map_err(|e| self.at(e))
    }

    fn string(&mut self, field: &'static str) -> Result<String, Malformed> {
        self.c.string(field).map_err(|e| self.at(e))
    }

    fn path(&mut self) -> &mut FieldPath {
        &mut self.path
    }

    fn count(&mut self, field: &'static str, min_element_size: usize) -> Result<usize, Malformed> {
        self.c.array_len(min_element_size, field).map_err(|e| self.at(e))
    }

    fn room_for<T>(&self, field: &'static str, n: usize) -> Result<Vec<T>, Malformed> {
        crate::bounded::vec_with_capacity(n)
            .map_err(|e| self.at(Malformed(format!("{field}: no memory for its {n} elements ({e})"))))
    }

    fn position(&self) -> usize {
        self.c.position()
    }

    fn invalid_at(&self, field: &'static str, _position: usize, what: impl fmt::Display) -> Malformed {
        Malformed(format!("{}: {what}", self.path.to(field)))
    }
}
