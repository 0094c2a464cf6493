//! SE(2): planar rigid transforms (Thrun et al., *Probabilistic Robotics*, §5.2 pose notation).

use serde::{Deserialize, Serialize};
use std::ops::Mul;

/// A point in the plane, in metres, in whatever frame its variable name says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point2 {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
}

impl Point2 {
    /// A point from its coordinates.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    /// Euclidean distance to `other`.
    pub fn distance(self, other: Point2) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }

    /// True when both coordinates are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

/// The largest coordinate a pose may have, metres: 10⁹ m is 25 times round the Earth, and
/// still resolved to 10⁻⁷ m by an `f64`. An odometry reset to 10¹⁷ m (where one `f64` step
/// is 16 m, so the readings after it carry no motion at all) is a broken reading, not a
/// position.
pub const MAX_POSITION_M: f64 = 1e9;

/// Wraps an angle to (-π, π].
///
/// Uses `rem_euclid`, so the result is exact for angles a few turns away and stays
/// bounded for any finite input.
pub fn normalize_angle(theta: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let a = (theta + PI).rem_euclid(TAU) - PI;
    // rem_euclid maps to [-π, π); move -π to +π so the interval is (-π, π].
    if a <= -PI {
        a + TAU
    } else {
        a
    }
}

/// A rigid transform of the plane: rotation by `theta`, then translation by (`x`, `y`).
///
/// As a robot pose, `world_from_base` maps points from the robot's base frame into the
/// world (map) frame: `(x, y)` is the base origin in the world and `theta` its heading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// Translation x, metres.
    pub x: f64,
    /// Translation y, metres.
    pub y: f64,
    /// Rotation, radians (not necessarily normalised; see [`Pose2::normalized`]).
    pub theta: f64,
}

impl Pose2 {
    /// The identity transform.
    pub const IDENTITY: Pose2 = Pose2 { x: 0.0, y: 0.0, theta: 0.0 };

    /// A transform from translation and rotation.
    pub const fn new(x: f64, y: f64, theta: f64) -> Self {
        Self { x, y, theta }
    }

    /// The translation part as a point.
    pub fn translation(self) -> Point2 {
        Point2::new(self.x, self.y)
    }

    /// The same transform with `theta` wrapped to (-π, π].
    pub fn normalized(self) -> Self {
        Self { theta: normalize_angle(self.theta), ..self }
    }

    /// True when all three components are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }

    /// True when the pose is finite and within [`MAX_POSITION_M`] of its frame's origin in
    /// x and y: a pose a robot can have. A pose stream's frame origin is where it began, a
    /// datum or a map origin, never farther than the Earth is round.
    pub fn is_position(self) -> bool {
        self.is_finite() && self.x.abs() <= MAX_POSITION_M && self.y.abs() <= MAX_POSITION_M
    }

    /// Composition: `(a_from_b.compose(b_from_c))` is `a_from_c`.
    pub fn compose(self, b_from_c: Pose2) -> Pose2 {
        let (s, c) = self.theta.sin_cos();
        Pose2 {
            x: self.x + c * b_from_c.x - s * b_from_c.y,
            y: self.y + s * b_from_c.x + c * b_from_c.y,
            theta: normalize_angle(self.theta + b_from_c.theta),
        }
    }

    /// The inverse transform: `a_from_b.inverse()` is `b_from_a`.
    pub fn inverse(self) -> Pose2 {
        let (s, c) = self.theta.sin_cos();
        Pose2 { x: -(c * self.x + s * self.y), y: -(-s * self.x + c * self.y), theta: normalize_angle(-self.theta) }
    }

    /// Maps a point: `a_from_b.transform_point(p_in_b)` is `p_in_a`.
    pub fn transform_point(self, p: Point2) -> Point2 {
        self.point_transform()(p)
    }

    /// [`transform_point`](Self::transform_point) for many points: the sine and cosine are
    /// taken once, the arithmetic per point is the same to the bit.
    pub fn point_transform(self) -> impl Fn(Point2) -> Point2 + Copy {
        let (s, c) = self.theta.sin_cos();
        move |p| Point2 { x: self.x + c * p.x - s * p.y, y: self.y + s * p.x + c * p.y }
    }

    /// Interpolates between two poses: linear in translation, shortest arc in rotation.
    /// `t = 0` gives `self`, `t = 1` gives `other`.
    pub fn interpolate(self, other: Pose2, t: f64) -> Pose2 {
        let dtheta = normalize_angle(other.theta - self.theta);
        Pose2 {
            x: self.x + (other.x - self.x) * t,
            y: self.y + (other.y - self.y) * t,
            theta: normalize_angle(self.theta + dtheta * t),
        }
    }
}

impl Mul for Pose2 {
    type Output = Pose2;
    /// `a_from_b * b_from_c == a_from_c`.
    fn mul(self, rhs: Pose2) -> Pose2 {
        self.compose(rhs)
    }
}

impl Mul<Point2> for Pose2 {
    type Output = Point2;
    /// `a_from_b * p_in_b == p_in_a`.
    fn mul(self, rhs: Point2) -> Point2 {
        self.transform_point(rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    fn close_angle(a: f64, b: f64) -> bool {
        normalize_angle(a - b).abs() < 1e-9
    }

    #[test]
    fn normalize_wraps_into_half_open_interval() {
        assert!(close(normalize_angle(0.0), 0.0));
        assert!(close(normalize_angle(PI), PI));
        assert!(close(normalize_angle(-PI), PI));
        assert!(close(normalize_angle(3.0 * PI), PI));
        assert!(close(normalize_angle(2.0 * PI + 0.5), 0.5));
        assert!(close(normalize_angle(-2.0 * PI - 0.5), -0.5));
    }

    #[test]
    fn quarter_turn_maps_x_axis_to_y_axis() {
        let world_from_base = Pose2::new(1.0, 2.0, PI / 2.0);
        let p = world_from_base * Point2::new(1.0, 0.0);
        assert!(close(p.x, 1.0) && close(p.y, 3.0), "{p:?}");
    }

    #[test]
    fn interpolation_takes_the_short_arc() {
        let a = Pose2::new(0.0, 0.0, PI - 0.1);
        let b = Pose2::new(2.0, 0.0, -PI + 0.1);
        let m = a.interpolate(b, 0.5);
        assert!(close(m.x, 1.0));
        assert!(close_angle(m.theta, PI), "{}", m.theta);
    }

    fn pose() -> impl Strategy<Value = Pose2> {
        (-1e3..1e3f64, -1e3..1e3f64, -10.0..10.0f64).prop_map(|(x, y, t)| Pose2::new(x, y, t))
    }

    proptest! {
        #[test]
        fn inverse_round_trips(p in pose(), q in (-50.0..50.0f64, -50.0..50.0f64)) {
            let pt = Point2::new(q.0, q.1);
            let back = p.inverse() * (p * pt);
            prop_assert!((back.x - pt.x).abs() < 1e-7 && (back.y - pt.y).abs() < 1e-7);
            let id = p * p.inverse();
            prop_assert!(id.x.abs() < 1e-7 && id.y.abs() < 1e-7 && close_angle(id.theta, 0.0));
        }

        #[test]
        fn composition_is_associative_and_acts_on_points(a in pose(), b in pose(), c in pose(),
                                                          q in (-50.0..50.0f64, -50.0..50.0f64)) {
            let pt = Point2::new(q.0, q.1);
            let left = (a * b) * c;
            let right = a * (b * c);
            prop_assert!((left.x - right.x).abs() < 1e-6 && (left.y - right.y).abs() < 1e-6);
            prop_assert!(close_angle(left.theta, right.theta));
            let p1 = (a * b) * pt;
            let p2 = a * (b * pt);
            prop_assert!((p1.x - p2.x).abs() < 1e-6 && (p1.y - p2.y).abs() < 1e-6);
        }

        #[test]
        fn normalize_is_idempotent_and_bounded(t in -1e4..1e4f64) {
            let n = normalize_angle(t);
            prop_assert!(n > -PI && n <= PI);
            prop_assert!((normalize_angle(n) - n).abs() < 1e-12);
            prop_assert!(close_angle(n, t));
        }

        #[test]
        fn interpolation_hits_the_ends(a in pose(), b in pose()) {
            let s = a.interpolate(b, 0.0);
            let e = a.interpolate(b, 1.0);
            prop_assert!(close(s.x, a.x) && close(s.y, a.y) && close_angle(s.theta, a.theta));
            prop_assert!((e.x - b.x).abs() < 1e-9 && (e.y - b.y).abs() < 1e-9);
            prop_assert!(normalize_angle(e.theta - b.theta).abs() < 1e-9);
        }
    }
}
