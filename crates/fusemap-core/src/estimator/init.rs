//! The start of the track: the gyro bias seen while standing still, the dead-reckoned path,
//! and the heading from the earliest absolute source, carried back to the first odometry
//! stamp.
//!
//! An EKF linearised around a heading it does not know diverges (the translation Jacobian
//! depends on the heading), and guessing one makes the track claim a heading it does not
//! have. So the heading is found first: from an IMU yaw or an absolute pose when the log
//! has one, otherwise from the course over ground — the dead-reckoned path over the first
//! few metres rigidly fitted to good fixes (2D Procrustes: Umeyama, *Least-squares
//! estimation of transformation parameters between two point patterns*, 1991), which is
//! exact through turns and accounts for the antenna's lever arm. The rotation of that fit
//! is the heading at the start of the dead-reckoned path, so the filter starts at the first
//! odometry stamp with a known heading whose uncertainty includes the dead-reckoning drift
//! back to the start. The fixes of the fit are used again by the filter (a mild double use,
//! covered by the fit's residual-based uncertainty); the smoother then makes the early poses
//! agree with everything after.

use super::config::EstimatorConfig;
use super::error::EstimatorError;
use super::input::Correction;
use super::linalg::Mat;
use super::report::{HeadingInit, HeadingSource};
use super::streams::{GyroTrack, OdometryTrack};
use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::time::Stamp;

/// The filter's initial state `[x, y, θ, gyro bias, odometry scale]` and covariance.
pub(crate) struct Init {
    pub x: [f64; 5],
    pub p: Mat<5, 5>,
    pub info: HeadingInit,
}

/// The dead-reckoned path in its own frame (starts at the identity at the first odometry
/// stamp), with the variance of its heading relative to the start.
struct DeadReckoning {
    poses: Vec<Pose2>,
    heading_var: Vec<f64>,
}

impl DeadReckoning {
    fn at(&self, odo: &OdometryTrack, t: Stamp) -> (Pose2, f64) {
        let k = odo.stamps.partition_point(|&s| s <= t).saturating_sub(1).min(odo.stamps.len() - 2);
        let (t0, t1) = (odo.stamps[k], odo.stamps[k + 1]);
        let f = ((t.0 - t0.0) as f64 / (t1.0 - t0.0) as f64).clamp(0.0, 1.0);
        // Interpolate the heading without wrapping: the dead-reckoned heading is continuous.
        let (a, b) = (self.poses[k], self.poses[k + 1]);
        let pose = Pose2::new(a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), a.theta + f * (b.theta - a.theta));
        (pose, self.heading_var[k] + f * (self.heading_var[k + 1] - self.heading_var[k]))
    }
}

/// The mean gyro rate over the first stretch of standing still, and its standard deviation.
pub(crate) fn stationary_bias(odo: &OdometryTrack, gyro: Option<&GyroTrack>) -> Option<(f64, f64)> {
    let gyro = gyro?;
    let first = odo.intervals.iter().position(|iv| iv.stationary)?;
    let last = first + odo.intervals[first..].iter().take_while(|iv| iv.stationary).count();
    let (a, b) = (odo.stamps[first], odo.stamps[last]);
    let (angle, var) = gyro.integral(a, b)?;
    let dt = b.secs_since(a);
    Some((angle / dt, var.sqrt() / dt))
}

fn dead_reckon(odo: &OdometryTrack, gyro: Option<&GyroTrack>, bias: f64, cfg: &EstimatorConfig) -> DeadReckoning {
    let mut poses = Vec::with_capacity(odo.stamps.len());
    let mut heading_var = Vec::with_capacity(odo.stamps.len());
    let (mut pose, mut var) = (Pose2::IDENTITY, 0.0);
    poses.push(pose);
    heading_var.push(var);
    for (i, iv) in odo.intervals.iter().enumerate() {
        let (dtheta, v) = if iv.stationary {
            (0.0, 0.0)
        } else {
            match gyro.and_then(|g| g.integral(odo.stamps[i], odo.stamps[i + 1])) {
                Some((g, vg)) => (g - bias * iv.dt, vg),
                None => (iv.delta.theta, iv.cov[2][2]),
            }
        };
        let (s, c) = pose.theta.sin_cos();
        pose = Pose2::new(
            pose.x + c * iv.delta.x - s * iv.delta.y,
            pose.y + s * iv.delta.x + c * iv.delta.y,
            pose.theta + dtheta,
        );
        var += v + cfg.heading_noise_per_sqrt_s.powi(2) * iv.dt;
        poses.push(pose);
        heading_var.push(var);
    }
    DeadReckoning { poses, heading_var }
}

/// The largest standard deviation of a 2×2 covariance.
fn max_sigma(r: &Mat<2, 2>) -> f64 {
    let half_trace = 0.5 * (r[0][0] + r[1][1]);
    let det = r[0][0] * r[1][1] - r[0][1] * r[1][0];
    (half_trace + (half_trace * half_trace - det).max(0.0).sqrt()).sqrt()
}

/// A rigid 2D fit `world = R(φ) local + T`.
struct Fit {
    phi: f64,
    t: Point2,
    rms: f64,
    worst: usize,
    spread: f64,
}

/// Least-squares rotation and translation between point pairs (Umeyama 1991, in 2D the
/// rotation has the closed form `atan2(Σ l̃ × w̃, Σ l̃ · w̃)` over centred points).
fn procrustes(pairs: &[(Point2, Point2)]) -> Fit {
    let n = pairs.len() as f64;
    let (mut lx, mut ly, mut wx, mut wy) = (0.0, 0.0, 0.0, 0.0);
    for (l, w) in pairs {
        lx += l.x;
        ly += l.y;
        wx += w.x;
        wy += w.y;
    }
    let (lx, ly, wx, wy) = (lx / n, ly / n, wx / n, wy / n);
    let (mut cross, mut dot, mut spread) = (0.0, 0.0, 0.0);
    for (l, w) in pairs {
        let (ax, ay, bx, by) = (l.x - lx, l.y - ly, w.x - wx, w.y - wy);
        cross += ax * by - ay * bx;
        dot += ax * bx + ay * by;
        spread += ax * ax + ay * ay;
    }
    let phi = cross.atan2(dot);
    let (s, c) = phi.sin_cos();
    let t = Point2::new(wx - (c * lx - s * ly), wy - (s * lx + c * ly));
    let (mut sum, mut worst, mut worst_r) = (0.0, 0, -1.0);
    for (i, (l, w)) in pairs.iter().enumerate() {
        let r2 = (c * l.x - s * l.y + t.x - w.x).powi(2) + (s * l.x + c * l.y + t.y - w.y).powi(2);
        sum += r2;
        if r2 > worst_r {
            worst_r = r2;
            worst = i;
        }
    }
    Fit { phi, t, rms: (sum / n).sqrt(), worst, spread }
}

/// The course-over-ground heading: (stamp of the last fix used, fit, fixes, distance, mean fix variance).
struct CourseFit {
    stamp: Stamp,
    fit: Fit,
    fixes: usize,
    distance: f64,
    fix_var: f64,
    mid: Stamp,
}

fn course_over_ground(
    odo: &OdometryTrack,
    dr: &DeadReckoning,
    fixes: &[(Stamp, [f64; 2], Mat<2, 2>, Point2)],
    cfg: &EstimatorConfig,
) -> Result<CourseFit, f64> {
    let mut travelled: f64 = 0.0;
    for a in 0..fixes.len() {
        let za = fixes[a].1;
        // The baseline grows with the fixes' imprecision: ten standard deviations at least.
        let mut sigma = max_sigma(&fixes[a].2);
        let Some(b) = (a + 1..fixes.len()).find(|&b| {
            sigma = sigma.max(max_sigma(&fixes[b].2));
            (fixes[b].1[0] - za[0]).hypot(fixes[b].1[1] - za[1]) >= cfg.heading_init_distance_m.max(10.0 * sigma)
        }) else {
            for f in &fixes[a..] {
                travelled = travelled.max((f.1[0] - za[0]).hypot(f.1[1] - za[1]));
            }
            break;
        };
        let mut pairs: Vec<(Point2, Point2)> = fixes[a..=b]
            .iter()
            .map(|(t, z, _, antenna)| {
                let (pose, _) = dr.at(odo, *t);
                (pose.transform_point(*antenna), Point2::new(z[0], z[1]))
            })
            .collect();
        let keep_at_least = (pairs.len() * 4).div_ceil(5).max(3);
        let fix_var = fixes[a..=b].iter().map(|f| 0.5 * (f.2[0][0] + f.2[1][1])).sum::<f64>() / (b - a + 1) as f64;
        let max_rms = cfg.heading_init_max_residual_m.max(3.0 * fix_var.sqrt());
        loop {
            let fit = procrustes(&pairs);
            if fit.rms <= max_rms {
                let mid = Stamp(fixes[a].0 .0 + (fixes[b].0 .0 - fixes[a].0 .0) / 2);
                let distance = (fixes[b].1[0] - za[0]).hypot(fixes[b].1[1] - za[1]);
                return Ok(CourseFit { stamp: fixes[b].0, fixes: pairs.len(), fit, distance, fix_var, mid });
            }
            if pairs.len() <= keep_at_least {
                break;
            }
            pairs.swap_remove(fit.worst);
        }
    }
    Err(travelled)
}

/// The absolute corrections inside the odometry's span that can start the track.
struct Starts {
    /// Position fixes precise enough to fit the course over ground: stamp, position,
    /// covariance, antenna lever arm.
    good_fixes: Vec<(Stamp, [f64; 2], Mat<2, 2>, Point2)>,
    /// The first position fix, however precise.
    first_fix: Option<(Stamp, [f64; 2], Point2)>,
    /// The first absolute heading: stamp, yaw, variance.
    first_heading: Option<(Stamp, f64, f64)>,
    /// The first absolute pose: stamp, pose, yaw variance.
    first_pose: Option<(Stamp, [f64; 3], f64)>,
}

fn starts(odo: &OdometryTrack, corrections: &[(Stamp, Correction)], cfg: &EstimatorConfig) -> Starts {
    let inside = |t: &Stamp| odo.contains(*t);
    let good_fixes = corrections
        .iter()
        .filter(|(t, _)| inside(t))
        .filter_map(|(t, c)| match c {
            Correction::Position { z, r, antenna, .. } if max_sigma(r) <= cfg.heading_init_max_fix_sigma_m => {
                Some((*t, *z, *r, *antenna))
            }
            _ => None,
        })
        .collect();
    let first_fix = corrections.iter().filter(|(t, _)| inside(t)).find_map(|(t, c)| match c {
        Correction::Position { z, antenna, .. } => Some((*t, *z, *antenna)),
        _ => None,
    });
    let first_heading = corrections.iter().filter(|(t, _)| inside(t)).find_map(|(t, c)| match c {
        Correction::Heading { yaw, var } => Some((*t, *yaw, *var)),
        _ => None,
    });
    let first_pose = corrections.iter().filter(|(t, _)| inside(t)).find_map(|(t, c)| match c {
        Correction::Pose { z, r } => Some((*t, *z, r[2][2])),
        _ => None,
    });
    Starts { good_fixes, first_fix, first_heading, first_pose }
}

/// The start position that puts `a` (a point dead-reckoned from the start, in the start's
/// frame) on the absolute position `z` when the start is turned by `phi`.
fn start_from(z: [f64; 2], a: Point2, phi: f64) -> Point2 {
    let (s, c) = phi.sin_cos();
    Point2::new(z[0] - (c * a.x - s * a.y), z[1] - (s * a.x + c * a.y))
}

/// The filter's first state and covariance: position, heading, no gyro bias, unit scale.
fn first_state(
    (stamp, source): (Option<Stamp>, HeadingSource),
    (phi, phi_var): (f64, f64),
    (position, p_var): (Point2, f64),
    cfg: &EstimatorConfig,
) -> Init {
    let mut p = [[0.0; 5]; 5];
    p[0][0] = p_var;
    p[1][1] = p_var;
    p[2][2] = phi_var;
    p[3][3] = cfg.initial_gyro_bias_sigma.powi(2);
    p[4][4] = cfg.initial_scale_sigma.powi(2);
    let info = HeadingInit { stamp, source, start_heading_rad: phi, start_heading_sigma_rad: phi_var.sqrt() };
    Init { x: [position.x, position.y, phi, 0.0, 1.0], p, info }
}

/// A source of the start heading, found at a stamp: an absolute pose (`[x, y, yaw]` and the
/// yaw's variance), an IMU heading (yaw and variance), or the course over ground.
enum Source<'a> {
    Pose([f64; 3], f64),
    Heading(f64, f64),
    Course(&'a CourseFit),
}

/// Finds the heading (and position) at the first odometry stamp.
pub(crate) fn initialise(
    odo: &OdometryTrack,
    gyro: Option<&GyroTrack>,
    corrections: &[(Stamp, Correction)],
    cfg: &EstimatorConfig,
) -> Result<Init, EstimatorError> {
    let (bias, bias_sigma) = stationary_bias(odo, gyro).unwrap_or((0.0, cfg.initial_gyro_bias_sigma));
    let dr = dead_reckon(odo, gyro, bias, cfg);
    let t0 = odo.stamps[0];
    // Heading drift of the dead reckoning between the start and t.
    let drift_var = |t: Stamp| {
        let (_, v) = dr.at(odo, t);
        v + if gyro.is_some() { (bias_sigma * t.secs_since(t0)).powi(2) } else { 0.0 }
    };
    let Starts { good_fixes, first_fix, first_heading, first_pose } = starts(odo, corrections, cfg);
    let course = course_over_ground(odo, &dr, &good_fixes, cfg);

    // The earliest source wins.
    let candidates = [
        first_pose.map(|(t, z, var)| (t, Source::Pose(z, var))),
        first_heading.map(|(t, yaw, var)| (t, Source::Heading(yaw, var))),
        course.as_ref().ok().map(|c| (c.stamp, Source::Course(c))),
    ];
    let best = candidates.into_iter().flatten().min_by_key(|(t, _)| *t);
    let pos_var = cfg.initial_position_sigma_m.powi(2);
    // A position found at t and carried back to the start by dead reckoning is as uncertain
    // as the dead reckoning over that distance: scale, heading drift and noise.
    let carried_var = |t: Stamp| {
        let (pose, _) = dr.at(odo, t);
        let d = pose.x.hypot(pose.y);
        pos_var
            + (cfg.initial_scale_sigma * d).powi(2)
            + drift_var(t) * d * d
            + cfg.odometry_translation_noise.powi(2) * d
    };
    let gauge = 1e-10;
    let (stamp, source, phi, phi_var, position, p_var) = match best {
        Some((t, Source::Pose(z, var))) => {
            let (pose, _) = dr.at(odo, t);
            let phi = normalize_angle(z[2] - pose.theta);
            let p = start_from([z[0], z[1]], Point2::new(pose.x, pose.y), phi);
            (Some(t), HeadingSource::AbsolutePose, phi, var + drift_var(t), p, carried_var(t))
        }
        Some((t, Source::Heading(yaw, var))) => {
            let (pose, _) = dr.at(odo, t);
            let phi = normalize_angle(yaw - pose.theta);
            // Position from the first fix when there is one; otherwise the start is the origin.
            let (p, p_var) = match first_fix {
                Some((tf, z, antenna)) => {
                    (start_from(z, dr.at(odo, tf).0.transform_point(antenna), phi), carried_var(tf))
                }
                None => (Point2::default(), gauge),
            };
            (Some(t), HeadingSource::ImuHeading, phi, var + drift_var(t), p, p_var)
        }
        Some((t, Source::Course(c))) => {
            // Rotation variance of a rigid fit: σ² / Σ|l̃|² (residual or fix noise, the larger).
            let rms2 = c.fit.rms.powi(2).max(c.fix_var);
            let var = rms2 / c.fit.spread.max(1e-9) + drift_var(c.mid);
            let source =
                HeadingSource::CourseOverGround { fixes: c.fixes, distance_m: c.distance, residual_rms_m: c.fit.rms };
            (Some(t), source, normalize_angle(c.fit.phi), var, c.fit.t, carried_var(c.mid))
        }
        None => {
            if let (Err(travelled), Some(_)) = (&course, first_fix) {
                return Err(EstimatorError::HeadingNotObservable {
                    travelled_m: *travelled,
                    needed_m: cfg.heading_init_distance_m,
                });
            }
            // No absolute source at all: the map frame is the start pose, exactly.
            (None, HeadingSource::StartPose, 0.0, gauge, Point2::default(), gauge)
        }
    };
    Ok(first_state((stamp, source), (phi, phi_var.max(gauge)), (position, p_var), cfg))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn procrustes_recovers_a_rigid_motion(phi in -3.1..3.1f64, tx in -50.0..50.0f64, ty in -50.0..50.0f64) {
            let local = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.2), Point2::new(2.0, 1.0), Point2::new(2.5, 3.0)];
            let world = Pose2::new(tx, ty, phi);
            let pairs: Vec<_> = local.iter().map(|&l| (l, world.transform_point(l))).collect();
            let fit = procrustes(&pairs);
            prop_assert!(normalize_angle(fit.phi - phi).abs() < 1e-9);
            prop_assert!((fit.t.x - tx).abs() < 1e-7 && (fit.t.y - ty).abs() < 1e-7);
            prop_assert!(fit.rms < 1e-7);
        }
    }
}
