//! The RTK receiver: the true antenna position (lever arm on the true pose) in the map's
//! ENU frame, plus the error of the zone it is in, converted to WGS84 through the datum
//! (exact ECEF maths, [`fusemap_core::geometry::geodetic`]).
//!
//! Degraded zones carry a first-order Gauss–Markov error
//! `e_k = φ·e_(k−1) + σ·√(1 − φ²)·n_k`, `φ = exp(−Δt/τ)` (stationary σ; Brown & Hwang,
//! *Introduction to Random Signals and Applied Kalman Filtering*, §2.9), and occasional
//! outliers the reported covariance does not admit, which a robust estimator must reject.

use crate::messages::{diagonal3, SimFix};
use crate::path::Trajectory;
use crate::sensors::{DropoutMode, GnssConfig, ZoneKind};
use fusemap_core::geometry::{Datum, Point2};
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::sensor_msgs::{NavSatFix, NavSatStatus};
use fusemap_io::log::ros2::msgs::std_msgs::Header;

/// The satellite systems every fix is computed from.
const SERVICES: u16 = NavSatStatus::SERVICE_GPS | NavSatStatus::SERVICE_GALILEO;

/// The fixes and the ground truth of their errors.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GnssOutput {
    /// Published fixes.
    pub fixes: Vec<SimFix>,
    /// Stamps of fixes carrying an unreported outlier.
    pub outliers: Vec<Stamp>,
    /// Intervals (receiver clock) with the antenna in a dropout zone.
    pub dropouts: Vec<(Stamp, Stamp)>,
}

/// The intervals (receiver clock) in which the antenna is `inside` a dropout zone, from
/// the 200 Hz truth.
fn dropout_intervals(
    traj: &Trajectory,
    inside: impl Fn(f64) -> bool,
    clock: impl Fn(f64) -> Stamp,
) -> Vec<(Stamp, Stamp)> {
    let mut dropouts = Vec::new();
    let mut open: Option<Stamp> = None;
    let mut last = Stamp::ZERO;
    for s in traj.samples() {
        match (inside(s.t), open) {
            (true, None) => open = Some(clock(s.t)),
            (false, Some(a)) => {
                dropouts.push((a, last));
                open = None;
            }
            _ => {}
        }
        last = clock(s.t);
    }
    if let Some(a) = open {
        dropouts.push((a, last));
    }
    dropouts
}

/// A receiver's message without a fix (status NO_FIX, NaN position).
fn no_fix(topic: &str, stamp: Stamp, frame_id: &str) -> SimFix {
    SimFix::new(
        topic,
        NavSatFix {
            header: Header::new(stamp, frame_id),
            status: NavSatStatus { status: NavSatStatus::STATUS_NO_FIX, service: SERVICES },
            latitude: f64::NAN,
            longitude: f64::NAN,
            altitude: f64::NAN,
            position_covariance: [0.0; 9],
            position_covariance_type: NavSatFix::COVARIANCE_TYPE_UNKNOWN,
        },
    )
}

/// Simulates the receiver over the run. `start` is the clock at t = 0.
pub fn simulate_gnss(
    cfg: &GnssConfig,
    datum: &Datum,
    frame_id: &str,
    traj: &Trajectory,
    start: Stamp,
    rng: &mut SplitMix64,
) -> GnssOutput {
    let clock = |t: f64| Stamp(start.0 + ((t + cfg.time_offset_s) * 1e9).round() as i64);
    let antenna = |t: f64| {
        let p = traj.pose_at(t) * Point2::new(cfg.mount.x, cfg.mount.y);
        (p, cfg.zone_at(p))
    };
    let mut out = GnssOutput {
        dropouts: dropout_intervals(traj, |t| antenna(t).1 == Some(ZoneKind::Dropout), clock),
        ..GnssOutput::default()
    };
    let dt = 1.0 / cfg.rate_hz;
    let phi = (-dt / cfg.degraded_tau_s).exp();
    let drive = cfg.degraded_sigma_m * (1.0 - phi * phi).sqrt();
    let mut gm = [cfg.degraded_sigma_m * rng.gaussian(), cfg.degraded_sigma_m * rng.gaussian()];
    let mut k = 0usize;
    while k as f64 * dt <= traj.duration() {
        let t = k as f64 * dt;
        k += 1;
        gm = [phi * gm[0] + drive * rng.gaussian(), phi * gm[1] + drive * rng.gaussian()];
        let white = [rng.gaussian(), rng.gaussian(), rng.gaussian()];
        let (p, zone) = antenna(t);
        let stamp = clock(t);
        let (status, sigma, err) = match zone {
            Some(ZoneKind::Dropout) => {
                if cfg.dropout_mode == DropoutMode::NoFix {
                    out.fixes.push(no_fix(&cfg.topic, stamp, frame_id));
                }
                continue;
            }
            Some(ZoneKind::Degraded) => {
                let g = cfg.good_sigma_m;
                let mut e = [gm[0] + g * white[0], gm[1] + g * white[1], 2.0 * cfg.degraded_sigma_m * white[2]];
                if rng.next_f64() < cfg.outlier_probability {
                    let size = rng.uniform(cfg.outlier_min_m, cfg.outlier_max_m);
                    let (s, c) = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI).sin_cos();
                    e[0] += size * c;
                    e[1] += size * s;
                    out.outliers.push(stamp);
                }
                (NavSatStatus::STATUS_FIX, cfg.degraded_sigma_m, e)
            }
            None => {
                let g = cfg.good_sigma_m;
                (NavSatStatus::STATUS_GBAS_FIX, g, [g * white[0], g * white[1], 2.0 * g * white[2]])
            }
        };
        let (latitude, longitude, altitude) = datum.to_geodetic([p.x + err[0], p.y + err[1], cfg.mount.z + err[2]]);
        out.fixes.push(SimFix::new(
            &cfg.topic,
            NavSatFix {
                header: Header::new(stamp, frame_id),
                status: NavSatStatus { status, service: SERVICES },
                latitude,
                longitude,
                altitude,
                position_covariance: diagonal3([sigma * sigma, sigma * sigma, 4.0 * sigma * sigma]),
                position_covariance_type: NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN,
            },
        ));
    }
    out
}
