//! `std_msgs/msg/Header`.

use super::builtin_interfaces::{write_time, TIME};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;
use fusemap_core::time::Stamp;

/// `std_msgs/Header`.
pub static HEADER: MsgDef =
    MsgDef { name: "std_msgs/Header", text: "builtin_interfaces/Time stamp\nstring frame_id\n", deps: &[&TIME] };

/// `std_msgs/msg/Header`: when the data was taken and in which frame (ROS 2 has no `seq`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// Acquisition time of the data.
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

impl CdrEncode for Header {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        write_time(w, "header.stamp", self.stamp)?;
        w.string("header.frame_id", &self.frame_id)
    }
}
