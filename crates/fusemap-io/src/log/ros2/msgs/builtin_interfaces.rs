//! `builtin_interfaces`: the time type every header carries, written from fusemap's
//! nanosecond stamps (each [`FieldReader`](super::wire::FieldReader) reads it as its
//! format's time primitive).

use crate::log::ros2::writer::cdr_write::{CdrWriteError, CdrWriter};
use crate::log::ros2::writer::definition::MsgDef;
use fusemap_core::time::Stamp;

/// `builtin_interfaces/Time`: whole seconds plus nanoseconds.
pub static TIME: MsgDef = MsgDef { name: "builtin_interfaces/Time", text: "int32 sec\nuint32 nanosec\n", deps: &[] };

/// `builtin_interfaces/Duration`: a signed span, whole seconds plus nanoseconds.
pub static DURATION: MsgDef =
    MsgDef { name: "builtin_interfaces/Duration", text: "int32 sec\nuint32 nanosec\n", deps: &[] };

/// Splits `stamp` into `(sec, nanosec)` with `0 <= nanosec < 1e9` (so a stamp before the
/// epoch has negative `sec` and positive `nanosec`, as `rclcpp::Time` does); the inverse
/// of [`Stamp::from_sec_nsec`].
pub fn split_stamp(field: &'static str, stamp: Stamp) -> Result<(i32, u32), CdrWriteError> {
    const NS: i64 = 1_000_000_000;
    let sec = i32::try_from(stamp.0.div_euclid(NS))
        .map_err(|_| CdrWriteError::StampOutOfRange { field, nanoseconds: stamp.0 })?;
    // rem_euclid of a positive divisor is in [0, 1e9), which fits a u32.
    let nanosec = stamp.0.rem_euclid(NS) as u32;
    Ok((sec, nanosec))
}

/// Writes `stamp` as a `builtin_interfaces/Time`.
pub fn write_time(w: &mut CdrWriter, field: &'static str, stamp: Stamp) -> Result<(), CdrWriteError> {
    let (sec, nanosec) = split_stamp(field, stamp)?;
    w.i32(sec);
    w.u32(nanosec);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn negative_stamps_keep_nanoseconds_positive() {
        assert_eq!(split_stamp("t", Stamp(-1)).unwrap(), (-1, 999_999_999));
        assert_eq!(split_stamp("t", Stamp(1_500_000_000)).unwrap(), (1, 500_000_000));
        let e = split_stamp("header.stamp", Stamp(i64::MAX)).unwrap_err();
        assert!(matches!(e, CdrWriteError::StampOutOfRange { field: "header.stamp", .. }));
        assert!(split_stamp("t", Stamp(i64::from(i32::MIN) * 1_000_000_000)).is_ok());
        assert!(split_stamp("t", Stamp(i64::from(i32::MIN) * 1_000_000_000 - 1)).is_err());
    }

    proptest! {
        #[test]
        fn split_inverts_from_sec_nsec(ns in (i64::from(i32::MIN) * 1_000_000_000)..(i64::from(i32::MAX) * 1_000_000_000)) {
            let (sec, nanosec) = split_stamp("t", Stamp(ns)).unwrap();
            prop_assert!(nanosec < 1_000_000_000);
            prop_assert_eq!(Stamp::from_sec_nsec(i64::from(sec), nanosec), Stamp(ns));
        }
    }
}
