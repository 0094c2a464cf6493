//! SE(3) rigid transforms as translation + unit quaternion, for chaining the static
//! transforms of a TF tree (`base_link → mount_plate → laser`) before reducing the
//! result to the plane.

use super::{quaternion_to_rpy, Mount3};

/// A 3D rigid transform `a_from_b`: rotate by the quaternion `(x, y, z, w)`, then
/// translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose3 {
    /// Translation, metres.
    pub translation: [f64; 3],
    /// Rotation quaternion `(x, y, z, w)`, normalised on construction.
    pub rotation: [f64; 4],
}

fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

impl Pose3 {
    /// The identity.
    pub const IDENTITY: Pose3 = Pose3 { translation: [0.0; 3], rotation: [0.0, 0.0, 0.0, 1.0] };

    /// A transform from translation and (not necessarily unit) quaternion. A zero or
    /// non-finite quaternion is kept as NaN so later checks refuse it.
    pub fn new(translation: [f64; 3], q: [f64; 4]) -> Self {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        let rotation = if n.is_finite() && n > 0.0 { [q[0] / n, q[1] / n, q[2] / n, q[3] / n] } else { [f64::NAN; 4] };
        Self { translation, rotation }
    }

    /// Rotates a vector.
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        let q = self.rotation;
        let p = qmul(qmul(q, [v[0], v[1], v[2], 0.0]), [-q[0], -q[1], -q[2], q[3]]);
        [p[0], p[1], p[2]]
    }

    /// `a_from_b.compose(b_from_c)` is `a_from_c`.
    pub fn compose(&self, b_from_c: &Pose3) -> Pose3 {
        let t = self.rotate(b_from_c.translation);
        Pose3::new(
            [self.translation[0] + t[0], self.translation[1] + t[1], self.translation[2] + t[2]],
            qmul(self.rotation, b_from_c.rotation),
        )
    }

    /// `a_from_b.inverse()` is `b_from_a`.
    pub fn inverse(&self) -> Pose3 {
        let q = self.rotation;
        let inv = Pose3 { translation: [0.0; 3], rotation: [-q[0], -q[1], -q[2], q[3]] };
        let t = inv.rotate(self.translation);
        Pose3 { translation: [-t[0], -t[1], -t[2]], rotation: inv.rotation }
    }

    /// As a mount (x, y, z, roll, pitch, yaw).
    pub fn to_mount(&self) -> Mount3 {
        let (roll, pitch, yaw) = quaternion_to_rpy(self.rotation);
        let [x, y, z] = self.translation;
        Mount3 { x, y, z, roll, pitch, yaw }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn yaw_q(yaw: f64) -> [f64; 4] {
        [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()]
    }

    #[test]
    fn chain_of_planar_transforms_matches_se2() {
        use crate::geometry::Pose2;
        let a = Pose3::new([1.0, 2.0, 0.3], yaw_q(0.5));
        let b = Pose3::new([0.2, -0.1, 0.1], yaw_q(-1.2));
        let m = a.compose(&b).to_mount();
        let p = Pose2::new(1.0, 2.0, 0.5) * Pose2::new(0.2, -0.1, -1.2);
        assert!((m.x - p.x).abs() < 1e-12 && (m.y - p.y).abs() < 1e-12);
        assert!((m.yaw - p.theta).abs() < 1e-12);
        assert!((m.z - 0.4).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn inverse_round_trips(t in prop::array::uniform3(-5.0..5.0f64), q in prop::array::uniform4(-1.0..1.0f64),
                               v in prop::array::uniform3(-5.0..5.0f64)) {
            prop_assume!(q.iter().map(|x| x * x).sum::<f64>() > 0.01);
            let a = Pose3::new(t, q);
            let id = a.compose(&a.inverse());
            for k in 0..3 { prop_assert!(id.translation[k].abs() < 1e-9); }
            let r = a.rotate(v);
            let back = a.inverse().rotate(r);
            for k in 0..3 { prop_assert!((back[k] - v[k]).abs() < 1e-9); }
        }
    }
}
