//! A small synthetic drive for the estimator's tests: a unicycle robot on straight legs,
//! turns and stops, with wheel odometry (scale error, noise, slip bursts), a biased gyro and
//! RTK fixes (good zones, degraded zones with correlated errors and unreported outliers, a
//! dropout). Exact ground truth at every odometry stamp.

use super::input::{EstimatorInput, FixQuality};
use crate::geometry::{Point2, Pose2};
use crate::sim::SplitMix64;
use crate::time::Stamp;

/// A standard normal sample (Box–Muller).
pub(crate) fn gaussian(rng: &mut SplitMix64) -> f64 {
    let u1 = rng.next_f64().max(1e-300);
    let u2 = rng.next_f64();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// What was simulated.
pub(crate) struct Drive {
    pub inputs: Vec<EstimatorInput>,
    /// True `map_from_base` at each odometry stamp.
    pub truth: Vec<(Stamp, Pose2)>,
    /// Raw odometry at each odometry stamp.
    pub odometry: Vec<Pose2>,
    /// Stamps of the injected outlier fixes.
    pub outlier_fixes: Vec<Stamp>,
    /// Stamps of every other fix.
    pub good_fixes: Vec<Stamp>,
    /// Slip bursts: (start, end), seconds. The wheels spin (distance ×1.5–2) and one side
    /// skids (a yaw-rate error of 0.2–0.4 rad/s).
    pub slips: Vec<(f64, f64)>,
    /// The RTK dropout, seconds.
    pub dropout: (f64, f64),
    pub gyro_bias: f64,
    /// True distance = scale × odometry distance.
    pub odometry_scale: f64,
}

/// The drive's parameters.
pub(crate) struct DriveSpec {
    /// (duration s, speed m/s, yaw rate rad/s) legs.
    pub legs: Vec<(f64, f64, f64)>,
    pub odometry_hz: f64,
    pub gyro_hz: f64,
    pub fix_hz: f64,
    pub seed: u64,
    pub start: Pose2,
    pub antenna: Point2,
}

impl DriveSpec {
    /// ≈ 122 s: a stop at the start and one in the middle, straight legs and turns.
    pub fn standard(seed: u64) -> Self {
        let legs = vec![
            (3.0, 0.0, 0.0),
            (20.0, 0.8, 0.0),
            (2.6, 0.5, 0.6),
            (15.0, 1.0, 0.0),
            (4.0, 0.5, -0.4),
            (10.0, 0.8, 0.0),
            (3.0, 0.0, 0.0),
            (8.0, 0.6, 0.3),
            (20.0, 0.9, 0.0),
            (3.0, 0.5, 0.7),
            (15.0, 0.8, 0.0),
            (6.0, 0.7, -0.25),
            (12.0, 1.0, 0.0),
        ];
        Self {
            legs,
            odometry_hz: 50.0,
            gyro_hz: 100.0,
            fix_hz: 5.0,
            seed,
            start: Pose2::new(12.0, -7.0, 0.9),
            antenna: Point2::new(-0.4, 0.15),
        }
    }

    /// The standard legs repeated to last about `seconds`.
    pub fn long(seed: u64, seconds: f64) -> Self {
        let mut spec = Self::standard(seed);
        let once: Vec<_> = spec.legs[1..].to_vec();
        while spec.legs.iter().map(|l| l.0).sum::<f64>() < seconds {
            spec.legs.extend_from_slice(&once);
        }
        spec
    }
}

/// The velocity command at time `t`.
fn command(legs: &[(f64, f64, f64)], t: f64) -> (f64, f64) {
    let mut start = 0.0;
    for &(d, v, w) in legs {
        if t < start + d {
            return (v, w);
        }
        start += d;
    }
    (0.0, 0.0)
}

/// Exact unicycle motion over `dt` from `p`.
fn advance(p: Pose2, v: f64, w: f64, dt: f64) -> Pose2 {
    let dtheta = w * dt;
    let (dx, dy) =
        if dtheta.abs() < 1e-9 { (v * dt, 0.0) } else { (v / w * dtheta.sin(), v / w * (1.0 - dtheta.cos())) };
    p.compose(Pose2::new(dx, dy, dtheta))
}

/// Simulates the drive.
pub(crate) fn simulate(spec: &DriveSpec) -> Drive {
    let mut rng = SplitMix64::new(spec.seed);
    let duration: f64 = spec.legs.iter().map(|l| l.0).sum();
    let gyro_bias = 0.015;
    let odometry_gain = 1.03; // odometry reports 3 % more than the true distance
    let total = duration;
    let slips = vec![
        (0.13 * total, 0.13 * total + 2.0),
        (0.42 * total, 0.42 * total + 2.0),
        (0.78 * total, 0.78 * total + 2.0),
    ];
    let degraded = [(0.33 * total, 0.45 * total), (0.66 * total, 0.76 * total)];
    let dropout = (0.50 * total, 0.50 * total + 12.0);
    let slip_at = |t: f64| slips.iter().position(|&(a, b)| t >= a && t < b);
    let slip_gain: Vec<f64> = slips.iter().map(|_| rng.uniform(1.5, 2.0)).collect();
    let slip_yaw: Vec<f64> =
        slips.iter().map(|_| rng.uniform(0.2, 0.4) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 }).collect();

    // Truth on a fine clock (the gyro's), odometry and fixes on theirs.
    let dt = 1.0 / spec.gyro_hz;
    let steps = (duration * spec.gyro_hz).round() as usize;
    let odo_every = (spec.gyro_hz / spec.odometry_hz).round() as usize;
    let fix_every = (spec.gyro_hz / spec.fix_hz).round() as usize;
    let mut inputs = Vec::new();
    let mut truth = Vec::new();
    let mut odometry = Vec::new();
    let (mut outlier_fixes, mut good_fixes) = (Vec::new(), Vec::new());
    let mut pose = spec.start;
    let mut odom = Pose2::new(3.0, 4.0, -0.2);
    let mut last_odo_truth = pose;
    let mut corr = [0.0f64; 2];
    let corr_tau = 3.0;
    let corr_sigma = 0.35;
    let stamp = |i: usize| Stamp(1_700_000_000_000_000_000 + (i as i64) * (1e9 / spec.gyro_hz) as i64);
    // The robot follows its commands through a first-order lag (0.5 s): speed and turn
    // rate ramp instead of jumping.
    let lag = (-dt / 0.5f64).exp();
    let (mut v, mut w) = (0.0, 0.0);
    for i in 0..=steps {
        let t = i as f64 * dt;
        let (vc, wc) = command(&spec.legs, t);
        v = lag * v + (1.0 - lag) * vc;
        w = lag * w + (1.0 - lag) * wc;
        // Gyro.
        inputs.push(EstimatorInput::Gyro {
            stamp: stamp(i),
            yaw_rate: w + gyro_bias + 0.005 * gaussian(&mut rng),
            variance: Some(0.005f64.powi(2)),
        });
        if i % odo_every == 0 {
            if i > 0 {
                let inc = last_odo_truth.inverse().compose(pose);
                let d = inc.x.hypot(inc.y);
                let mut ox = inc.x * odometry_gain;
                let mut oy = inc.y * odometry_gain;
                let mut oth = inc.theta;
                if d > 0.0 || inc.theta.abs() > 0.0 {
                    ox += 0.005 * d.sqrt() * gaussian(&mut rng);
                    oy += 0.005 * d.sqrt() * gaussian(&mut rng);
                    oth += (0.005 * d.sqrt() + 0.01 * inc.theta.abs().sqrt()) * gaussian(&mut rng);
                }
                if let Some(k) = slip_at(t) {
                    ox *= slip_gain[k];
                    oy *= slip_gain[k];
                    oth += slip_yaw[k] * (odo_every as f64 * dt);
                }
                odom = odom.compose(Pose2::new(ox, oy, oth));
            }
            last_odo_truth = pose;
            inputs.push(EstimatorInput::Odometry { stamp: stamp(i), pose: odom, covariance: None });
            truth.push((stamp(i), pose));
            odometry.push(odom);
        }
        // Correlated fix error: first-order Gauss–Markov.
        let a = (-dt / corr_tau).exp();
        for c in &mut corr {
            *c = a * *c + corr_sigma * (1.0 - a * a).sqrt() * gaussian(&mut rng);
        }
        if i % fix_every == 0 && !(t >= dropout.0 && t < dropout.1) {
            let antenna = pose.transform_point(spec.antenna);
            let in_degraded = degraded.iter().any(|&(a, b)| t >= a && t < b);
            let (err, sigma, quality, outlier) = if in_degraded {
                if rng.next_f64() < 0.15 {
                    let r = rng.uniform(3.0, 10.0);
                    let ang = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI);
                    ([r * ang.cos(), r * ang.sin()], 0.7, FixQuality::Fix, true)
                } else {
                    (corr, 0.7, FixQuality::Fix, false)
                }
            } else {
                ([0.02 * gaussian(&mut rng), 0.02 * gaussian(&mut rng)], 0.025, FixQuality::RtkFixed, false)
            };
            if outlier {
                outlier_fixes.push(stamp(i));
            } else {
                good_fixes.push(stamp(i));
            }
            inputs.push(EstimatorInput::Position {
                stamp: stamp(i),
                enu: [antenna.x + err[0], antenna.y + err[1]],
                covariance: [[sigma * sigma, 0.0], [0.0, sigma * sigma]].into(),
                antenna: spec.antenna,
                quality,
            });
        }
        pose = advance(pose, v, w, dt);
    }
    Drive {
        inputs,
        truth,
        odometry,
        outlier_fixes,
        good_fixes,
        slips,
        dropout,
        gyro_bias,
        odometry_scale: 1.0 / odometry_gain,
    }
}
