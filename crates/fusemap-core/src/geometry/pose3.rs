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

    /// True when the translation and the rotation are all finite (a zero quaternion
    /// given to [`Pose3::new`] becomes NaN, so it is not finite either).
    pub fn is_finite(&self) -> bool {
        self.translation.iter().chain(self.rotation.iter()).all(|v| v.is_finite())
    }

    /// The angle, radians in `[0, π]`, of the rotation taking `self`'s orientation to
    /// `other`'s. Computed as `2·atan2(‖v‖, |w|)` of the relative quaternion, which stays
    /// exact for tiny angles where `2·acos(w)` loses half its digits.
    pub fn angle_to(&self, other: &Pose3) -> f64 {
        let q = self.rotation;
        let d = qmul([-q[0], -q[1], -q[2], q[3]], other.rotation);
        2.0 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().atan2(d[3].abs())
    }

    /// The Euclidean distance between the two translations, metres.
    pub fn distance_to(&self, other: &Pose3) -> f64 {
        let [dx, dy, dz] = [0, 1, 2].map(|k| other.translation[k] - self.translation[k]);
        (dx * dx + dy * dy + dz * dz).sqrt()
    }

    /// Interpolates between two transforms: linear in translation, spherical-linear
    /// (slerp, Shoemake 1985) along the shorter arc in rotation. `t = 0` gives `self`,
    /// `t = 1` gives `other`. This is what tf2 and Cartographer's
    /// `TransformInterpolationBuffer` do between two stamped samples.
    pub fn interpolate(&self, other: &Pose3, t: f64) -> Pose3 {
        let a = self.rotation;
        let mut b = other.rotation;
        // q and -q are the same rotation: take the one on a's side for the short arc.
        if a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
            b = b.map(|v| -v);
        }
        // Angle between a and b as 4-vectors, exact at both ends of its range.
        let diff: f64 = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        let sum: f64 = a.iter().zip(&b).map(|(x, y)| (x + y) * (x + y)).sum::<f64>().sqrt();
        let omega = 2.0 * diff.atan2(sum);
        let (wa, wb) = if omega < 1e-12 {
            (1.0 - t, t)
        } else {
            let s = omega.sin();
            (((1.0 - t) * omega).sin() / s, (t * omega).sin() / s)
        };
        let q = [0, 1, 2, 3].map(|k| wa * a[k] + wb * b[k]);
        let translation = [0, 1, 2].map(|k| self.translation[k] + (other.translation[k] - self.translation[k]) * t);
        Pose3::new(translation, q)
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

    #[test]
    fn planar_interpolation_matches_se2() {
        use crate::geometry::{normalize_angle, Pose2};
        // Across ±π the short arc goes through π, as Pose2::interpolate does.
        for (ya, yb) in [(0.2, 1.4), (3.0, -3.0), (-0.5, 2.5), (1.0, 1.0)] {
            let a = Pose3::new([1.0, -2.0, 0.5], yaw_q(ya));
            let b = Pose3::new([3.0, 2.0, -0.5], yaw_q(yb));
            for t in [0.0, 0.25, 0.5, 0.9, 1.0] {
                let m = a.interpolate(&b, t).to_mount();
                let p = Pose2::new(1.0, -2.0, ya).interpolate(Pose2::new(3.0, 2.0, yb), t);
                assert!((m.x - p.x).abs() < 1e-12 && (m.y - p.y).abs() < 1e-12, "{t}");
                assert!((m.z - (0.5 - t)).abs() < 1e-12);
                assert!(normalize_angle(m.yaw - p.theta).abs() < 1e-9, "{ya} {yb} {t}: {} vs {}", m.yaw, p.theta);
            }
        }
    }

    #[test]
    fn angle_and_distance() {
        let a = Pose3::new([0.0, 0.0, 0.0], yaw_q(0.1));
        let b = Pose3::new([3.0, 4.0, 0.0], yaw_q(0.1 + 1e-9));
        assert!((a.angle_to(&b) - 1e-9).abs() < 1e-15);
        assert_eq!(a.distance_to(&b), 5.0);
        // q and -q: the same rotation.
        let c = Pose3 { rotation: a.rotation.map(|v| -v), ..a };
        assert_eq!(a.angle_to(&c), 0.0);
        let d = Pose3::new([0.0; 3], [1.0, 0.0, 0.0, 0.0]);
        assert!((Pose3::IDENTITY.angle_to(&d) - std::f64::consts::PI).abs() < 1e-12);
        assert!(!Pose3::new([0.0; 3], [0.0; 4]).is_finite());
        assert!(!Pose3::new([f64::INFINITY, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).is_finite());
        assert!(a.is_finite());
    }

    proptest! {
        #[test]
        fn slerp_moves_at_constant_rate(qa in prop::array::uniform4(-1.0..1.0f64), qb in prop::array::uniform4(-1.0..1.0f64),
                                        t in 0.0..1.0f64) {
            prop_assume!(qa.iter().map(|x| x * x).sum::<f64>() > 0.01 && qb.iter().map(|x| x * x).sum::<f64>() > 0.01);
            let a = Pose3::new([0.0; 3], qa);
            let b = Pose3::new([0.0; 3], qb);
            let m = a.interpolate(&b, t);
            let total = a.angle_to(&b);
            // On the geodesic: the two parts add up to the whole, in proportion t.
            prop_assert!((a.angle_to(&m) - t * total).abs() < 1e-9);
            prop_assert!((m.angle_to(&b) - (1.0 - t) * total).abs() < 1e-9);
            prop_assert!(a.interpolate(&b, 0.0).angle_to(&a) < 1e-9);
            prop_assert!(a.interpolate(&b, 1.0).angle_to(&b) < 1e-9);
        }

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
