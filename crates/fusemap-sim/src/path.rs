//! The robot's true motion: a closed loop of waypoints with rounded corners, followed by
//! a unicycle under speed, acceleration and turn-rate limits (pure pursuit, Coulter 1992),
//! sampled at 200 Hz.
//!
//! Each 5 ms step applies a constant command `(v, ω)` and integrates the unicycle exactly
//! along its arc, so wheel odometry fed the same commands without errors reproduces the
//! true motion to rounding.

use crate::scenario::RobotConfig;
use crate::world::WorldObject;
use fusemap_core::geometry::{normalize_angle, Point2, Pose2};

/// Integration and truth rate, Hz.
pub const TRUTH_RATE_HZ: f64 = 200.0;

/// The true state at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TruthSample {
    /// Seconds since the start.
    pub t: f64,
    /// `map_from_base`.
    pub pose: Pose2,
    /// Forward speed over the step that starts here, m/s.
    pub v: f64,
    /// Turn rate over the step that starts here, rad/s.
    pub omega: f64,
    /// Forward acceleration, m/s².
    pub accel: f64,
    /// Angular acceleration, rad/s².
    pub alpha: f64,
}

/// The whole true motion.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    samples: Vec<TruthSample>,
}

/// One exact unicycle step: constant `v`, `omega` for `dt`.
pub fn unicycle_step(p: Pose2, v: f64, omega: f64, dt: f64) -> Pose2 {
    let dth = omega * dt;
    // sin(x)/x and (1 - cos x)/x, with their series near 0.
    let (s, c) =
        if dth.abs() < 1e-6 { (1.0 - dth * dth / 6.0, dth / 2.0) } else { (dth.sin() / dth, (1.0 - dth.cos()) / dth) };
    let (st, ct) = p.theta.sin_cos();
    let (fx, fy) = (v * dt * s, v * dt * c);
    Pose2::new(p.x + ct * fx - st * fy, p.y + st * fx + ct * fy, normalize_angle(p.theta + dth))
}

/// The loop through `waypoints` with each corner replaced by a tangent arc of `radius`
/// (shrunk where a leg is too short), sampled about every `spacing` metres. It starts
/// where the first corner's arc ends, on the leg towards the second waypoint.
pub fn rounded_loop(waypoints: &[[f64; 2]], radius: f64, spacing: f64) -> Vec<Point2> {
    let n = waypoints.len();
    let w: Vec<Point2> = waypoints.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let unit = |a: Point2, b: Point2| {
        let d = a.distance(b);
        ((b.x - a.x) / d, (b.y - a.y) / d, d)
    };
    // Per corner: (arc start, arc end, centre, signed sweep, radius).
    let corners: Vec<(Point2, Point2, Point2, f64, f64)> = (0..n)
        .map(|i| {
            let (prev, cur, next) = (w[(i + n - 1) % n], w[i], w[(i + 1) % n]);
            let (d1x, d1y, l1) = unit(prev, cur);
            let (d2x, d2y, l2) = unit(cur, next);
            let turn = (d1x * d2y - d1y * d2x).atan2(d1x * d2x + d1y * d2y);
            if turn.abs() < 1e-9 || radius <= 0.0 {
                return (cur, cur, cur, 0.0, 0.0);
            }
            let half = (turn.abs() / 2.0).tan();
            let t = (radius * half).min(0.45 * l1.min(l2));
            let r = t / half;
            let a = Point2::new(cur.x - d1x * t, cur.y - d1y * t);
            let b = Point2::new(cur.x + d2x * t, cur.y + d2y * t);
            let side = turn.signum();
            let c = Point2::new(a.x - side * d1y * r, a.y + side * d1x * r);
            (a, b, c, turn, r)
        })
        .collect();
    let mut out = Vec::new();
    for k in 0..n {
        let (_, from, ..) = corners[k];
        let (to, _, centre, sweep, r) = corners[(k + 1) % n];
        let steps = (from.distance(to) / spacing).ceil().max(1.0) as usize;
        out.extend((0..steps).map(|j| {
            let u = j as f64 / steps as f64;
            Point2::new(from.x + (to.x - from.x) * u, from.y + (to.y - from.y) * u)
        }));
        let steps = (sweep.abs() * r / spacing).ceil() as usize;
        let a0 = (to.y - centre.y).atan2(to.x - centre.x);
        out.extend((0..steps).map(|j| {
            let a = a0 + sweep * j as f64 / steps as f64;
            Point2::new(centre.x + r * a.cos(), centre.y + r * a.sin())
        }));
    }
    out
}

impl Trajectory {
    /// Drives the loop of `robot` for `robot.duration_s` seconds, starting at rest.
    pub fn generate(robot: &RobotConfig) -> Trajectory {
        const SPACING: f64 = 0.05;
        let path = rounded_loop(&robot.waypoints, robot.corner_radius_m, SPACING);
        let n = path.len();
        let dt = 1.0 / TRUTH_RATE_HZ;
        let steps = (robot.duration_s * TRUTH_RATE_HZ).round() as usize;
        let look = ((robot.lookahead_m / SPACING).round() as usize).max(1);
        let start_dir = path[1 % n];
        let mut pose = Pose2::new(path[0].x, path[0].y, (start_dir.y - path[0].y).atan2(start_dir.x - path[0].x));
        let (mut v, mut omega, mut idx) = (0.0f64, 0.0f64, 0usize);
        let mut samples = Vec::with_capacity(steps + 1);
        for k in 0..=steps {
            // Progress: the nearest path point a little ahead of the last one.
            let best = (0..look * 2)
                .map(|j| (idx + j) % n)
                .min_by(|&a, &b| path[a].distance(pose.translation()).total_cmp(&path[b].distance(pose.translation())));
            idx = best.unwrap_or(idx);
            let target = pose.inverse() * path[(idx + look) % n];
            let ld = target.x.hypot(target.y).max(1e-6);
            let kappa = 2.0 * target.y / (ld * ld);
            let v_des = if kappa.abs() > 1e-9 {
                robot.max_speed_mps.min(robot.max_turn_rate_radps / kappa.abs())
            } else {
                robot.max_speed_mps
            };
            let a_step = robot.max_accel_mps2 * dt;
            let v_new = if k == steps { v } else { v + (v_des - v).clamp(-a_step, a_step) };
            let w_des = (v_new * kappa).clamp(-robot.max_turn_rate_radps, robot.max_turn_rate_radps);
            let al_step = robot.max_angular_accel_radps2 * dt;
            let w_new = if k == steps { omega } else { omega + (w_des - omega).clamp(-al_step, al_step) };
            samples.push(TruthSample {
                t: k as f64 * dt,
                pose,
                v: v_new,
                omega: w_new,
                accel: (v_new - v) / dt,
                alpha: (w_new - omega) / dt,
            });
            pose = unicycle_step(pose, v_new, w_new, dt);
            (v, omega) = (v_new, w_new);
        }
        Trajectory { samples }
    }

    /// The 200 Hz samples.
    pub fn samples(&self) -> &[TruthSample] {
        &self.samples
    }

    /// Seconds from the first to the last sample.
    pub fn duration(&self) -> f64 {
        self.samples.last().map_or(0.0, |s| s.t)
    }

    /// The true state at `t` seconds (clamped to the run): the pose moves along the
    /// step's exact arc, speeds are the step's constant command.
    pub fn sample_at(&self, t: f64) -> TruthSample {
        let last = self.samples.len().saturating_sub(1);
        // The nudge keeps a time on a step boundary (0.29 s · 200 = 57.999…) in the step it
        // starts rather than the one before.
        let k = ((t * TRUTH_RATE_HZ + 1e-6).floor().max(0.0) as usize).min(last);
        let s = self.samples[k];
        let dt = (t - s.t).clamp(0.0, 1.0 / TRUTH_RATE_HZ);
        TruthSample { t, pose: unicycle_step(s.pose, s.v, s.omega, dt), ..s }
    }

    /// `map_from_base` at `t` seconds.
    pub fn pose_at(&self, t: f64) -> Pose2 {
        self.sample_at(t).pose
    }

    /// Where the base origin comes closest to an object (every 200 Hz sample against
    /// every object's solid): a scenario check for the command line, and what the tests
    /// hold to ≥ 0.5 m. `None` without objects.
    pub fn closest_approach(&self, objects: &[WorldObject]) -> Option<Approach> {
        let mut best: Option<Approach> = None;
        for s in &self.samples {
            for (object, o) in objects.iter().enumerate() {
                let distance_m = o.distance(s.pose.translation());
                if best.is_none_or(|b| distance_m < b.distance_m) {
                    best = Some(Approach { distance_m, object, t: s.t });
                }
            }
        }
        best
    }
}

/// The closest approach of the robot to the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Approach {
    /// Distance from the base origin to the object's solid, metres.
    pub distance_m: f64,
    /// Index of the object.
    pub object: usize,
    /// When, seconds since the start.
    pub t: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounded_loop_is_closed_and_evenly_sampled() {
        let path = rounded_loop(&[[0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [0.0, 5.0]], 1.0, 0.05);
        let gaps: Vec<f64> = (0..path.len()).map(|i| path[i].distance(path[(i + 1) % path.len()])).collect();
        assert!(gaps.iter().all(|&g| g > 0.02 && g < 0.0501), "{:?}", gaps.iter().cloned().fold(0.0, f64::max));
        let length: f64 = gaps.iter().sum();
        // 30 m of rectangle minus 4 corners of (2r - πr/2).
        let expected = 30.0 - 4.0 * (2.0 - std::f64::consts::FRAC_PI_2);
        assert!((length - expected).abs() < 0.01, "{length} vs {expected}");
        assert!((path[0].x - 1.0).abs() < 1e-12 && path[0].y.abs() < 1e-12);
    }

    #[test]
    fn limits_hold_and_the_loop_is_followed() {
        let robot = RobotConfig { duration_s: 120.0, ..RobotConfig::default() };
        let traj = Trajectory::generate(&robot);
        let path = rounded_loop(&robot.waypoints, robot.corner_radius_m, 0.05);
        let s = traj.samples();
        assert_eq!(s.len(), 120 * 200 + 1);
        let mut dist = 0.0;
        let mut worst_off_path = 0.0f64;
        for w in s.windows(2) {
            assert!(w[0].v <= robot.max_speed_mps + 1e-12 && w[0].v >= 0.0);
            assert!(w[0].omega.abs() <= robot.max_turn_rate_radps + 1e-12);
            assert!(w[1].accel.abs() <= robot.max_accel_mps2 + 1e-9);
            assert!(w[1].alpha.abs() <= robot.max_angular_accel_radps2 + 1e-9);
            dist += w[0].pose.translation().distance(w[1].pose.translation());
            let off = path.iter().map(|p| p.distance(w[1].pose.translation())).fold(f64::INFINITY, f64::min);
            worst_off_path = worst_off_path.max(off);
        }
        let mean_speed = dist / traj.duration();
        eprintln!("120 s: {dist:.1} m driven, mean speed {mean_speed:.2} m/s, worst distance from the loop {worst_off_path:.3} m");
        assert!(mean_speed > 0.6, "{mean_speed}");
        assert!(worst_off_path < 0.3, "{worst_off_path}");
        // The interpolated pose between samples lies on the step's arc.
        let mid = traj.pose_at(10.0025);
        let a = traj.pose_at(10.0);
        assert!((mid.translation().distance(a.translation()) - s[2000].v * 0.0025).abs() < 1e-9);
    }

    #[test]
    fn unicycle_step_matches_the_circle() {
        // A quarter circle of radius 2 in one step.
        let p = unicycle_step(Pose2::IDENTITY, 2.0 * std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2, 1.0);
        assert!((p.x - 2.0).abs() < 1e-12 && (p.y - 2.0).abs() < 1e-12, "{p:?}");
        let straight = unicycle_step(Pose2::new(1.0, 1.0, 0.5), 1.0, 0.0, 2.0);
        assert!((straight.x - 1.0 - 2.0 * 0.5f64.cos()).abs() < 1e-12);
    }
}
