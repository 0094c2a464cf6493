//! A sensor's mounting pose on `base_link` (its extrinsics) and its reduction to the plane.
//!
//! Config files and URDF/TF give a full 3D pose `base_from_sensor` as x, y, z and
//! roll, pitch, yaw (ROS REP 103: fixed-axis X-Y-Z, i.e. `R = Rz(yaw)·Ry(pitch)·Rx(roll)`).
//! A 2D grid needs where the scan plane's rays go in the base's x-y plane. Two facts of
//! real robots shape the reduction:
//! * a lidar mounted upside down (roll = π) scans clockwise when seen from above: the
//!   planar transform then mirrors beam angles, which no SE(2) pose can express, so
//!   [`PlanarMount`] carries a handedness sign;
//! * a tilted lidar does not scan a horizontal plane, so its returns do not belong in a
//!   2D grid as they are; the reduction refuses tilts above a tolerance instead of
//!   silently projecting them.

use super::{normalize_angle, Point2, Pose2};
use serde::{Deserialize, Serialize};

/// A full 3D mounting pose `base_from_sensor` (metres, radians; ROS REP 103 RPY).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Mount3 {
    /// Sensor origin x in `base_link`, metres.
    pub x: f64,
    /// Sensor origin y in `base_link`, metres.
    pub y: f64,
    /// Sensor origin z in `base_link`, metres (ignored by the 2D grid).
    pub z: f64,
    /// Rotation about the base's x axis, radians.
    pub roll: f64,
    /// Rotation about the base's y axis, radians.
    pub pitch: f64,
    /// Rotation about the base's z axis, radians.
    pub yaw: f64,
}

/// Why a 3D mount cannot be reduced to the plane.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MountError {
    /// A component is NaN or infinite.
    #[error("mount field `{field}` is not a finite number")]
    NotFinite {
        /// The offending field.
        field: &'static str,
    },
    /// The scan plane is tilted more than allowed.
    #[error("the sensor's scan plane is tilted {tilt_deg:.2}° from horizontal (limit {limit_deg:.2}°): a 2D grid needs a level scan plane")]
    Tilted {
        /// Measured tilt, degrees.
        tilt_deg: f64,
        /// Allowed tilt, degrees.
        limit_deg: f64,
    },
}

impl Mount3 {
    /// The rotation as a unit quaternion `(x, y, z, w)`: `q = q_z(yaw) · q_y(pitch) ·
    /// q_x(roll)`, the same fixed-axis RPY as [`Mount3::rotation`].
    pub fn quaternion(&self) -> [f64; 4] {
        let (sr, cr) = (self.roll / 2.0).sin_cos();
        let (sp, cp) = (self.pitch / 2.0).sin_cos();
        let (sy, cy) = (self.yaw / 2.0).sin_cos();
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ]
    }

    /// A mount from a translation and a unit quaternion `(x, y, z, w)` (as ROS
    /// `geometry_msgs/Transform` carries it). The quaternion is normalised first; a zero
    /// or non-finite quaternion gives NaN angles, which [`Mount3::to_planar`] refuses.
    pub fn from_translation_quaternion(t: [f64; 3], q: [f64; 4]) -> Self {
        let (roll, pitch, yaw) = quaternion_to_rpy(q);
        Self { x: t[0], y: t[1], z: t[2], roll, pitch, yaw }
    }

    /// The rotation matrix `R = Rz(yaw)·Ry(pitch)·Rx(roll)`, row-major.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (sr, cr) = self.roll.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let (sy, cy) = self.yaw.sin_cos();
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    }

    /// Reduces the mount to the plane, refusing a scan plane tilted more than
    /// `max_tilt` radians from horizontal (upright or upside down).
    pub fn to_planar(&self, max_tilt: f64) -> Result<PlanarMount, MountError> {
        for (field, v) in
            [("x", self.x), ("y", self.y), ("z", self.z), ("roll", self.roll), ("pitch", self.pitch), ("yaw", self.yaw)]
        {
            if !v.is_finite() {
                return Err(MountError::NotFinite { field });
            }
        }
        let r = self.rotation();
        // The sensor's z axis expressed in the base frame is R's third column.
        let z_z = r[2][2];
        let tilt = z_z.abs().clamp(0.0, 1.0).acos();
        if tilt > max_tilt {
            return Err(MountError::Tilted { tilt_deg: tilt.to_degrees(), limit_deg: max_tilt.to_degrees() });
        }
        // Heading of the sensor's x axis (R's first column) projected on the base plane.
        let yaw = r[1][0].atan2(r[0][0]);
        let handedness = if z_z < 0.0 { -1.0 } else { 1.0 };
        Ok(PlanarMount { base_from_sensor: Pose2::new(self.x, self.y, normalize_angle(yaw)), handedness })
    }
}

/// Roll, pitch, yaw (ROS REP 103 fixed-axis X-Y-Z) of a quaternion `(x, y, z, w)`.
/// The quaternion is normalised first; a zero or non-finite one gives NaN angles.
pub fn quaternion_to_rpy(q: [f64; 4]) -> (f64, f64, f64) {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !(n.is_finite() && n > 0.0) {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let [x, y, z, w] = [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    (roll, pitch, yaw)
}

/// The yaw of a quaternion `(x, y, z, w)`: the heading of its x axis projected on the
/// x-y plane (what a planar robot's odometry orientation means). NaN for a zero or
/// non-finite quaternion.
pub fn quaternion_yaw(q: [f64; 4]) -> f64 {
    let n2 = q.iter().map(|v| v * v).sum::<f64>();
    if !(n2.is_finite() && n2 > 0.0) {
        return f64::NAN;
    }
    // The formula below holds for unit quaternions only; a scaled one (a driver that
    // does not normalise) is normalised first. Unit ones are left bit for bit as they are.
    let [x, y, z, w] = if (n2 - 1.0).abs() > 1e-12 { q.map(|v| v / n2.sqrt()) } else { q };
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// A sensor mount reduced to the plane of the grid.
///
/// A beam at angle `a` in the sensor frame points at angle
/// `base_from_sensor.theta + handedness * a` in the base frame and starts at
/// `base_from_sensor.translation()`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarMount {
    /// The planar part of the mount.
    pub base_from_sensor: Pose2,
    /// +1 for a sensor whose z axis points up, -1 for one mounted upside down.
    pub handedness: f64,
}

impl Default for PlanarMount {
    fn default() -> Self {
        Self { base_from_sensor: Pose2::IDENTITY, handedness: 1.0 }
    }
}

impl PlanarMount {
    /// The beam angle in the base frame of a beam at `angle_in_sensor`.
    pub fn beam_angle_in_base(&self, angle_in_sensor: f64) -> f64 {
        self.base_from_sensor.theta + self.handedness * angle_in_sensor
    }

    /// The sensor origin in the base frame.
    pub fn origin_in_base(&self) -> Point2 {
        self.base_from_sensor.translation()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_of_a_scaled_quaternion_is_its_rotation() {
        let h = 0.7f64 / 2.0;
        let q = [0.0, 0.0, 3.0 * h.sin(), 3.0 * h.cos()];
        assert!((quaternion_yaw(q) - 0.7).abs() < 1e-12);
        assert!(quaternion_yaw([0.0; 4]).is_nan());
    }

    #[test]
    fn quaternion_round_trips_through_rpy() {
        let m = Mount3 { x: 0.1, y: -0.2, z: 0.3, roll: 0.3, pitch: -0.4, yaw: 2.5 };
        let back = Mount3::from_translation_quaternion([m.x, m.y, m.z], m.quaternion());
        for (a, b) in [(m.roll, back.roll), (m.pitch, back.pitch), (m.yaw, back.yaw)] {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn level_mount_keeps_yaw_and_translation() {
        let m = Mount3 { x: 0.2, y: -0.1, z: 0.3, yaw: 0.5, ..Default::default() };
        let p = m.to_planar(0.01).unwrap();
        assert_eq!(p.handedness, 1.0);
        assert!((p.base_from_sensor.theta - 0.5).abs() < 1e-12);
        assert_eq!(p.origin_in_base(), Point2::new(0.2, -0.1));
    }

    #[test]
    fn upside_down_mount_mirrors_beams() {
        // roll = π: the sensor's +y axis points to the base's -y.
        let m = Mount3 { roll: PI, ..Default::default() };
        let p = m.to_planar(0.01).unwrap();
        assert_eq!(p.handedness, -1.0);
        let a = p.beam_angle_in_base(FRAC_PI_2);
        assert!((normalize_angle(a) + FRAC_PI_2).abs() < 1e-12, "{a}");
        // The same holds when flipped by pitch = π instead: forward becomes backward.
        let m = Mount3 { pitch: PI, ..Default::default() };
        let p = m.to_planar(0.01).unwrap();
        assert_eq!(p.handedness, -1.0);
        assert!((normalize_angle(p.beam_angle_in_base(0.0)).abs() - PI).abs() < 1e-12);
    }

    #[test]
    fn mirrored_beam_direction_matches_the_3d_rotation() {
        let m = Mount3 { roll: PI, yaw: 0.7, ..Default::default() };
        let p = m.to_planar(0.01).unwrap();
        let r = m.rotation();
        for a in [-1.2f64, -0.3, 0.0, 0.4, 1.5] {
            let d = [a.cos(), a.sin(), 0.0];
            let bx = r[0][0] * d[0] + r[0][1] * d[1];
            let by = r[1][0] * d[0] + r[1][1] * d[1];
            let want = by.atan2(bx);
            assert!(normalize_angle(p.beam_angle_in_base(a) - want).abs() < 1e-9);
        }
    }

    #[test]
    fn quaternions() {
        let h = std::f64::consts::FRAC_PI_4;
        // Yaw of 90°: q = (0, 0, sin 45°, cos 45°).
        let q = [0.0, 0.0, h.sin(), h.cos()];
        assert!((quaternion_yaw(q) - FRAC_PI_2).abs() < 1e-12);
        let (r, p, y) = quaternion_to_rpy(q);
        assert!(r.abs() < 1e-12 && p.abs() < 1e-12 && (y - FRAC_PI_2).abs() < 1e-12);
        // Upside down (roll = π): q = (1, 0, 0, 0); unnormalised input is fine.
        let m = Mount3::from_translation_quaternion([0.1, 0.0, 0.2], [2.0, 0.0, 0.0, 0.0]);
        assert_eq!(m.to_planar(0.01).unwrap().handedness, -1.0);
        assert!(quaternion_yaw([0.0; 4]).is_nan());
        assert!(Mount3::from_translation_quaternion([0.0; 3], [0.0; 4]).to_planar(0.1).is_err());
    }

    #[test]
    fn tilted_mount_is_refused() {
        let m = Mount3 { pitch: 0.2, ..Default::default() };
        let e = m.to_planar(0.05).unwrap_err();
        assert!(matches!(e, MountError::Tilted { .. }), "{e}");
        assert!(e.to_string().contains("tilted"));
    }

    #[test]
    fn non_finite_mount_names_the_field() {
        let m = Mount3 { yaw: f64::NAN, ..Default::default() };
        assert_eq!(m.to_planar(0.1).unwrap_err(), MountError::NotFinite { field: "yaw" });
    }
}
