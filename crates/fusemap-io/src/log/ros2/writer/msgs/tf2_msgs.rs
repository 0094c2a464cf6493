//! `tf2_msgs/msg/TFMessage`: a batch of transforms (`/tf`, `/tf_static`).

use super::geometry_msgs::{TransformStamped, TRANSFORM_STAMPED};
use crate::log::ros2::writer::cdr_write::{CdrEncode, CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;

/// `tf2_msgs/TFMessage`.
pub static TF_MESSAGE: MsgDef = MsgDef {
    name: "tf2_msgs/TFMessage",
    text: "geometry_msgs/TransformStamped[] transforms\n",
    deps: &[&TRANSFORM_STAMPED],
};

/// `tf2_msgs/msg/TFMessage`'s body.
pub(crate) struct TfMessageRef<'a>(pub &'a [TransformStamped]);

impl CdrEncode for TfMessageRef<'_> {
    fn encode(&self, w: &mut CdrWriter) -> Result<(), CdrWriteError> {
        w.seq("transforms", self.0)
    }
}
