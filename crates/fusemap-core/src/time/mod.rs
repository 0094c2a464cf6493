//! Time: stamps, the pose buffer that answers "where was the robot at t?", and the
//! synchronisation modes of the design document's §4.1.

mod glitch;
mod pose_buffer;
mod stamp;
mod timing;
mod track;

pub use glitch::{plausible_samples, MotionLimits};
pub use pose_buffer::{NoPose, PoseBuffer, PushOutcome, SyncMode};
pub use stamp::Stamp;
pub use timing::{DelayStats, StreamTiming, TimingLimits};
pub use track::{Covariance3, InFrame, PoseTrack};
