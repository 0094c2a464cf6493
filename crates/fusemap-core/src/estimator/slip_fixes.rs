//! Slip seen by the fixes: the distance the odometry claims (times the estimated scale)
//! against the distance precise fixes moved over the same short window.
//!
//! The gyro check (`streams.rs`) sees slip only when the wheels also disagree on the yaw;
//! spinning wheels on a straight line mostly add distance, which precise fixes see at once
//! (a ×1.5 slip at 0.8 m/s is 0.4 m per second against centimetre fixes). Offline, the fixes
//! on both sides of an increment are known before the filter predicts it. Only fixes
//! precise enough to judge (largest σ ≤ `slip_fix_max_sigma_m`) take part, and both halves
//! of the window must agree on the excess, so one wrong fix cannot declare a slip.

use super::config::EstimatorConfig;
use super::filter::N;
use super::input::Correction;
use super::linalg::Mat;
use super::streams::OdometryTrack;
use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::time::Stamp;

/// Precise fixes for the slip check.
pub(crate) struct FixSlipCheck {
    stamps: Vec<Stamp>,
    z: Vec<[f64; 2]>,
    antenna: Vec<Point2>,
    var: Vec<f64>,
    /// The odometry pose at each fix, looked up once.
    odo: Vec<Pose2>,
    half_window_ns: i64,
    k: f64,
    translation_var_per_m: f64,
}

impl FixSlipCheck {
    pub fn new(corrections: &[(Stamp, Correction)], odo: &OdometryTrack, cfg: &EstimatorConfig) -> Self {
        let mut s = Self {
            stamps: Vec::new(),
            z: Vec::new(),
            antenna: Vec::new(),
            var: Vec::new(),
            odo: Vec::new(),
            half_window_ns: (cfg.slip_fix_window_s * 0.5e9) as i64,
            k: cfg.slip_sigma,
            translation_var_per_m: cfg.odometry_translation_noise.powi(2),
        };
        for (t, c) in corrections {
            if let Correction::Position { z, r, antenna, .. } = c {
                let max_var = r[0][0].max(r[1][1]);
                if max_var <= cfg.slip_fix_max_sigma_m.powi(2) && s.stamps.last() != Some(t) && odo.contains(*t) {
                    s.odo.push(odo.pose_at(*t));
                    s.stamps.push(*t);
                    s.z.push(*z);
                    s.antenna.push(*antenna);
                    s.var.push(0.5 * (r[0][0] + r[1][1]));
                }
            }
        }
        s
    }

    /// The base position of fix `j`, its lever arm removed with the filter's heading
    /// carried to the fix's stamp by the odometry (`odo_theta_now`: the odometry heading at
    /// the filter's stamp).
    fn base(&self, j: usize, x: &[f64; N], odo_theta_now: f64) -> [f64; 2] {
        let dtheta = normalize_angle(self.odo[j].theta - odo_theta_now);
        let (s, c) = (x[2] + dtheta).sin_cos();
        let a = self.antenna[j];
        [self.z[j][0] - (c * a.x - s * a.y), self.z[j][1] - (s * a.x + c * a.y)]
    }

    /// (excess distance of the fixes over the scaled odometry, its variance) between fixes `a` and `b`.
    fn excess(&self, a: usize, b: usize, x: &[f64; N], p: &Mat<N, N>, odo_theta_now: f64) -> (f64, f64) {
        let (ba, bb) = (self.base(a, x, odo_theta_now), self.base(b, x, odo_theta_now));
        let fix_d = (bb[0] - ba[0]).hypot(bb[1] - ba[1]);
        let odo_d = self.odo[a].translation().distance(self.odo[b].translation());
        let var = self.var[a] + self.var[b] + self.translation_var_per_m * odo_d + p[4][4] * odo_d * odo_d + 1e-4;
        (fix_d - x[4] * odo_d, var)
    }

    /// True when the precise fixes in the window centred at `centre` show the odometry
    /// distance off by more than `slip_sigma` standard deviations, both halves agreeing.
    fn window_slips(&self, centre: Stamp, x: &[f64; N], p: &Mat<N, N>, odo_theta_now: f64) -> bool {
        let lo = self.stamps.partition_point(|&s| s.0 < centre.0 - self.half_window_ns);
        let hi = self.stamps.partition_point(|&s| s.0 <= centre.0 + self.half_window_ns);
        if hi < lo + 3 {
            return false;
        }
        let (first, last) = (lo, hi - 1);
        if self.stamps[last].0 - self.stamps[first].0 < self.half_window_ns {
            return false;
        }
        let mid = (first + last) / 2;
        let (e, v) = self.excess(first, last, x, p, odo_theta_now);
        let (e1, v1) = self.excess(first, mid, x, p, odo_theta_now);
        let (e2, v2) = self.excess(mid, last, x, p, odo_theta_now);
        e * e > self.k * self.k * v && e1 * e > 0.0 && e2 * e > 0.0 && e1 * e1 > v1 && e2 * e2 > v2
    }

    /// True when the odometry increment `[a, b]` slips by the fixes (windows centred on it
    /// and half a window either side, so the flag covers the whole burst).
    pub fn slips(&self, a: Stamp, b: Stamp, odo: &OdometryTrack, x: &[f64; N], p: &Mat<N, N>) -> bool {
        if self.stamps.len() < 3 {
            return false;
        }
        let c = Stamp(a.0 + (b.0 - a.0) / 2);
        // Quick exit: no precise fix near the increment.
        let lo = self.stamps.partition_point(|&s| s.0 < c.0 - 2 * self.half_window_ns);
        if self.stamps.get(lo).is_none_or(|s| s.0 > c.0 + 2 * self.half_window_ns) {
            return false;
        }
        let odo_theta_now = odo.pose_at(a).theta;
        [c, Stamp(c.0 - self.half_window_ns), Stamp(c.0 + self.half_window_ns)]
            .into_iter()
            .any(|w| self.window_slips(w, x, p, odo_theta_now))
    }
}
