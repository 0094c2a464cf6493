//! Measurement models: innovation `ν = z − h(x)` and Jacobian `H = ∂h/∂x` of every
//! correction, over the state `[x, y, θ, gyro bias, odometry scale]`.

use super::linalg::Mat;
use crate::geometry::{normalize_angle, Point2};

/// A GNSS antenna position: `h(x) = p + R(θ) a` with `a` the antenna in the base frame
/// (`base_from_antenna`). Ignoring the lever arm would turn every rotation of the robot into
/// a position error of up to twice the arm's length.
pub(crate) fn position(x: &[f64; 5], z: [f64; 2], antenna: Point2) -> ([f64; 2], Mat<2, 5>) {
    let (s, c) = x[2].sin_cos();
    let hx = x[0] + c * antenna.x - s * antenna.y;
    let hy = x[1] + s * antenna.x + c * antenna.y;
    let h = [[1.0, 0.0, -s * antenna.x - c * antenna.y, 0.0, 0.0], [0.0, 1.0, c * antenna.x - s * antenna.y, 0.0, 0.0]];
    ([z[0] - hx, z[1] - hy], h)
}

/// An absolute heading: `h(x) = θ`, innovation wrapped to (−π, π].
pub(crate) fn heading(x: &[f64; 5], yaw: f64) -> ([f64; 1], Mat<1, 5>) {
    ([normalize_angle(yaw - x[2])], [[0.0, 0.0, 1.0, 0.0, 0.0]])
}

/// An absolute pose: `h(x) = (x, y, θ)`.
pub(crate) fn pose(x: &[f64; 5], z: [f64; 3]) -> ([f64; 3], Mat<3, 5>) {
    (
        [z[0] - x[0], z[1] - x[1], normalize_angle(z[2] - x[2])],
        [[1.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0]],
    )
}

/// The gyro's mean rate while standing still measures its bias: `h(x) = b`.
pub(crate) fn zero_rate(x: &[f64; 5], mean_rate: f64) -> ([f64; 1], Mat<1, 5>) {
    ([mean_rate - x[3]], [[0.0, 0.0, 0.0, 1.0, 0.0]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The lever-arm Jacobian against central finite differences of h.
        #[test]
        fn position_jacobian_matches_finite_differences(
            th in -3.2..3.2f64, ax in -2.0..2.0f64, ay in -2.0..2.0f64, px in -100.0..100.0f64, py in -100.0..100.0f64,
        ) {
            let antenna = Point2::new(ax, ay);
            let x = [px, py, th, 0.01, 1.02];
            let (_, h) = position(&x, [0.0, 0.0], antenna);
            let eps = 1e-6;
            for j in 0..5 {
                let (mut xp, mut xm) = (x, x);
                xp[j] += eps;
                xm[j] -= eps;
                // With z = 0 the innovation is −h(x).
                let (np, _) = position(&xp, [0.0, 0.0], antenna);
                let (nm, _) = position(&xm, [0.0, 0.0], antenna);
                for i in 0..2 {
                    let fd = -(np[i] - nm[i]) / (2.0 * eps);
                    prop_assert!((fd - h[i][j]).abs() < 1e-6, "H[{}][{}] = {} vs {}", i, j, h[i][j], fd);
                }
            }
        }
    }

    #[test]
    fn angle_innovations_take_the_short_way() {
        let x = [0.0, 0.0, 3.1, 0.0, 1.0];
        let (nu, _) = heading(&x, -3.1);
        assert!((nu[0] - (2.0 * std::f64::consts::PI - 6.2)).abs() < 1e-12);
        let (nu, _) = pose(&x, [1.0, 2.0, -3.1]);
        assert!(nu[2] > 0.0 && nu[2] < 0.1);
    }
}
