//! The ROS 2 message types fusemap reads and writes, one module per ROS package. Each
//! struct mirrors its `.msg` definition field for field (in declaration order, which is
//! the CDR order), and each exists once: the reader decodes it ([`CdrDecode`]), the
//! rosbag2 writer encodes it ([`CdrEncode`]) under the `.msg` text of its [`MsgDef`]
//! static, so a field can never be read one way and written another. Stamps are fusemap's
//! [`Stamp`](fusemap_core::time::Stamp) (`builtin_interfaces/Time` on the wire).
//!
//! [`CdrDecode`]: super::cdr::CdrDecode
//! [`CdrEncode`]: super::writer::cdr_write::CdrEncode
//! [`MsgDef`]: super::writer::definition::MsgDef

pub mod builtin_interfaces;
pub mod geometry_msgs;
pub mod nav_msgs;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod tf2_msgs;
