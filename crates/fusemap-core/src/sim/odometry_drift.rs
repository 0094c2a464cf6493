//! Wheel odometry made from a reference trajectory with a known error model: how a test
//! bench turns a corrected log (poses known to centimetres) into a raw one whose drift is
//! known.
//!
//! The model is the usual one for differential-drive odometry (Borenstein & Feng 1996,
//! "Measurement and correction of systematic odometry errors"; Thrun et al.,
//! *Probabilistic Robotics*, §5.4): each increment of the reference, in the frame of the
//! previous pose, is
//!
//! - **scaled** by `1 + scale_error` (a wrong wheel diameter),
//! - **turned** by `heading_bias_rad_per_m` per metre driven (unequal wheel diameters:
//!   the systematic heading drift),
//! - **turned** further by a heading random walk of `heading_random_walk_rad_per_sqrt_m`
//!   per √m (uneven floors),
//! - and **jittered** by white noise: σ `translation_noise_m_per_sqrt_m` per √m on x and y,
//!   `rotation_noise_ratio` of the increment's own turn on θ.
//!
//! Every term scales with the distance (or the turn) of the increment, and variances add
//! along the path, so the drift does not depend on how often the log samples its poses.
//! The corrupted increments are integrated from the reference's first pose.

use super::rng::SplitMix64;
use crate::geometry::Pose2;

/// The error of a simulated wheel odometry (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OdometryErrorModel {
    /// Relative error of every distance driven (0.03: 3 % long).
    pub scale_error: f64,
    /// Heading error added per metre driven, radians.
    pub heading_bias_rad_per_m: f64,
    /// σ of the heading random walk, radians per √m.
    pub heading_random_walk_rad_per_sqrt_m: f64,
    /// σ of the white noise on each increment's translation, metres per √m driven.
    pub translation_noise_m_per_sqrt_m: f64,
    /// σ of the white noise on each increment's turn, as a share of the turn.
    pub rotation_noise_ratio: f64,
}

impl OdometryErrorModel {
    /// No error at all: the odometry is the reference (the control of a test bench).
    pub const ZERO: Self = Self {
        scale_error: 0.0,
        heading_bias_rad_per_m: 0.0,
        heading_random_walk_rad_per_sqrt_m: 0.0,
        translation_noise_m_per_sqrt_m: 0.0,
        rotation_noise_ratio: 0.0,
    };

    /// Mild drift: 1 % scale, 0.2°/m heading bias, 0.05°/√m random walk, a little noise.
    pub fn mild() -> Self {
        Self {
            scale_error: 0.01,
            heading_bias_rad_per_m: 0.2f64.to_radians(),
            heading_random_walk_rad_per_sqrt_m: 0.05f64.to_radians(),
            translation_noise_m_per_sqrt_m: 0.005,
            rotation_noise_ratio: 0.01,
        }
    }

    /// Strong drift: 3 % scale, 1°/m heading bias, 0.3°/√m random walk, more noise.
    pub fn strong() -> Self {
        Self {
            scale_error: 0.03,
            heading_bias_rad_per_m: 1f64.to_radians(),
            heading_random_walk_rad_per_sqrt_m: 0.3f64.to_radians(),
            translation_noise_m_per_sqrt_m: 0.01,
            rotation_noise_ratio: 0.02,
        }
    }

    /// `reference` as this odometry would have measured it, from `seed`: the same first
    /// pose, then every increment corrupted and integrated. The zero model returns the
    /// reference's increments integrated, equal to it up to rounding.
    pub fn corrupt(&self, reference: &[Pose2], seed: u64) -> Vec<Pose2> {
        let mut rng = SplitMix64::new(seed);
        let mut out = Vec::with_capacity(reference.len());
        let Some(&first) = reference.first() else { return out };
        out.push(first);
        let mut pose = first;
        for w in reference.windows(2) {
            let d = w[0].inverse().compose(w[1]);
            let length = d.x.hypot(d.y);
            let sqrt_l = length.sqrt();
            let k = 1.0 + self.scale_error;
            let x = d.x * k + rng.normal(0.0, self.translation_noise_m_per_sqrt_m * sqrt_l);
            let y = d.y * k + rng.normal(0.0, self.translation_noise_m_per_sqrt_m * sqrt_l);
            let theta = d.theta
                + self.heading_bias_rad_per_m * length
                + rng.normal(0.0, self.heading_random_walk_rad_per_sqrt_m * sqrt_l)
                + rng.normal(0.0, self.rotation_noise_ratio * d.theta.abs());
            pose = pose.compose(Pose2::new(x, y, theta));
            out.push(pose);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(n: usize, step: f64) -> Vec<Pose2> {
        (0..n).map(|k| Pose2::new(k as f64 * step, 0.0, 0.0)).collect()
    }

    #[test]
    fn zero_drift_is_the_reference_and_drift_grows_as_modelled() {
        let truth: Vec<Pose2> = (0..200)
            .map(|k| Pose2::new((k as f64 * 0.1).cos() * 5.0, (k as f64 * 0.1).sin() * 5.0, k as f64 * 0.1))
            .collect();
        let same = OdometryErrorModel::ZERO.corrupt(&truth, 1);
        for (a, b) in same.iter().zip(&truth) {
            assert!((a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9);
        }
        // Scale alone: 100 m driven straight ends 3 m long.
        let line = straight(101, 1.0);
        let m = OdometryErrorModel { scale_error: 0.03, ..OdometryErrorModel::ZERO };
        let end = *m.corrupt(&line, 1).last().unwrap();
        assert!((end.x - 103.0).abs() < 1e-9 && end.y.abs() < 1e-9);
        // Heading bias alone: 1°/m over 10 m is 10° of heading, whatever the sampling.
        let m = OdometryErrorModel { heading_bias_rad_per_m: 1f64.to_radians(), ..OdometryErrorModel::ZERO };
        for step in [0.1, 0.5, 1.0] {
            let line = straight((10.0 / step) as usize + 1, step);
            let end = *m.corrupt(&line, 1).last().unwrap();
            assert!((end.theta.to_degrees() - 10.0).abs() < 1e-6, "{step}: {}", end.theta.to_degrees());
        }
    }

    #[test]
    fn the_random_walk_does_not_depend_on_the_sampling() {
        // Heading variance after 100 m: σ² · 100 whatever the step; averaged over seeds.
        let m = OdometryErrorModel { heading_random_walk_rad_per_sqrt_m: 0.01, ..OdometryErrorModel::ZERO };
        for step in [0.25, 1.0] {
            let line = straight((100.0 / step) as usize + 1, step);
            let var: f64 = (0..400).map(|s| m.corrupt(&line, s).last().unwrap().theta.powi(2)).sum::<f64>() / 400.0;
            assert!((var / 0.01 - 1.0).abs() < 0.2, "step {step}: variance {var}");
        }
        assert_eq!(m.corrupt(&straight(10, 1.0), 7), m.corrupt(&straight(10, 1.0), 7), "seeded");
    }
}
