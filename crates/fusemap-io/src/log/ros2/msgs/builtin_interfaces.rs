//! `builtin_interfaces`: the time type every header carries.

use crate::log::ros2::cdr::{CdrDecode, CdrError, CdrReader};
use fusemap_core::time::Stamp;

/// `builtin_interfaces/msg/Time`: a point in time as whole seconds plus nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Time {
    /// Whole seconds (since the Unix epoch for wall-clock stamps).
    pub sec: i32,
    /// Nanoseconds to add to `sec`; a well-formed stamp keeps it below 1e9.
    pub nanosec: u32,
}

impl Time {
    /// fusemap's stamp: `sec * 1e9 + nanosec` nanoseconds, exactly.
    pub fn to_stamp(self) -> Stamp {
        Stamp::from_sec_nsec(i64::from(self.sec), self.nanosec)
    }
}

impl CdrDecode for Time {
    fn decode(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self { sec: r.i32("sec")?, nanosec: r.u32("nanosec")? })
    }
}
