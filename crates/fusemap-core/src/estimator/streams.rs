//! The motion streams as functions of time: the odometry pose and the integrated gyro
//! angle at any stamp, so the filter can stop at any measurement's own stamp (offline, the
//! whole log is known, so the odometry on both sides of a fix is available and the fix
//! needs no extrapolation).

use super::config::EstimatorConfig;
use super::input::{RawGyro, RawOdometry};
use super::linalg::Mat;
use super::report::OdometryReport;
use crate::geometry::{normalize_angle, Pose2};
use crate::time::Stamp;

/// The index `k` of the segment `[stamps[k], stamps[k + 1]]` holding `t`, clamped to the
/// segments that exist (`stamps` holds at least two entries).
fn segment(stamps: &[Stamp], t: Stamp) -> usize {
    stamps.partition_point(|&s| s <= t).saturating_sub(1).min(stamps.len() - 2)
}

/// One odometry increment, between consecutive messages.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interval {
    /// `base_start_from_base_end`.
    pub delta: Pose2,
    /// Duration, seconds.
    pub dt: f64,
    /// Covariance of (x, y, yaw) of the increment in the base frame at its start.
    pub cov: Mat<3, 3>,
    /// Part of a stretch of standing still long enough for zero-rate updates.
    pub stationary: bool,
}

/// Wheel odometry as a function of time.
pub(crate) struct OdometryTrack {
    pub stamps: Vec<Stamp>,
    pub poses: Vec<Pose2>,
    /// `intervals[i]` lies between `stamps[i]` and `stamps[i + 1]`.
    pub intervals: Vec<Interval>,
}

impl OdometryTrack {
    /// Builds the increments and their noise; `None` with fewer than two messages.
    pub fn build(raw: RawOdometry, cfg: &EstimatorConfig, counts: &mut OdometryReport) -> Option<Self> {
        if raw.stamps.len() < 2 {
            return None;
        }
        let n = raw.stamps.len();
        let mut intervals = Vec::with_capacity(n - 1);
        for i in 1..n {
            let delta = raw.poses[i - 1].inverse().compose(raw.poses[i]);
            let dt = raw.stamps[i].secs_since(raw.stamps[i - 1]);
            let d = delta.x.hypot(delta.y);
            let gap = dt > cfg.max_odometry_gap_s;
            let mut cov = raw.covariances[i].as_deref().copied().unwrap_or_else(|| {
                let vt =
                    cfg.odometry_translation_noise.powi(2) * d + cfg.odometry_translation_noise_per_sqrt_s.powi(2) * dt;
                let vr = cfg.odometry_rotation_noise_per_rad.powi(2) * delta.theta.abs()
                    + cfg.odometry_rotation_noise_per_m.powi(2) * d;
                [[vt, 0.0, 0.0], [0.0, vt, 0.0], [0.0, 0.0, vr]]
            });
            if gap {
                // Encoders count through a gap in the messages, so the increment as a whole
                // is still measured; what is unknown is the path inside it, which a stamp
                // inside the gap interpolates. That error is bounded by the motion across
                // the gap (none when standing still) and by the speed uncertainty.
                counts.gaps += 1;
                let extra = (cfg.gap_speed_sigma_mps * dt).min(d).powi(2);
                cov[0][0] += extra;
                cov[1][1] += extra;
            }
            let still = d <= cfg.stationary_max_speed_mps * dt && delta.theta.abs() <= cfg.stationary_max_rate * dt;
            intervals.push(Interval { delta, dt, cov, stationary: still });
        }
        // Only runs of standing still lasting stationary_min_s count: a single quiet
        // increment at low speed is not a stop.
        let mut i = 0;
        while i < intervals.len() {
            if !intervals[i].stationary {
                i += 1;
                continue;
            }
            let mut j = i;
            let mut duration = 0.0;
            while j < intervals.len() && intervals[j].stationary {
                duration += intervals[j].dt;
                j += 1;
            }
            if duration < cfg.stationary_min_s || j == i {
                for iv in &mut intervals[i..j.max(i + 1)] {
                    iv.stationary = false;
                }
            }
            i = j.max(i + 1);
        }
        Some(Self { stamps: raw.stamps, poses: raw.poses, intervals })
    }

    /// The first and last stamp.
    pub fn span(&self) -> (Stamp, Stamp) {
        (self.stamps[0], self.stamps[self.stamps.len() - 1])
    }

    /// True when `t` lies inside the track.
    pub fn contains(&self, t: Stamp) -> bool {
        let (a, b) = self.span();
        t >= a && t <= b
    }

    /// The odometry pose at `t` (linear interpolation; clamped to the track).
    pub fn pose_at(&self, t: Stamp) -> Pose2 {
        let k = segment(&self.stamps, t);
        let (t0, t1) = (self.stamps[k], self.stamps[k + 1]);
        let f = ((t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64).clamp(0.0, 1.0);
        self.poses[k].interpolate(self.poses[k + 1], f)
    }
}

/// The gyro's integrated angle and its variance as functions of time.
pub(crate) struct GyroTrack {
    stamps: Vec<Stamp>,
    /// ∫ω dt up to each sample (trapezoid rule), radians.
    angle: Vec<f64>,
    /// Variance of that integral, rad².
    variance: Vec<f64>,
    /// Number of gap segments before each sample.
    gaps_before: Vec<u32>,
}

impl GyroTrack {
    /// `None` with fewer than two samples.
    pub fn build(raw: RawGyro, cfg: &EstimatorConfig) -> Option<Self> {
        let n = raw.stamps.len();
        if n < 2 {
            return None;
        }
        let (mut angle, mut variance, mut gaps_before) = (vec![0.0; n], vec![0.0; n], vec![0u32; n]);
        for k in 1..n {
            let h = raw.stamps[k].secs_since(raw.stamps[k - 1]);
            let gap = h > cfg.max_gyro_gap_s;
            angle[k] = angle[k - 1] + 0.5 * (raw.rates[k - 1] + raw.rates[k]) * h;
            variance[k] = variance[k - 1] + 0.5 * (raw.variances[k - 1] + raw.variances[k]) * h * h;
            gaps_before[k] = gaps_before[k - 1] + gap as u32;
        }
        Some(Self { stamps: raw.stamps, angle, variance, gaps_before })
    }

    fn at(&self, t: Stamp, k: usize) -> (f64, f64) {
        let (t0, t1) = (self.stamps[k], self.stamps[k + 1]);
        let f = ((t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64).clamp(0.0, 1.0);
        (
            self.angle[k] + f * (self.angle[k + 1] - self.angle[k]),
            self.variance[k] + f * (self.variance[k + 1] - self.variance[k]),
        )
    }

    /// ∫ω dt over `[a, b]` (raw rates, bias not removed) and its variance, or `None` when
    /// the gyro does not cover the whole interval without a gap.
    pub fn integral(&self, a: Stamp, b: Stamp) -> Option<(f64, f64)> {
        let n = self.stamps.len();
        if a < self.stamps[0] || b > self.stamps[n - 1] || b < a {
            return None;
        }
        let (ka, kb) = (segment(&self.stamps, a), segment(&self.stamps, b));
        let kb = if kb > ka && self.stamps[kb] == b { kb - 1 } else { kb };
        if self.gaps_before[kb + 1] != self.gaps_before[ka] {
            return None;
        }
        let (ga, va) = self.at(a, ka);
        let (gb, vb) = self.at(b, kb);
        Some((gb - ga, (vb - va).max(0.0)))
    }
}

/// Slip detection: the odometry heading increment compared with the bias-corrected gyro
/// over a sliding window. Over one window `D = Σ(Δθ_odo − Δθ_gyro) + b Σ dt` has
/// variance `V = Σ(σ²_odo + σ²_gyro)`; `D² > k² V` means the wheels and the gyro disagree
/// beyond their noise, and the wheels are the ones that slip (a gyro does not).
pub(crate) struct SlipDetector {
    mids: Vec<f64>,
    prefix_d: Vec<f64>,
    prefix_dt: Vec<f64>,
    prefix_v: Vec<f64>,
    prefix_uncovered: Vec<u32>,
    half_window: f64,
    k2: f64,
}

impl SlipDetector {
    pub fn new(odo: &OdometryTrack, gyro: Option<&GyroTrack>, cfg: &EstimatorConfig) -> Self {
        let m = odo.intervals.len();
        let t0 = odo.stamps[0];
        let mut s = Self {
            mids: Vec::with_capacity(m),
            prefix_d: vec![0.0; m + 1],
            prefix_dt: vec![0.0; m + 1],
            prefix_v: vec![0.0; m + 1],
            prefix_uncovered: vec![0; m + 1],
            half_window: 0.5 * cfg.slip_window_s,
            k2: cfg.slip_sigma * cfg.slip_sigma,
        };
        for (i, iv) in odo.intervals.iter().enumerate() {
            let (a, b) = (odo.stamps[i], odo.stamps[i + 1]);
            s.mids.push(0.5 * (a.secs_since(t0) + b.secs_since(t0)));
            let g = gyro.and_then(|g| g.integral(a, b));
            let (d, v, unc) = match g {
                Some((g, vg)) => (normalize_angle(iv.delta.theta - g), iv.cov[2][2] + vg, 0),
                None => (0.0, 0.0, 1),
            };
            s.prefix_d[i + 1] = s.prefix_d[i] + d;
            s.prefix_dt[i + 1] = s.prefix_dt[i] + iv.dt;
            s.prefix_v[i + 1] = s.prefix_v[i] + v;
            s.prefix_uncovered[i + 1] = s.prefix_uncovered[i] + unc;
        }
        s
    }

    /// True when the window of intervals centred at `centre` (seconds from the track
    /// start) shows slip under bias `bias`; false when it cannot tell (no gyro).
    fn window_slips(&self, centre: f64, bias: f64) -> bool {
        let lo = self.mids.partition_point(|&m| m < centre - self.half_window);
        let hi = self.mids.partition_point(|&m| m <= centre + self.half_window);
        if hi <= lo || self.prefix_uncovered[hi] != self.prefix_uncovered[lo] {
            return false;
        }
        let d = self.prefix_d[hi] - self.prefix_d[lo] + bias * (self.prefix_dt[hi] - self.prefix_dt[lo]);
        let v = self.prefix_v[hi] - self.prefix_v[lo];
        d * d > self.k2 * v
    }

    /// True when interval `i` slips: any window centred within half a window of it
    /// disagrees, so the flag covers the whole burst and not only its middle.
    pub fn slips(&self, i: usize, bias: f64) -> bool {
        let c = self.mids[i];
        [c, c - self.half_window, c + self.half_window].into_iter().any(|c| self.window_slips(c, bias))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(sec: f64) -> Stamp {
        Stamp::from_secs_f64(sec).unwrap()
    }

    #[test]
    fn gyro_integral_is_exact_for_piecewise_linear_rates_and_refuses_gaps() {
        let stamps: Vec<Stamp> = [0.0, 0.01, 0.02, 0.03, 0.5, 0.51].iter().map(|&t| s(t)).collect();
        let raw = RawGyro { stamps, rates: vec![1.0; 6], variances: vec![1e-4; 6] };
        let g = GyroTrack::build(raw, &EstimatorConfig::default()).unwrap();
        let (a, v) = g.integral(s(0.005), s(0.025)).unwrap();
        assert!((a - 0.02).abs() < 1e-12, "{a}");
        assert!(v > 0.0);
        assert!(g.integral(s(0.0), s(0.03)).is_some());
        assert!(g.integral(s(0.02), s(0.505)).is_none(), "crosses the 0.47 s gap");
        assert!(g.integral(s(-0.1), s(0.01)).is_none());
        assert!(g.integral(s(0.50), s(0.51)).is_some());
    }

    #[test]
    fn standing_still_needs_a_long_enough_run() {
        let cfg = EstimatorConfig::default();
        // 1 s still, 0.2 s moving, 0.3 s still, then moving.
        let mut stamps = Vec::new();
        let mut poses = Vec::new();
        let mut x = 0.0;
        for i in 0..=100 {
            let t = i as f64 * 0.02;
            let moving = (1.0..1.2).contains(&t) || t >= 1.5;
            if moving {
                x += 0.02;
            }
            stamps.push(s(t));
            poses.push(Pose2::new(x, 0.0, 0.0));
        }
        let covariances = vec![None; stamps.len()];
        let odo =
            OdometryTrack::build(RawOdometry { stamps, poses, covariances }, &cfg, &mut Default::default()).unwrap();
        assert!(odo.intervals[10].stationary);
        assert!(!odo.intervals[55].stationary);
        assert!(!odo.intervals[65].stationary, "0.3 s is shorter than stationary_min_s");
    }
}
