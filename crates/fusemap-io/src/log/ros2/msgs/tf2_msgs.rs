//! `tf2_msgs`: batches of frame transforms (`/tf`, `/tf_static`).

use super::geometry_msgs::{TransformStamped, TRANSFORM_STAMPED};
use super::wire::{FieldReader, RosMsg};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

/// `tf2_msgs/TFMessage`.
pub static TF_MESSAGE: MsgDef = MsgDef {
    name: "tf2_msgs/TFMessage",
    text: "geometry_msgs/TransformStamped[] transforms\n",
    deps: &[&TRANSFORM_STAMPED],
};

/// `tf2_msgs/msg/TFMessage`: several transforms sent together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TfMessage {
    /// The transforms, each with its own stamp and frames.
    pub transforms: Vec<TransformStamped>,
}

/// The fewest bytes one serialised `TransformStamped` can take in either format: stamp
/// (8), two string lengths (8) and seven doubles (56; ROS 1 adds a 4-byte `seq`). Bounds
/// a corrupt count before allocating.
const MIN_TRANSFORM_STAMPED_LEN: usize = 8 + 8 + 56;

impl RosMsg for TfMessage {
    fn read<'a, R: FieldReader<'a>>(r: &mut R) -> Result<Self, R::Error> {
        Ok(Self { transforms: r.seq("transforms", MIN_TRANSFORM_STAMPED_LEN, TransformStamped::read)? })
    }
}

/// A `tf2_msgs/msg/TFMessage` body over borrowed transforms, for the writer.
pub(crate) struct TfMessageRef<'a>(pub &'a [TransformStamped]);

impl CdrEncode for TfMessageRef<'_> {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.seq("transforms", self.0)
    }
}
