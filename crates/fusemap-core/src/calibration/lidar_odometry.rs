//! The lidar's planar mount and the wheel odometry's scale from the two tracks a log
//! gives: the wheels' (odometry) and the lidar's (SLAM, which places the base through the
//! configured mount M′). Censi et al. 2013 calibrate odometry and a lidar mount jointly
//! from the same two kinds of motion; this is the planar hand–eye form of it.
//!
//! SLAM's base pose is the true one composed with a constant body-frame error,
//! `B′ = B ∘ Δ` with `Δ = M ∘ M′⁻¹` (M the true mount). So each relative motion SLAM
//! reports is the true one conjugated, `C = Δ⁻¹ A Δ`, where the odometry reports `A` with
//! its translation scaled by ρ. Written out, `ρ R_φ t_C − t_A = ρ (R_A − I) t_Δ`: linear in
//! `(ρ cos φ, ρ sin φ, ρ t_Δ)`, solved by iteratively reweighted least squares (Huber
//! weights: wheel slip makes outliers). The rotation φ and the scale ρ come from every
//! step that moves; the lever arm `t_Δ` only from steps that turn (`R_A − I` vanishes on a
//! straight drive), and is reported as undetermined when the turns do not fix it.

use super::{jackknife_sigma, Interval};
use crate::geometry::{normalize_angle, Pose2};
use serde::Serialize;

/// One step of the robot seen by both tracks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionStep {
    /// The odometry's relative motion (its own frame at the step's start).
    pub odometry: Pose2,
    /// SLAM's relative motion over the same instants.
    pub lidar: Pose2,
}

/// The estimate.
#[derive(Clone, Debug, Serialize)]
pub struct LidarOdometry {
    /// Steps used.
    pub steps: u64,
    /// Of them, those turning more than 5°.
    pub turning_steps: u64,
    /// `Δ`'s rotation, radians: the true mount's yaw is the configured one plus this.
    pub yaw: Interval,
    /// `Δ`'s translation (x, y), metres, in the base frame; `None` when the log's turns do
    /// not fix it (its 95 % interval would be wider than `max_lever_interval_m`).
    pub lever: Option<[Interval; 2]>,
    /// Odometry distance / true distance.
    pub scale: Interval,
    /// The wheel base the odometry should assume, as a multiple of the one it does: with
    /// both wheels' distances scaled by ρ and the base wrong, its turns are scaled by
    /// κ = ρ · true base / assumed base, so this is κ / ρ (κ from [`turn_agreement`] over
    /// the steps that turn). `None` with fewer than 12 turning steps (each jackknife subset
    /// needs 10), or when the odometry does not turn the way SLAM does.
    pub wheel_base: Option<Interval>,
    /// Residual RMS of the step equations with no correction (Δ = identity, ρ = 1), metres.
    pub cost_before_m: f64,
    /// … and with the estimate.
    pub cost_after_m: f64,
}

/// Regularisation of the lever-arm unknowns (m² of `R_A − I` content).
const LEVER_RIDGE: f64 = 1e-9;

/// Huber's tuning constant (95 % efficiency under Gaussian noise).
const HUBER_K: f64 = 1.345;

/// Solves the 4 × 4 system `n x = b` (Gaussian elimination with partial pivoting); `None`
/// when singular.
fn solve4(mut n: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    for c in 0..4 {
        let p = (c..4).max_by(|&i, &j| n[i][c].abs().total_cmp(&n[j][c].abs()))?;
        if n[p][c].abs() < 1e-12 {
            return None;
        }
        n.swap(c, p);
        b.swap(c, p);
        let pivot = n[c];
        for r in c + 1..4 {
            let f = n[r][c] / pivot[c];
            for (x, p) in n[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * p;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 4];
    for c in (0..4).rev() {
        let s: f64 = (c + 1..4).map(|k| n[c][k] * x[k]).sum();
        x[c] = (b[c] - s) / n[c][c];
    }
    Some(x)
}

/// The inverse of a 4 × 4 matrix, column by column.
fn inverse4(n: [[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut inv = [[0.0; 4]; 4];
    for c in 0..4 {
        let mut e = [0.0; 4];
        e[c] = 1.0;
        let x = solve4(n, e)?;
        for r in 0..4 {
            inv[r][c] = x[r];
        }
    }
    Some(inv)
}

/// The two rows of a step: coefficients of `(ρc, ρs, ρtx, ρty)` and the right-hand side.
fn rows(s: &MotionStep) -> [([f64; 4], f64); 2] {
    // The rotation is SLAM's: conjugation keeps it, while the odometry's own is scaled by
    // its wheel-base error (estimated apart, `turn_scale`).
    let (a, c) = (s.odometry, s.lidar);
    let (co, si) = (c.theta.cos(), c.theta.sin());
    [([c.x, -c.y, -(co - 1.0), si], a.x), ([c.y, c.x, -si, -(co - 1.0)], a.y)]
}

fn residual(r: &([f64; 4], f64), u: &[f64; 4]) -> f64 {
    r.0.iter().zip(u).map(|(a, b)| a * b).sum::<f64>() - r.1
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        crate::metrics::median_of_sorted(&v)
    }
}

/// Contiguous blocks of steps left out in turn for the jackknife.
const JACKKNIFE_BLOCKS: usize = 10;

/// The weighted least-squares fit: `(ρc, ρs, ρtx, ρty)` and its covariance.
fn fit(steps: &[MotionStep]) -> Option<([f64; 4], [[f64; 4]; 4])> {
    let all: Vec<([f64; 4], f64)> = steps.iter().flat_map(rows).collect();
    let mut u = [1.0, 0.0, 0.0, 0.0];
    let mut weights = vec![1.0; all.len()];
    let mut normal = [[0.0; 4]; 4];
    let mut sigma = 0.0;
    for _ in 0..10 {
        normal = [[0.0; 4]; 4];
        let mut b = [0.0; 4];
        for (r, w) in all.iter().zip(&weights) {
            for (i, row) in normal.iter_mut().enumerate() {
                b[i] += w * r.0[i] * r.1;
                for (v, rj) in row.iter_mut().zip(&r.0) {
                    *v += w * r.0[i] * rj;
                }
            }
        }
        // A whisper of ridge on the lever arm keeps a straight drive's system solvable; its
        // interval then comes out enormous, and the lever is reported undetermined.
        normal[2][2] += LEVER_RIDGE;
        normal[3][3] += LEVER_RIDGE;
        u = solve4(normal, b)?;
        let res: Vec<f64> = all.iter().map(|r| residual(r, &u)).collect();
        sigma = (1.4826 * median(res.iter().map(|r| r.abs()).collect())).max(1e-9);
        for (w, r) in weights.iter_mut().zip(&res) {
            let z = r.abs() / sigma;
            *w = if z <= HUBER_K { 1.0 } else { HUBER_K / z };
        }
    }
    Some((u, inverse4(normal)?.map(|row| row.map(|v| v * sigma * sigma))))
}

/// The parameters of a fit: yaw φ, scale ρ, lever x, y.
fn parameters(u: &[f64; 4]) -> [f64; 4] {
    let rho = u[0].hypot(u[1]);
    [u[1].atan2(u[0]), rho, u[2] / rho, u[3] / rho]
}

/// The parameters' standard errors from the fit's covariance (first-order propagation).
fn model_sigmas(u: &[f64; 4], cov: &[[f64; 4]; 4]) -> [f64; 4] {
    let rho = u[0].hypot(u[1]);
    let var = |g: [f64; 2]| {
        (g[0] * g[0] * cov[0][0] + 2.0 * g[0] * g[1] * cov[0][1] + g[1] * g[1] * cov[1][1]).max(0.0).sqrt()
    };
    [
        var([-u[1] / (rho * rho), u[0] / (rho * rho)]),
        var([u[0] / rho, u[1] / rho]),
        cov[2][2].max(0.0).sqrt() / rho,
        cov[3][3].max(0.0).sqrt() / rho,
    ]
}

/// The parameters' delete-a-block jackknife standard errors: steps close in time share
/// their errors (a SLAM submap, a stretch of slipping wheels), which the fit's own
/// covariance, treating every step as independent, does not see. `None` for a parameter a
/// reduced fit could not give.
fn jackknife_sigmas(steps: &[MotionStep]) -> [Option<f64>; 4] {
    let k = JACKKNIFE_BLOCKS;
    let n = steps.len();
    let mut estimates = Vec::new();
    for b in 0..k {
        let (lo, hi) = (b * n / k, (b + 1) * n / k);
        let kept: Vec<MotionStep> = steps[..lo].iter().chain(&steps[hi..]).copied().collect();
        if let Some((u, _)) = fit(&kept) {
            estimates.push(parameters(&u));
        }
    }
    std::array::from_fn(|i| {
        let of: Vec<f64> = estimates.iter().map(|e| e[i]).collect();
        (of.len() == k).then(|| jackknife_sigma(&of, i == 0))
    })
}

/// Estimates the correction from `steps` (see the module docs); `None` with fewer than 10
/// steps or a singular system. Each interval is ±1.96 of the larger of the fit's standard
/// error and the jackknife's. `max_lever_interval_m`: the widest lever-arm interval still
/// reported.
pub fn lidar_odometry(steps: &[MotionStep], max_lever_interval_m: f64) -> Option<LidarOdometry> {
    if steps.len() < 10 {
        return None;
    }
    let all: Vec<([f64; 4], f64)> = steps.iter().flat_map(rows).collect();
    let rms = |u: &[f64; 4]| (all.iter().map(|r| residual(r, u).powi(2)).sum::<f64>() / all.len() as f64).sqrt();
    let (u, cov) = fit(steps)?;
    let p = parameters(&u);
    let model = model_sigmas(&u, &cov);
    let jack = jackknife_sigmas(steps);
    let sigma: [f64; 4] = std::array::from_fn(|i| jack[i].map_or(model[i], |j| j.max(model[i])));
    let lever = [Interval::of(p[2], sigma[2]), Interval::of(p[3], sigma[3])];
    let determined = lever.iter().all(|l| 2.0 * l.half_width() <= max_lever_interval_m);
    Some(LidarOdometry {
        steps: steps.len() as u64,
        turning_steps: steps.iter().filter(|s| s.odometry.theta.abs() > 5f64.to_radians()).count() as u64,
        yaw: Interval::of(normalize_angle(p[0]), sigma[0]),
        lever: determined.then_some(lever),
        scale: Interval::of(p[1], sigma[1]),
        wheel_base: wheel_base(steps, p[1], sigma[1]),
        cost_before_m: rms(&[1.0, 0.0, 0.0, 0.0]),
        cost_after_m: rms(&u),
    })
}

/// Steps turning more than this count for the wheel base, radians.
const TURNING_RAD: f64 = 0.087;

/// [`LidarOdometry::wheel_base`]: κ over the turning steps, its standard error by a
/// delete-a-block jackknife, divided by the scale ρ (its error added in quadrature).
fn wheel_base(steps: &[MotionStep], rho: f64, sigma_rho: f64) -> Option<Interval> {
    let turning: Vec<MotionStep> = steps.iter().copied().filter(|s| s.lidar.theta.abs() > TURNING_RAD).collect();
    let (kappa, _, n) = turn_agreement(&turning)?;
    let k = JACKKNIFE_BLOCKS;
    let reduced: Vec<f64> = (0..k)
        .filter_map(|b| {
            let kept: Vec<MotionStep> =
                turning[..b * n / k].iter().chain(&turning[(b + 1) * n / k..]).copied().collect();
            turn_agreement(&kept).map(|t| t.0)
        })
        .collect();
    if reduced.len() < k {
        return None;
    }
    let sigma_kappa = jackknife_sigma(&reduced, false);
    if !(rho > 0.0 && kappa > 0.0) {
        return None; // no turning the odometry agrees with in sign: nothing to scale
    }
    let ratio = kappa / rho;
    let sigma = ((sigma_kappa / rho).powi(2) + (kappa * sigma_rho / (rho * rho)).powi(2)).sqrt();
    ratio.is_finite().then(|| Interval::of(ratio, sigma))
}

/// How the odometry's turning agrees with SLAM's: `κ`, the least-squares ratio of the
/// odometry's rotation to SLAM's over the steps (a wheel-base error scales every turn the
/// wheels report), and the cost `Σ (θ_odometry − κ θ_SLAM)²` with the number of steps.
/// Rotation alone does not depend on the mount's lever arm or the wheels' scale, so this
/// cost is the criterion of a clock-offset search: shifted in time, the two tracks' turns
/// stop lining up.
pub fn turn_agreement(steps: &[MotionStep]) -> Option<(f64, f64, usize)> {
    if steps.len() < 10 {
        return None;
    }
    let (sxy, sxx) = steps
        .iter()
        .fold((0.0, 0.0), |(xy, xx), s| (xy + s.odometry.theta * s.lidar.theta, xx + s.lidar.theta * s.lidar.theta));
    if sxx < 1e-9 {
        return None;
    }
    let kappa = sxy / sxx;
    let cost = steps.iter().map(|s| (s.odometry.theta - kappa * s.lidar.theta).powi(2)).sum();
    Some((kappa, cost, steps.len()))
}

/// Cuts two tracks sampled at the same instants, `(odometry, lidar)`, into steps: from
/// each step's start, the first sample at least `step_m` away or `step_rad` turned along
/// the lidar's track. The cuts depend on the lidar's poses alone, so the odometry read at
/// shifted instants (a clock-offset search) gives the same steps.
pub fn steps_of(pairs: &[(Pose2, Pose2)], step_m: f64, step_rad: f64) -> Vec<MotionStep> {
    let mut out = Vec::new();
    let mut a = 0;
    for j in 1..pairs.len() {
        let lidar = pairs[a].1.inverse() * pairs[j].1;
        if lidar.x.hypot(lidar.y) < step_m && lidar.theta.abs() < step_rad {
            continue;
        }
        out.push(MotionStep { odometry: pairs[a].0.inverse() * pairs[j].0, lidar });
        a = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A drive of straight legs and turns both ways.
    fn drive() -> Vec<Pose2> {
        let mut p = Pose2::new(0.0, 0.0, 0.0);
        let mut out = vec![p];
        for k in 0..600 {
            let turn = match k % 50 {
                0..=29 => 0.0,
                30..=39 => 0.2,
                _ => -0.15,
            };
            p = p * Pose2::new(0.08, 0.0, turn);
            out.push(p);
        }
        out
    }

    proptest! {
        /// A SLAM track that is the true one composed with a constant Δ, and odometry that
        /// is the true one with its translations scaled: Δ and the scale come back.
        #[test]
        fn recovers_the_mount_error_and_the_scale(yaw_deg in -5.0f64..5.0, x in -0.1f64..0.1, y in -0.1f64..0.1, scale in 0.95f64..1.05) {
            let truth = drive();
            let delta = Pose2::new(x, y, yaw_deg.to_radians());
            let pairs: Vec<(Pose2, Pose2)> = truth.iter().map(|&b| (b, b * delta)).collect();
            let mut steps = steps_of(&pairs, 0.3, 0.2);
            for s in &mut steps {
                s.odometry.x *= scale;
                s.odometry.y *= scale;
            }
            let c = lidar_odometry(&steps, 0.05).unwrap();
            prop_assert!((c.yaw.value - yaw_deg.to_radians()).abs() < 1e-6, "{c:?}");
            prop_assert!((c.scale.value - scale).abs() < 1e-6, "{c:?}");
            let lever = c.lever.unwrap();
            prop_assert!((lever[0].value - x).abs() < 1e-6 && (lever[1].value - y).abs() < 1e-6, "{c:?}");
            prop_assert!(c.cost_after_m <= c.cost_before_m);
            // Turns untouched while distances scale: the odometry assumes a base `scale`
            // times too large for its wheels: the true base is 1 / scale of the one assumed.
            prop_assert!((c.wheel_base.unwrap().value - 1.0 / scale).abs() < 1e-6, "{c:?}");
        }
    }

    #[test]
    fn a_straight_drive_leaves_the_lever_arm_undetermined() {
        let truth: Vec<Pose2> = (0..300).map(|k| Pose2::new(0.05 * k as f64, 0.0, 0.0)).collect();
        let delta = Pose2::new(0.05, 0.0, 0.03);
        // A little noise, as any real pair of tracks has.
        let pairs: Vec<(Pose2, Pose2)> = truth
            .iter()
            .enumerate()
            .map(|(k, &b)| {
                (b, b * delta * Pose2::new(0.001 * ((k * 7) % 5) as f64, 0.0, 0.0002 * ((k * 3) % 4) as f64))
            })
            .collect();
        let c = lidar_odometry(&steps_of(&pairs, 0.3, 0.2), 0.05).unwrap();
        assert!(c.lever.is_none(), "{c:?}");
        assert!((c.yaw.value - 0.03).abs() < 0.01, "{c:?}");
    }
}
