//! The extended Kalman filter over `[x, y, θ, gyro bias b, odometry scale s]`
//! (Thrun et al., *Probabilistic Robotics*, §3.3, Table 3.3).
//!
//! Prediction uses the motion sources as control inputs (the design robot_localization
//! calls "differential" odometry): translation is the odometry increment scaled by `s`
//! (true distance = `s` × odometry distance) and rotated by the heading at the start of the
//! increment; heading is the bias-corrected gyro integral `∫ω dt − b Δt` when a gyro
//! covers the increment, the odometry's own heading increment otherwise, and nothing while
//! the robot stands still (the gyro then measures its bias instead). Bias and scale are
//! random walks. Corrections are gated by their normalised innovation squared and applied
//! in Joseph form, which keeps the covariance symmetric positive definite.

use super::linalg::{add, identity, mul, mul_vec, sandwich, spd_inverse, sub, symmetrize, transpose, Mat};
use crate::geometry::normalize_angle;
use crate::time::Stamp;

/// State dimension.
pub(crate) const N: usize = 5;
/// Indices into the state.
pub(crate) const THETA: usize = 2;

/// What one filter step leaves for the smoother: the filtered state at the step and the
/// prediction that led into it (Rauch, Tung & Striebel 1965 need exactly these).
#[derive(Clone, Debug)]
pub(crate) struct StepRecord {
    pub stamp: Stamp,
    pub x: [f64; N],
    pub p: Mat<N, N>,
    pub x_pred: [f64; N],
    pub p_pred: Mat<N, N>,
    /// Jacobian of the prediction into this step.
    pub f: Mat<N, N>,
}

/// How the heading moves over one prediction.
#[derive(Clone, Copy, Debug)]
pub(crate) enum HeadingMotion {
    /// Standing still: no rotation.
    Still,
    /// Raw gyro integral `∫ω dt` over `dt` seconds, with its variance.
    Gyro { angle: f64, var: f64, dt: f64 },
    /// The odometry's heading increment (its variance is in the increment covariance).
    Odometry,
}

/// One prediction's inputs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Motion {
    /// Odometry increment (x, y in the base frame at its start; θ).
    pub dx: f64,
    pub dy: f64,
    pub dtheta: f64,
    /// Its covariance.
    pub cov: Mat<3, 3>,
    pub heading: HeadingMotion,
    /// Extra heading variance (unmodelled gyro errors over the step).
    pub heading_noise: f64,
    /// Random-walk variances added to bias and scale over the step.
    pub bias_noise: f64,
    pub scale_noise: f64,
}

/// Propagates `(x, P)` through one motion; returns the Jacobian too.
pub(crate) fn predict(x: &[f64; N], p: &Mat<N, N>, m: &Motion) -> ([f64; N], Mat<N, N>, Mat<N, N>) {
    let (s, c) = x[THETA].sin_cos();
    let scale = x[4];
    let (rx, ry) = (c * m.dx - s * m.dy, s * m.dx + c * m.dy);
    let (dtheta, dtheta_db, heading_var) = match m.heading {
        HeadingMotion::Still => (0.0, 0.0, 0.0),
        HeadingMotion::Gyro { angle, var, dt } => (angle - x[3] * dt, -dt, var),
        HeadingMotion::Odometry => (m.dtheta, 0.0, m.cov[2][2]),
    };
    let mut xn = *x;
    xn[0] += scale * rx;
    xn[1] += scale * ry;
    xn[THETA] = normalize_angle(x[THETA] + dtheta);
    let mut f: Mat<N, N> = identity();
    f[0][THETA] = -scale * ry;
    f[1][THETA] = scale * rx;
    f[0][4] = rx;
    f[1][4] = ry;
    f[THETA][3] = dtheta_db;
    // Noise of the increment mapped into the world: G = s R(θ) on translation.
    let g = [[scale * c, -scale * s], [scale * s, scale * c]];
    let t_cov = [[m.cov[0][0], m.cov[0][1]], [m.cov[1][0], m.cov[1][1]]];
    let q_xy = sandwich(&g, &t_cov);
    let mut q = [[0.0; N]; N];
    q[0][0] = q_xy[0][0];
    q[0][1] = q_xy[0][1];
    q[1][0] = q_xy[1][0];
    q[1][1] = q_xy[1][1];
    if matches!(m.heading, HeadingMotion::Odometry) {
        // Translation and heading increments of the same odometry may be correlated.
        let cross = mul_vec(&g, &[m.cov[0][2], m.cov[1][2]]);
        q[0][THETA] = cross[0];
        q[THETA][0] = cross[0];
        q[1][THETA] = cross[1];
        q[THETA][1] = cross[1];
    }
    q[THETA][THETA] = heading_var + m.heading_noise;
    q[3][3] = m.bias_noise;
    q[4][4] = m.scale_noise;
    let pn = add(&sandwich(&f, p), &q);
    (xn, symmetrize(&pn), f)
}

/// The result of gating a correction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Gated {
    /// Normalised innovation squared (NaN when the innovation covariance is singular).
    pub nis: f64,
    /// Applied.
    pub accepted: bool,
}

/// Gates and applies a linearised correction with innovation `nu`, Jacobian `h` and
/// measurement covariance `r`.
pub(crate) fn update<const M: usize>(
    x: &mut [f64; N],
    p: &mut Mat<N, N>,
    nu: [f64; M],
    h: &Mat<M, N>,
    r: &Mat<M, M>,
    gate: f64,
) -> Gated {
    update_weighted(x, p, nu, h, r, r, gate)
}

/// [`update`] gated with the measurement's own covariance `r_gate` but applied with
/// `r`: a correlated measurement is tested for being an outlier at its own σ, and weighted
/// as the share of an independent one it is.
pub(crate) fn update_weighted<const M: usize>(
    x: &mut [f64; N],
    p: &mut Mat<N, N>,
    nu: [f64; M],
    h: &Mat<M, N>,
    r_gate: &Mat<M, M>,
    r: &Mat<M, M>,
    gate: f64,
) -> Gated {
    let ht = transpose(h);
    let Some(g_inv) = spd_inverse(&add(&sandwich(h, p), r_gate)) else {
        return Gated { nis: f64::NAN, accepted: false };
    };
    let nis: f64 = (0..M).map(|i| (0..M).map(|j| nu[i] * g_inv[i][j] * nu[j]).sum::<f64>()).sum();
    if nis.is_nan() || nis > gate {
        return Gated { nis, accepted: false };
    }
    let s = add(&sandwich(h, p), r);
    let Some(s_inv) = spd_inverse(&s) else {
        return Gated { nis: f64::NAN, accepted: false };
    };
    let k = mul(&mul(p, &ht), &s_inv);
    let dx = mul_vec(&k, &nu);
    for i in 0..N {
        x[i] += dx[i];
    }
    x[THETA] = normalize_angle(x[THETA]);
    let i_kh = sub(&identity::<N>(), &mul(&k, h));
    *p = add(&sandwich(&i_kh, p), &sandwich(&k, r));
    Gated { nis, accepted: true }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_motion_moves_along_the_heading_and_grows_uncertainty() {
        let x = [1.0, 2.0, std::f64::consts::FRAC_PI_2, 0.0, 1.1];
        let p = symmetrize(&[
            [1e-4, 0.0, 0.0, 0.0, 0.0],
            [0.0, 1e-4, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1e-4, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1e-6, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1e-4],
        ]);
        let m = Motion {
            dx: 1.0,
            dy: 0.0,
            dtheta: 0.0,
            cov: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
            heading: HeadingMotion::Gyro { angle: 0.1, var: 1e-6, dt: 1.0 },
            heading_noise: 0.0,
            bias_noise: 0.0,
            scale_noise: 0.0,
        };
        let (xn, pn, f) = predict(&x, &p, &m);
        assert!((xn[0] - 1.0).abs() < 1e-12 && (xn[1] - 3.1).abs() < 1e-12, "{xn:?}");
        assert!((xn[2] - (std::f64::consts::FRAC_PI_2 + 0.1)).abs() < 1e-12);
        assert!(pn[0][0] > p[0][0] && pn[1][1] > p[1][1]);
        assert_eq!(f[2][3], -1.0);
    }

    #[test]
    fn the_gate_rejects_far_measurements_and_keeps_the_state() {
        let mut x = [0.0, 0.0, 0.0, 0.0, 1.0];
        let mut p: Mat<N, N> = identity();
        for row in p.iter_mut() {
            for v in row.iter_mut() {
                *v *= 0.01;
            }
        }
        let h = [[1.0, 0.0, 0.0, 0.0, 0.0]];
        let r = [[0.01]];
        let far = update(&mut x, &mut p, [5.0], &h, &r, 6.63);
        assert!(!far.accepted && (far.nis - 1250.0).abs() < 1e-9);
        assert_eq!(x[0], 0.0);
        let near = update(&mut x, &mut p, [0.1], &h, &r, 6.63);
        assert!(near.accepted);
        assert!((x[0] - 0.05).abs() < 1e-12 && (p[0][0] - 0.005).abs() < 1e-12);
    }
}
