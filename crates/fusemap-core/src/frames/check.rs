//! Checks every transform passes before it touches the tree: frame names, and a
//! translation and quaternion that describe a rigid transform.

use super::FrameError;
use crate::geometry::Pose3;

/// The frame name without one leading `/`: tf (ROS 1) wrote `/base_link`, tf2 writes
/// `base_link`, and tf2's `BufferCore` strips the slash so both name one frame.
/// An empty name is refused.
pub(super) fn frame_name(name: &str) -> Result<&str, FrameError> {
    let clean = name.strip_prefix('/').unwrap_or(name);
    if clean.is_empty() {
        return Err(FrameError::InvalidName { name: name.to_owned() });
    }
    Ok(clean)
}

/// The transform with its quaternion normalised, if it is one: every component finite,
/// the quaternion non-zero and its squared norm within `tolerance` of 1 (tf2's
/// `BufferCore::setTransform` applies the same test, with tolerance 0.01, before storing).
/// A quaternion that far from unit length is not a rotation with rounding errors but
/// a wrong one, and normalising it would hide that.
pub(super) fn rigid_transform(parent: &str, child: &str, pose: Pose3, tolerance: f64) -> Result<Pose3, FrameError> {
    let names = || (parent.to_owned(), child.to_owned());
    if !pose.translation.iter().chain(pose.rotation.iter()).all(|v| v.is_finite()) {
        let (parent, child) = names();
        return Err(FrameError::NotFinite { parent, child });
    }
    let norm_squared: f64 = pose.rotation.iter().map(|v| v * v).sum();
    if norm_squared == 0.0 {
        let (parent, child) = names();
        return Err(FrameError::ZeroQuaternion { parent, child });
    }
    // Written so that a NaN tolerance refuses rather than accepts.
    let near_unit = (norm_squared - 1.0).abs() <= tolerance;
    if !near_unit {
        let (parent, child) = names();
        return Err(FrameError::NotUnitQuaternion { parent, child, norm_squared, tolerance });
    }
    Ok(Pose3::new(pose.translation, pose.rotation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_lose_one_leading_slash() {
        assert_eq!(frame_name("/odom"), Ok("odom"));
        assert_eq!(frame_name("odom"), Ok("odom"));
        assert_eq!(frame_name("//odom"), Ok("/odom"));
        assert!(matches!(frame_name("/"), Err(FrameError::InvalidName { .. })));
        assert!(matches!(frame_name(""), Err(FrameError::InvalidName { .. })));
    }

    #[test]
    fn quaternions_are_checked_then_normalised() {
        let raw = |q: [f64; 4]| Pose3 { translation: [1.0, 2.0, 3.0], rotation: q };
        let ok = rigid_transform("a", "b", raw([0.0, 0.0, 0.0, 1.004]), 0.01).unwrap();
        assert_eq!(ok.rotation, [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(ok.translation, [1.0, 2.0, 3.0]);
        let e = rigid_transform("a", "b", raw([0.0, 0.0, 0.0, 1.1]), 0.01).unwrap_err();
        assert!(matches!(e, FrameError::NotUnitQuaternion { norm_squared, .. } if (norm_squared - 1.21).abs() < 1e-12));
        let e = rigid_transform("a", "b", raw([0.0; 4]), 0.01).unwrap_err();
        assert!(matches!(e, FrameError::ZeroQuaternion { .. }));
        for bad in [raw([f64::NAN, 0.0, 0.0, 1.0]), raw([0.0, 0.0, 0.0, f64::INFINITY])] {
            assert!(matches!(rigid_transform("a", "b", bad, 0.01), Err(FrameError::NotFinite { .. })));
        }
        let mut t = raw([0.0, 0.0, 0.0, 1.0]);
        t.translation[2] = f64::NEG_INFINITY;
        assert!(matches!(rigid_transform("a", "b", t, 0.01), Err(FrameError::NotFinite { .. })));
        // Pose3::new turns a zero quaternion into NaN: refused as well.
        let e = rigid_transform("a", "b", Pose3::new([0.0; 3], [0.0; 4]), 0.01).unwrap_err();
        assert_eq!(e.to_string(), "transform a → b has a non-finite translation or rotation");
    }
}
