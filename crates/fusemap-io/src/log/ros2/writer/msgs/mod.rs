//! The messages the rosbag2 writer can write, as plain structs: one module per ROS
//! package, each struct holding every field of its `.msg` (in declaration order, which is
//! the CDR order), stamps as fusemap's [`Stamp`](fusemap_core::time::Stamp).
//!
//! Each struct implements [`CdrEncode`](super::cdr_write::CdrEncode), and each type has
//! a [`MsgDef`](super::definition::MsgDef) static with its `.msg` text for the schema.
//! Vectors and quaternions are arrays (`[x, y, z]`, `[x, y, z, w]`) as in
//! [`crate::log`]'s decoded types.

pub mod builtin_interfaces;
pub mod geometry_msgs;
pub mod nav_msgs;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod tf2_msgs;
