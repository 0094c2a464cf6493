//! The ROS message types fusemap reads and writes, one module per ROS package, shared by
//! the ROS 1 bag reader and the ROS 2 reader and writer. Each struct mirrors its `.msg`
//! definition field for field, in declaration order (the order both wire formats use),
//! and each exists once: both readers decode it through [`RosMsg`] (ROS 1's packed
//! layout and ROS 2's CDR differ only below the field, in their [`FieldReader`]), and the
//! rosbag2 writer encodes it ([`CdrEncode`]) under the `.msg` text of its [`MsgDef`]
//! static, so a field can never be read one way and written another. The map messages
//! fusemap only writes (occupancy grids, paths, point clouds, markers) have no reader.
//! Stamps are fusemap's [`Stamp`](fusemap_core::time::Stamp) (`time` or
//! `builtin_interfaces/Time` on the wire).
//!
//! [`RosMsg`]: wire::RosMsg
//! [`FieldReader`]: wire::FieldReader
//! [`CdrEncode`]: super::writer::cdr_write::CdrEncode
//! [`MsgDef`]: super::writer::definition::MsgDef

pub mod builtin_interfaces;
pub mod geometry_msgs;
pub mod nav_msgs;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod tf2_msgs;
pub mod visualization_msgs;
pub mod wire;
