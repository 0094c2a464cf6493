//! `std_msgs`: the header shared by stamped messages.

use super::builtin_interfaces::Time;
use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};

/// `std_msgs/msg/Header`: when the data was taken and in which coordinate frame.
/// (ROS 2 dropped the ROS 1 `seq` counter.)
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// Acquisition time of the data.
    pub stamp: Time,
    /// The frame the data is expressed in (`laser`, `odom`, …).
    pub frame_id: String,
}

impl CdrDecode for Header {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { stamp: r.decode_field("stamp")?, frame_id: r.string("frame_id")? })
    }
}
