//! `std_msgs`: the header shared by stamped messages, and colours.

use super::builtin_interfaces::{write_time, TIME};
use super::wire::{FieldReader, RosMsg};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;
use fusemap_core::time::Stamp;

/// `std_msgs/Header`.
pub static HEADER: MsgDef =
    MsgDef { name: "std_msgs/Header", text: "builtin_interfaces/Time stamp\nstring frame_id\n", deps: &[&TIME] };

/// `std_msgs/msg/Header`: when the data was taken and in which coordinate frame.
/// (ROS 2 dropped the ROS 1 `seq` counter; a ROS 1 reader reads past it.)
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// Acquisition time of the data (`builtin_interfaces/Time` on the wire).
    pub stamp: Stamp,
    /// The frame the data is expressed in (`laser`, `odom`, …).
    pub frame_id: String,
}

impl Header {
    /// A header at `stamp` in `frame_id`.
    pub fn new(stamp: Stamp, frame_id: impl Into<String>) -> Self {
        Self { stamp, frame_id: frame_id.into() }
    }
}

impl RosMsg for Header {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        r.header_seq()?;
        let stamp = r.time("stamp")?;
        Ok(Self { stamp, frame_id: r.string("frame_id")? })
    }
}

impl CdrEncode for Header {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        write_time(w, "header.stamp", self.stamp)?;
        w.string("header.frame_id", &self.frame_id)
    }
}

/// `std_msgs/ColorRGBA`.
pub static COLOR_RGBA: MsgDef =
    MsgDef { name: "std_msgs/ColorRGBA", text: "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n", deps: &[] };

/// `std_msgs/msg/ColorRGBA`: a colour, each channel in [0, 1]. Written only (markers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ColorRgba {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity (0 is invisible).
    pub a: f32,
}

impl CdrEncode for ColorRgba {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        for c in [self.r, self.g, self.b, self.a] {
            w.f32(c);
        }
        Ok(())
    }
}
