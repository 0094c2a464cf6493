//! The ROS 2 message types fusemap reads, one module per ROS package, each struct
//! mirroring its `.msg` definition field for field (in declaration order, which is the
//! CDR order) so that decoding is a straight walk over the fields.

pub mod builtin_interfaces;
pub mod geometry_msgs;
pub mod nav_msgs;
pub mod sensor_msgs;
pub mod std_msgs;
pub mod tf2_msgs;
