//! `tf2_msgs`: batches of frame transforms (`/tf`, `/tf_static`).

use super::geometry_msgs::TransformStamped;
use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};

/// `tf2_msgs/msg/TFMessage`: several transforms sent together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TfMessage {
    /// The transforms, each with its own stamp and frames.
    pub transforms: Vec<TransformStamped>,
}

/// The fewest bytes one serialised `TransformStamped` can take: stamp (8), two string
/// lengths (8) and seven doubles (56). Bounds a corrupt count before allocating.
const MIN_TRANSFORM_STAMPED_LEN: usize = 8 + 8 + 56;

impl CdrDecode for TfMessage {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { transforms: r.seq("transforms", MIN_TRANSFORM_STAMPED_LEN, TransformStamped::decode)? })
    }
}
