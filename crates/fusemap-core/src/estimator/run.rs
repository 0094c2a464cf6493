//! The forward pass: the filter stepped through the log, stopping at every odometry
//! stamp (the track's samples) and at every correction's own stamp.

use super::chi2::chi_square_quantile;
use super::config::EstimatorConfig;
use super::error::EstimatorError;
use super::filter::{predict, update, update_weighted, Gated, HeadingMotion, Motion, StepRecord, N};
use super::init::Init;
use super::input::{Correction, FixQuality};
use super::linalg::{all_finite, identity, spd_inverse, Mat};
use super::models;
use super::report::{CorrectionReport, FixQualityCount, FixRejection, RejectedFix};
use super::slip_fixes::FixSlipCheck;
use super::streams::{GyroTrack, Interval, OdometryTrack, SlipDetector};
use crate::geometry::Pose2;
use crate::time::Stamp;

/// What the forward pass counts.
#[derive(Clone)]
pub(crate) struct RunCounts {
    pub fixes: CorrectionReport,
    pub poses: CorrectionReport,
    pub headings: CorrectionReport,
    pub zero_rate: CorrectionReport,
    pub by_quality: Vec<FixQualityCount>,
    pub rejected_fixes: Vec<RejectedFix>,
    pub gate_resets: usize,
    pub gate_resets_refused: usize,
    pub stationary_s: f64,
    pub steps_without_gyro: usize,
}

/// The forward pass's result.
pub(crate) struct RunOutput {
    /// The records of the steps the pass was asked to keep.
    pub records: Vec<StepRecord>,
    /// Per odometry interval: flagged as slipping (from the pass's start on).
    pub slip: Vec<bool>,
    /// Steps of the whole pass.
    pub steps: usize,
    /// The checkpoints it was asked for ([`Pass::checkpoint_every`]), in step order.
    pub checkpoints: Vec<Checkpoint>,
}

/// What one forward pass keeps and where it starts.
pub(crate) struct Pass<'a> {
    /// The steps whose records are kept (step 0 is the start).
    pub keep: std::ops::Range<usize>,
    /// Run to the end of the log, not only to the end of `keep`.
    pub whole: bool,
    /// Resume from this checkpoint instead of the log's start.
    pub resume: Option<&'a Checkpoint>,
    /// With `n > 0`, a checkpoint for every multiple `k·n` (`k ≥ 1`) of the steps: the
    /// state at the start of the odometry interval holding step `k·n`.
    pub checkpoint_every: usize,
}

/// The forward pass's state at the start of an odometry interval: all it needs to go on
/// from there exactly as the pass did (the smoother's checkpoints: a segment's records are
/// computed again from the checkpoint before it, not from the log's start). Counts are
/// not part of it: a resumed pass counts into a scratch copy.
#[derive(Clone)]
pub(crate) struct Checkpoint {
    interval: usize,
    steps: usize,
    x: [f64; N],
    p: Mat<N, N>,
    rejected_run: RejectedRun,
    last_fix: Option<Stamp>,
    driven_since_fix_m: f64,
    reset_refused: bool,
    next_correction: usize,
    held_speed: f64,
    t_cur: Stamp,
    odo_cur: Pose2,
}

/// Time constant of the odometry speed held through a slip, seconds.
const SPEED_TIME_CONSTANT_S: f64 = 1.0;

struct Gates {
    one: f64,
    two: f64,
    three: f64,
}

/// Recent gate-rejected fixes in a row: (innovation, R + P_xy).
type RejectedRun = Vec<([f64; 2], Mat<2, 2>)>;

struct Filter<'a> {
    x: [f64; N],
    p: Mat<N, N>,
    cfg: &'a EstimatorConfig,
    gates: Gates,
    counts: &'a mut RunCounts,
    rejected_run: RejectedRun,
    last_fix: Option<Stamp>,
    /// Odometry distance since the filter last took a fix (infinite before the first).
    driven_since_fix_m: f64,
    /// A reset was refused since the filter last took a fix.
    reset_refused: bool,
}

impl Filter<'_> {
    fn correct(&mut self, stamp: Stamp, c: &Correction) {
        match *c {
            Correction::Position { z, r, antenna, quality } => {
                let (nu, h) = models::position(&self.x, z, antenna);
                // Drivers report RTK float (and WAAS) as GBAS_FIX too: only a fix that also
                // claims centimetres is taken as an RTK fixed solution with white errors.
                let rtk_var = self.cfg.rtk_fix_max_sigma_m * self.cfg.rtk_fix_max_sigma_m;
                let tau = match quality {
                    FixQuality::RtkFixed if r[0][0].max(r[1][1]) <= rtk_var => self.cfg.rtk_fix_correlation_time_s,
                    _ => self.cfg.fix_correlation_time_s,
                };
                let interval = self.last_fix.map_or(f64::INFINITY, |l| stamp.secs_since(l));
                self.last_fix = Some(stamp);
                let k = if interval > 0.0 { (tau / interval).max(1.0) } else { tau.max(1.0) };
                let r_w = [[r[0][0] * k, r[0][1] * k], [r[1][0] * k, r[1][1] * k]];
                let g = update_weighted(&mut self.x, &mut self.p, nu, &h, &r, &r_w, self.gates.two);
                let accepted = g.accepted || (!g.nis.is_nan() && self.reset_if_consistent(nu, &r, z, antenna));
                record(&mut self.counts.fixes, stamp, g, accepted);
                let q = &mut self.counts.by_quality[quality.index()];
                if accepted {
                    q.used += 1;
                    self.rejected_run.clear();
                    self.driven_since_fix_m = 0.0;
                    self.reset_refused = false;
                } else {
                    q.rejected_gate += 1;
                    self.counts.rejected_fixes.push(RejectedFix { stamp, reason: FixRejection::Gate, nis: g.nis });
                }
            }
            Correction::Heading { yaw, var } => {
                let (nu, h) = models::heading(&self.x, yaw);
                let g = update(&mut self.x, &mut self.p, nu, &h, &[[var]], self.gates.one);
                record(&mut self.counts.headings, stamp, g, g.accepted);
            }
            Correction::Pose { z, r } => {
                let (nu, h) = models::pose(&self.x, z);
                let g = update(&mut self.x, &mut self.p, nu, &h, &r, self.gates.three);
                record(&mut self.counts.poses, stamp, g, g.accepted);
            }
        }
    }

    /// After a rejected fix: when the last few rejected fixes in a row agree with each
    /// other, the filter (not the fixes) is off — typically after a stretch of correlated
    /// fix errors made it overconfident. Outliers scatter; a filter offset repeats. The
    /// position uncertainty is then reopened by the common innovation and the fix applied.
    fn reset_if_consistent(
        &mut self,
        nu: [f64; 2],
        r: &Mat<2, 2>,
        z: [f64; 2],
        antenna: crate::geometry::Point2,
    ) -> bool {
        let m = self.cfg.gate_reset_consistent_fixes;
        if m == 0 {
            return false;
        }
        let pxy = [[self.p[0][0] + r[0][0], self.p[0][1] + r[0][1]], [self.p[1][0] + r[1][0], self.p[1][1] + r[1][1]]];
        self.rejected_run.push((nu, pxy));
        // Only the last `m` are judged: the run is kept to them (a receiver that jumped
        // for the rest of the log would otherwise grow it by a fix a fix).
        if self.rejected_run.len() > m {
            self.rejected_run.drain(..self.rejected_run.len() - m);
        }
        let run = &self.rejected_run;
        if run.len() < m {
            return false;
        }
        let last = &run[run.len() - m..];
        let mean = [
            last.iter().map(|(v, _)| v[0]).sum::<f64>() / m as f64,
            last.iter().map(|(v, _)| v[1]).sum::<f64>() / m as f64,
        ];
        // Each innovation within the gate of the mean, and the spread small beside the
        // mean offset: a few outliers of metres in random directions do not line up.
        let offset = mean[0].hypot(mean[1]);
        let consistent = last.iter().all(|(v, s)| {
            let d = [v[0] - mean[0], v[1] - mean[1]];
            d[0].hypot(d[1]) <= 0.25 * offset
                && spd_inverse(s).is_some_and(|si| {
                    d[0] * (si[0][0] * d[0] + si[0][1] * d[1]) + d[1] * (si[1][0] * d[0] + si[1][1] * d[1])
                        <= self.gates.two
                })
        });
        if !consistent {
            return false;
        }
        // The odometry must be able to explain the offset (see `gate_reset_max_drift`).
        let sigma = r[0][0].max(r[1][1]).sqrt();
        if offset > self.cfg.gate_reset_max_drift * self.driven_since_fix_m + 10.0 * sigma {
            // Counted once per jump, not once per fix after it.
            if !self.reset_refused {
                self.counts.gate_resets_refused += 1;
                self.reset_refused = true;
            }
            return false;
        }
        let n2 = mean[0] * mean[0] + mean[1] * mean[1];
        self.p[0][0] += mean[0] * mean[0] + n2;
        self.p[0][1] += mean[0] * mean[1];
        self.p[1][0] += mean[0] * mean[1];
        self.p[1][1] += mean[1] * mean[1] + n2;
        self.counts.gate_resets += 1;
        self.rejected_run.clear();
        let (nu, h) = models::position(&self.x, z, antenna);
        update(&mut self.x, &mut self.p, nu, &h, r, self.gates.two).accepted
    }
}

fn record(rep: &mut CorrectionReport, stamp: Stamp, g: Gated, accepted: bool) {
    if accepted {
        rep.used += 1;
    } else {
        rep.rejected_gate += 1;
    }
    if g.nis.is_finite() {
        rep.innovation.record(stamp, g.nis, g.accepted);
    }
}

/// The motion streams and the slip checks on them.
#[derive(Clone, Copy)]
pub(crate) struct MotionSources<'a> {
    pub odo: &'a OdometryTrack,
    pub gyro: Option<&'a GyroTrack>,
    pub slip: &'a SlipDetector,
    pub fix_slip: &'a FixSlipCheck,
}

/// The chi-square gates of `estimator.gate_probability` for 1, 2 and 3 degrees of freedom.
fn gates(cfg: &EstimatorConfig) -> Result<Gates, EstimatorError> {
    let p = cfg.gate_probability;
    let q = |dof| {
        chi_square_quantile(dof, p).ok_or_else(|| EstimatorError::Config(format!("estimator.gate_probability {p}")))
    };
    Ok(Gates { one: q(1)?, two: q(2)?, three: q(3)? })
}

/// Counts a correction outside the odometry's span: there is no state to correct there.
fn count_outside(stamp: Stamp, c: &Correction, counts: &mut RunCounts) {
    match c {
        Correction::Position { .. } => {
            counts.fixes.ignored_outside_track += 1;
            counts.rejected_fixes.push(RejectedFix { stamp, reason: FixRejection::OutsideTrack, nis: f64::NAN });
        }
        Correction::Heading { .. } => counts.headings.ignored_outside_track += 1,
        Correction::Pose { .. } => counts.poses.ignored_outside_track += 1,
    }
}

/// The factor on a slipping increment's distance. Spinning wheels report distance the
/// robot did not drive; its speed rarely jumps while they spin, so a slipping increment
/// keeps the speed of the odometry before the slip (in the odometry's direction), its
/// inflated noise covering the rest. Otherwise 1, and the held speed follows the odometry.
fn speed_factor(slipping: bool, iv: &Interval, held_speed: &mut f64, cfg: &EstimatorConfig) -> f64 {
    let iv_d = iv.delta.x.hypot(iv.delta.y);
    if slipping && cfg.slip_hold_speed && iv_d > 0.0 {
        (*held_speed * iv.dt / iv_d).clamp(0.0, 1.0)
    } else {
        // Standing still counts too: a robot that spins its wheels when starting off
        // is slow, not at the speed it had before it stopped.
        let a = (-iv.dt / SPEED_TIME_CONSTANT_S).exp();
        *held_speed = a * *held_speed + (1.0 - a) * iv_d / iv.dt;
        1.0
    }
}

/// How one odometry interval is driven: its increment's noise inflation and distance factor.
#[derive(Clone, Copy)]
struct Drive<'a> {
    iv: &'a Interval,
    inflation: f64,
    speed_factor: f64,
}

impl Filter<'_> {
    /// Counts the corrections before the track's start `t0` as outside it and applies
    /// those at `t0`; returns the index of the first correction after it.
    fn start(&mut self, corrections: &[(Stamp, Correction)], t0: Stamp) -> usize {
        let mut j = 0;
        while j < corrections.len() && corrections[j].0 < t0 {
            count_outside(corrections[j].0, &corrections[j].1, self.counts);
            j += 1;
        }
        while j < corrections.len() && corrections[j].0 == t0 {
            self.correct(corrections[j].0, &corrections[j].1);
            j += 1;
        }
        j
    }

    /// Predicts over the `dt` seconds ending at `t` of `drive` moving by `inc` (odometry) and `gyro_angle`
    /// (the gyro's integral, with its variance), and while standing still corrects with
    /// the gyro's zero rate. Returns the prediction and its Jacobian.
    fn predict_step(
        &mut self,
        drive: Drive,
        inc: Pose2,
        (t, dt): (Stamp, f64),
        gyro_angle: Option<(f64, f64)>,
    ) -> ([f64; N], Mat<N, N>, Mat<N, N>) {
        let (iv, cfg) = (drive.iv, self.cfg);
        let frac = dt / iv.dt;
        let mut cov = iv.cov;
        for v in cov.iter_mut().flatten() {
            *v *= frac * drive.inflation;
        }
        let heading = if iv.stationary {
            HeadingMotion::Still
        } else if let Some((angle, var)) = gyro_angle {
            HeadingMotion::Gyro { angle, var, dt }
        } else {
            self.counts.steps_without_gyro += 1;
            HeadingMotion::Odometry
        };
        let motion = Motion {
            dx: inc.x * drive.speed_factor,
            dy: inc.y * drive.speed_factor,
            dtheta: inc.theta,
            cov,
            heading,
            heading_noise: cfg.heading_noise_per_sqrt_s.powi(2) * dt,
            bias_noise: cfg.gyro_bias_random_walk.powi(2) * dt,
            scale_noise: cfg.odometry_scale_random_walk.powi(2) * inc.x.hypot(inc.y),
        };
        self.driven_since_fix_m += inc.x.hypot(inc.y);
        let (x_pred, p_pred, jac) = predict(&self.x, &self.p, &motion);
        self.x = x_pred;
        self.p = p_pred;
        if let (true, Some((angle, var))) = (iv.stationary && dt > 0.0, gyro_angle) {
            let (nu, h) = models::zero_rate(&self.x, angle / dt);
            let g = update(&mut self.x, &mut self.p, nu, &h, &[[var / (dt * dt)]], self.gates.one);
            record(&mut self.counts.zero_rate, t, g, g.accepted);
            self.counts.stationary_s += dt;
        }
        (x_pred, p_pred, jac)
    }
}

impl Filter<'_> {
    /// The filter at the log's start (its start corrections applied; step 0 recorded when
    /// kept), or at `resume`; with the loop's state there.
    fn begin(
        &mut self,
        init: &Init,
        corrections: &[(Stamp, Correction)],
        pass: &Pass,
        (t0, odo_t0): (Stamp, Pose2),
    ) -> (Checkpoint, Vec<StepRecord>) {
        let mut records = Vec::new();
        if let Some(c) = pass.resume {
            (self.x, self.p, self.rejected_run) = (c.x, c.p, c.rejected_run.clone());
            (self.last_fix, self.driven_since_fix_m, self.reset_refused) =
                (c.last_fix, c.driven_since_fix_m, c.reset_refused);
            return (c.clone(), records);
        }
        let next_correction = self.start(corrections, t0);
        if pass.keep.contains(&0) {
            records.push(StepRecord { stamp: t0, x: self.x, p: self.p, x_pred: init.x, p_pred: init.p, f: identity() });
        }
        (self.checkpoint(0, 1, next_correction, (0.0, t0, odo_t0)), records)
    }

    /// The filter's state as a checkpoint at interval `interval`, step `steps`, with the
    /// loop's held speed, time and odometry pose there.
    fn checkpoint(
        &self,
        interval: usize,
        steps: usize,
        next_correction: usize,
        (held_speed, t_cur, odo_cur): (f64, Stamp, Pose2),
    ) -> Checkpoint {
        Checkpoint {
            interval,
            steps,
            x: self.x,
            p: self.p,
            rejected_run: self.rejected_run.clone(),
            last_fix: self.last_fix,
            driven_since_fix_m: self.driven_since_fix_m,
            reset_refused: self.reset_refused,
            next_correction,
            held_speed,
            t_cur,
            odo_cur,
        }
    }
}

/// Runs the filter over the whole track from its start or from `pass.resume` (up to the
/// end of `pass.keep` only, unless `pass.whole`), keeping the records of the steps in
/// `pass.keep` and the checkpoints asked for (see [`super::smoother::filter_and_smooth`]).
pub(crate) fn run(
    motion: &MotionSources,
    corrections: &[(Stamp, Correction)],
    init: &Init,
    cfg: &EstimatorConfig,
    counts: &mut RunCounts,
    pass: &Pass,
) -> Result<RunOutput, EstimatorError> {
    let MotionSources { odo, gyro, slip, fix_slip } = *motion;
    let (t0, t_last) = odo.span();
    let mut slips = vec![false; odo.intervals.len()];
    let mut f = Filter {
        x: init.x,
        p: init.p,
        cfg,
        gates: gates(cfg)?,
        counts,
        rejected_run: Vec::new(),
        last_fix: None,
        driven_since_fix_m: f64::INFINITY,
        reset_refused: false,
    };
    let (at, mut records) = f.begin(init, corrections, pass, (t0, odo.pose_at(t0)));
    records.reserve(pass.keep.len().min(odo.stamps.len() + corrections.len()));
    let (mut steps, mut j, mut held_speed, mut t_cur) = (at.steps, at.next_correction, at.held_speed, at.t_cur);
    let mut odo_cur = at.odo_cur;
    let mut checkpoints = Vec::new();
    let every = pass.checkpoint_every;
    for (i, iv) in odo.intervals.iter().enumerate().skip(at.interval) {
        let t_end = odo.stamps[i + 1];
        // The checkpoint of the interval holding step k·every is taken at its start, and
        // kept once that step is reached.
        let start = (every > 0).then(|| f.checkpoint(i, steps, j, (held_speed, t_cur, odo_cur)));
        slips[i] = !iv.stationary && (slip.slips(i, f.x[3]) || fix_slip.slips(t_cur, t_end, odo, &f.x, &f.p));
        let inflation = if slips[i] { cfg.slip_noise_inflation } else { 1.0 };
        let drive = Drive { iv, inflation, speed_factor: speed_factor(slips[i], iv, &mut held_speed, cfg) };
        loop {
            let t = match corrections.get(j) {
                Some(&(tc, _)) if tc <= t_end => tc,
                _ => t_end,
            };
            let odo_t = odo.pose_at(t);
            let inc = odo_cur.inverse().compose(odo_t);
            let gyro_angle = gyro.and_then(|g| g.integral(t_cur, t));
            let (x_pred, p_pred, jac) = f.predict_step(drive, inc, (t, t.secs_since(t_cur)), gyro_angle);
            while j < corrections.len() && corrections[j].0 == t {
                f.correct(corrections[j].0, &corrections[j].1);
                j += 1;
            }
            if !all_finite(&f.p) || !f.x.iter().all(|v| v.is_finite()) {
                return Err(EstimatorError::Numerical { stamp: t.0 });
            }
            if pass.keep.contains(&steps) {
                records.push(StepRecord { stamp: t, x: f.x, p: f.p, x_pred, p_pred, f: jac });
            }
            if every > 0 && steps % every == 0 && checkpoints.len() < steps / every {
                checkpoints.extend(start.clone());
            }
            steps += 1;
            if !pass.whole && steps >= pass.keep.end {
                return Ok(RunOutput { records, slip: slips, steps, checkpoints });
            }
            t_cur = t;
            odo_cur = odo_t;
            if t == t_end {
                break;
            }
        }
    }
    debug_assert_eq!(t_cur, t_last);
    for (stamp, c) in &corrections[j..] {
        count_outside(*stamp, c, f.counts);
    }
    Ok(RunOutput { records, slip: slips, steps, checkpoints })
}

/// Empty per-quality counters.
pub(crate) fn quality_counts() -> Vec<FixQualityCount> {
    FixQuality::ALL.iter().map(|&quality| FixQualityCount { quality, received: 0, used: 0, rejected_gate: 0 }).collect()
}
