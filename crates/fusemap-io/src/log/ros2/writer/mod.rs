//! Writing rosbag2 bags: a directory with `metadata.yaml` and one MCAP storage file,
//! which `ros2 bag` (Humble and later, `mcap` storage plugin), the python `rosbags`
//! library, Foxglove and fusemap's own [reader](super::Ros2Reader) read.
//!
//! - [`Rosbag2Writer`] streams [`OutMessage`]s (laser scans, odometry, IMU, GNSS fixes,
//!   pose estimates, transforms, camera images and calibration) into the bag and moves the
//!   directory into place at [`finish`](Rosbag2Writer::finish), all at once.
//! - [`cdr_write`] serialises them as little-endian CDR, the mirror of
//!   [`super::cdr`]; the message structs are the reader's own ([`super::msgs`]), one
//!   module per ROS package, so what is written is what is read.
//! - [`definition`] gives each type's full `.msg` text for the `ros2msg` MCAP schema;
//!   [`metadata`] writes `metadata.yaml` and the QoS profiles players use (static
//!   transforms latched).
//!
//! ```no_run
//! use fusemap_core::time::Stamp;
//! use fusemap_io::log::ros2::msgs::geometry_msgs::{Transform, TransformStamped};
//! use fusemap_io::log::ros2::msgs::std_msgs::Header;
//! use fusemap_io::log::ros2::writer::{OutMessage, Rosbag2Writer};
//!
//! # fn main() -> fusemap_io::Result<()> {
//! let mut bag = Rosbag2Writer::create("out/run1".as_ref())?;
//! let mount = TransformStamped {
//!     header: Header::new(Stamp(0), "base_link"),
//!     child_frame_id: "laser".into(),
//!     transform: Transform { translation: [0.2, 0.0, 0.1].into(), rotation: Default::default() },
//! };
//! bag.write(Stamp(0), "/tf_static", &OutMessage::Tf { is_static: true, transforms: vec![mount] })?;
//! let written = bag.finish()?; // out/run1/metadata.yaml and out/run1/run1_0.mcap appear now
//! println!("{} messages", written.message_count);
//! # Ok(())
//! # }
//! ```

mod bag;
pub mod cdr_write;
pub mod definition;
mod message;
pub mod metadata;
mod staging;

pub use bag::{check_topic_name, ChunkCompression, Rosbag2Writer, Rosbag2WriterOptions, WrittenBag};
pub use message::OutMessage;
pub use metadata::{QosProfile, TopicInfo};

#[cfg(test)]
mod tests;
