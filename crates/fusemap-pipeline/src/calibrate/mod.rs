//! `fusemap calibrate`, planned and run: what the design document's §4.3 tells a user to
//! check by hand, estimated from the log with 95 % intervals, and named as undetermined
//! where the log cannot fix it.
//!
//! This version estimates the lidar's planar mount (yaw, x, y) and the wheel odometry's
//! scale and wheel base from the two tracks of one robot: SLAM's, which follows the lidar through its
//! configured mount, and the wheels' ([`fusemap_core::calibration::lidar_odometry`],
//! after Censi et al. 2013), and the lidar's clock offset against the odometry from when
//! their turns line up ([`fusemap_core::calibration::turn_agreement`]). It needs SLAM on
//! a timed track and a wheel-odometry topic; without them it says so. Each camera's clock
//! offset and mount yaw come from its wall points scored on the lidars' map of the same
//! pass (`calibrate/camera.rs`, [`fusemap_core::calibration::camera_against_map`]); its
//! height above the floor and its tilt from the floor its depth pixels see
//! ([`fusemap_core::calibration::camera_floor`]).

mod camera;
mod revalidate;

pub use revalidate::{Figures, Revalidation};

use crate::job::{JobError, LogJob};
use crate::outputs::{finish, prepare, ExportOptions, RunRecord};
use crate::recording::Inventory;
use crate::sensors::Bound;
use crate::track::{ChosenTrack, Track};
use crate::{PassMaps, PipelineError, Progress};
use fusemap_core::calibration::{
    jackknife_sigma, lidar_odometry, steps_of, turn_agreement, Interval, LidarOdometry, MotionStep,
};
use fusemap_core::config::{Plan, SensorKind};
use fusemap_core::fusion::{MapSet, SensorSelection};
use fusemap_core::geometry::{Mount3, Pose2};
use fusemap_core::grid::FusionGrid;
use fusemap_core::time::{Stamp, SyncMode};
use serde::Serialize;
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// The file of ready-to-paste `[[sensor]]` tables.
pub const CALIBRATION_TOML: &str = "calibration.toml";

/// Steps of the two tracks: at least this far along the odometry, metres …
const STEP_M: f64 = 0.3;
/// … or this far turned, radians.
const STEP_RAD: f64 = 0.2;
/// The widest lever-arm interval reported; wider, the log does not fix x and y.
const MAX_LEVER_INTERVAL_M: f64 = 0.05;

/// A calibration, planned.
pub struct CalibrateJob {
    /// The configuration, the log and the output directory.
    pub job: LogJob,
    /// Validate again with the calibration pasted in (the command always does; it costs two
    /// validation passes).
    pub revalidate: bool,
}

/// One sensor's estimates (`summary.json`'s `calibration.sensors[]`).
#[derive(Clone, Debug, Serialize)]
pub struct SensorCalibration {
    /// The sensor's name (a lidar) or topic (the wheel odometry).
    pub name: String,
    /// Its kind.
    pub kind: SensorKind,
    /// The mount's x, metres (a lidar whose turns fix it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x: Option<Interval>,
    /// The mount's y, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub y: Option<Interval>,
    /// The mount's yaw, radians.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub yaw: Option<Interval>,
    /// The mount's z, metres: a camera's height above the floor (`base_link`'s z = 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<Interval>,
    /// The mount's roll, radians (a camera's, from the floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roll: Option<Interval>,
    /// The mount's pitch, radians (a camera's, from the floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch: Option<Interval>,
    /// The clock offset to add to its stamps, seconds (a lidar: against the odometry).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_offset_s: Option<Interval>,
    /// Odometry distance / true distance (the wheel odometry).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<Interval>,
    /// The true wheel base as a multiple of the one the odometry assumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wheel_base: Option<Interval>,
    /// The residual RMS of the motion equations before, metres (a camera: of its obstacle
    /// points' distances to the lidar's walls, truncated at 0.3 m).
    pub cost_before: f64,
    /// … and after.
    pub cost_after: f64,
    /// Robot steps used (and of them, turning ones); a camera: frames and points scored.
    pub steps: [u64; 2],
    /// The cost over the clock offsets searched, `[offset_s, cost]` (a camera): the one
    /// its fine searches minimise, truncated nearer the walls than `cost_before` and
    /// `cost_after` are (`CameraSearch::fine_reach_m`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub clock_curve: Vec<[f64; 2]>,
    /// The same cost over the mount yaws searched, `[yaw, cost]` (a camera).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub yaw_curve: Vec<[f64; 2]>,
}

/// What `calibrate` found: `summary.json`'s `calibration`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Calibration {
    /// The estimates.
    pub sensors: Vec<SensorCalibration>,
    /// What this log cannot determine, or this version does not estimate, and why.
    pub undetermined: Vec<String>,
    /// `validate` with the configuration as given and with the calibration applied.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revalidation: Option<Revalidation>,
}

/// What the run wrote and found.
pub struct CalibrateRun {
    /// The summary (`summary.json`, with `calibration`).
    pub summary: crate::outputs::Summary,
    /// The calibration.
    pub calibration: Calibration,
}

impl CalibrateJob {
    /// `fusemap calibrate [--config C] --out DIR LOG`.
    pub fn plan(config: Option<&Path>, log: &Path, out: &Path) -> Result<Self, JobError> {
        Ok(Self { job: LogJob::plan(config, log, out)?, revalidate: true })
    }

    /// Estimates, maps with the configuration as given, and writes the set: the map's
    /// files, `calibration.toml` and `summary.json` with its `calibration`.
    pub fn run(self, progress: &mut dyn FnMut(Progress)) -> Result<CalibrateRun, JobError> {
        let started = Instant::now();
        let job = &self.job;
        let (plan, input) = (&job.plan, job.log.display().to_string());
        let outputs = prepare(&job.out, &job.inputs)?;
        let named = |e| job.named(e);
        let inv = job.read(progress)?;
        let (bound, raw, track_s) = crate::run::prepare_track(plan, &inv).map_err(named)?;
        let (chosen, track_s) = crate::run::correct(plan, &inv, &bound, raw, track_s, progress).map_err(named)?;
        let (estimate, mut undetermined) = lidar_against_odometry(plan, &inv, &bound, &chosen).map_err(named)?;
        let grid = || FusionGrid::new(plan.geometry, plan.occupancy);
        let set = MapSet::new("all", SensorSelection::All, grid()).with(
            camera::LIDAR_MAP,
            SensorSelection::Kinds(vec![fusemap_core::measurement::SensorKind::Lidar]),
            grid(),
        );
        let maps = PassMaps { set: Some(set), holdout_share: None, camera_samples: true, endpoints: false };
        let run = crate::map_with_track(plan, &inv, &bound, chosen, track_s, maps, progress).map_err(named)?;
        let mount = run.report.lidars.first().map(|l| (l.name.clone(), l.topic.clone(), l.extrinsics.base_from_sensor));
        let configured_offset = run.report.lidars.first().map_or(0.0, |l| l.time_offset_s);
        let mut calibration = Calibration::default();
        // The pass placed the base through the configured lidar mount, and the cameras were
        // fitted to that base: a lidar yaw corrected by φ turns the base by φ, and each
        // camera's mount with it.
        let mut base_turn = 0.0;
        let mut text = format!("# fusemap calibrate on {input}\n# A value whose interval holds the configured one is left as configured.\n");
        if let (Some(mut estimate), Some((name, topic, configured))) = (estimate, mount) {
            // The search's offset is relative to the configured one.
            estimate.clock = estimate.clock.map(|c| shifted(c, configured_offset));
            calibration.sensors = sensors_of(&estimate, &name, &configured, &mut undetermined);
            text.push_str(&calibration_toml(&estimate, &name, &topic, &configured, configured_offset));
            base_turn = claim(corrected(&estimate.motion, &configured).0, configured.yaw) - configured.yaw;
        }
        for mut c in camera::cameras_against_lidar(&run, &mut undetermined) {
            c.base_turn = base_turn;
            calibration.sensors.push(c.entry());
            c.toml(&mut text);
        }
        if !calibration.sensors.is_empty() {
            let path = outputs.staged(CALIBRATION_TOML);
            fusemap_io::atomic::write_atomic(&path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
            if self.revalidate {
                match revalidate::revalidate(plan, &inv, &text, progress).map_err(named)? {
                    Ok(r) => calibration.revalidation = Some(r),
                    Err(why) => undetermined.push(why),
                }
            }
        }
        calibration.undetermined = undetermined;
        let mut notes = run.notes;
        notes.extend(calibration.undetermined.iter().map(|u| format!("calibration: {u}")));
        notes.extend(calibration.revalidation.iter().map(|r| format!("calibration: {}", r.sentence)));
        let record = RunRecord {
            source_kind: &run.format.to_string(),
            source: &input,
            started,
            notes,
            log: Some(serde_json::to_value(&run.report)?),
            trajectory: Some(&run.trajectory),
            validation: None,
            calibration: Some(serde_json::to_value(&calibration)?),
            endpoints: None,
            map_from_odom: run.map_from_odom.as_ref().map(|(f, m)| (f.as_str(), *m)),
            seconds: crate::outputs::Seconds::of_log(&run.report),
        };
        let export = ExportOptions::of(plan, None);
        let summary = finish(&run.engine, outputs, &export, record)?;
        Ok(CalibrateRun { summary, calibration })
    }
}

/// The hand–eye estimate of the first lidar against the wheel odometry, with the odometry
/// topic; `None` and why when the log cannot give it.
type Estimated = Option<Estimate>;

fn lidar_against_odometry(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: &ChosenTrack,
) -> Result<(Estimated, Vec<String>), PipelineError> {
    let why = |s: &str| Ok((None, vec![format!("the lidar's mount and the odometry's scale: {s}")]));
    let Some(odom) = bound.first(SensorKind::WheelOdometry) else {
        return why(
            "the log has no wheel-odometry topic to compare the lidar's motion with (the odometry on CARMEN scan \
             lines is not compared yet)",
        );
    };
    let Some(slam) = &chosen.slam else {
        return why("SLAM did not run (it needs raw poses: odometry, the estimator or TF under `odom`)");
    };
    let odometry = crate::track::odometry_track(inv, &plan.log, odom)?;
    let Track::Timed(track) = &odometry.track else { return why("the odometry is not a timed track") };
    // The SLAM poses the odometry covers at every offset of the search, so that each offset
    // compares the same steps.
    let reach = crate::offset_ns(CLOCK_SEARCH_S);
    let covered = |t: Stamp| {
        [t.0.saturating_sub(reach), t.0.saturating_add(reach)]
            .iter()
            .all(|&s| track.pose_at(Stamp(s), SyncMode::Interpolate).is_ok())
    };
    let poses: Vec<(Stamp, Pose2)> = slam.scan_poses.iter().copied().filter(|(t, _)| covered(*t)).collect();
    // The steps with the odometry read `offset_ns` later, the poses of `skip` left out.
    let steps_at = |offset_ns: i64, skip: std::ops::Range<usize>| {
        let pairs: Vec<(Pose2, Pose2)> = poses
            .iter()
            .enumerate()
            .filter(|(i, _)| !skip.contains(i))
            .filter_map(|(_, (t, p))| {
                let at = Stamp(t.0.saturating_add(offset_ns));
                track.pose_at(at, SyncMode::Interpolate).ok().map(|o| (o, *p))
            })
            .collect();
        steps_of(&pairs, STEP_M, STEP_RAD)
    };
    let offset = clock_offset(&steps_at, poses.len());
    let fit_at = |dt: f64| lidar_odometry(&steps_at(crate::offset_ns(dt), 0..0), MAX_LEVER_INTERVAL_M);
    let Some(mut e) = fit_at(offset.map_or(0.0, |o| o.value)) else {
        return why("fewer than 10 steps of the robot are seen by both SLAM and the odometry");
    };
    // The mount depends on the clock offset (a turn seen late looks like a lever arm): its
    // intervals take in the fits at both ends of the offset's interval.
    for end in offset.iter().flat_map(|o| [o.low, o.high]) {
        if let Some(other) = fit_at(end) {
            widen(&mut e, &other);
        }
    }
    Ok((Some(Estimate { motion: e, odometry: odom.topic.clone(), clock: offset }), Vec::new()))
}

/// Widens `e`'s intervals to take in `other`'s.
fn widen(e: &mut LidarOdometry, other: &LidarOdometry) {
    let hull = |a: &mut Interval, b: &Interval| {
        a.low = a.low.min(b.low);
        a.high = a.high.max(b.high);
    };
    hull(&mut e.yaw, &other.yaw);
    hull(&mut e.scale, &other.scale);
    match (&mut e.lever, &other.lever) {
        (Some(a), Some(b)) => {
            hull(&mut a[0], &b[0]);
            hull(&mut a[1], &b[1]);
        }
        (lever, None) => *lever = None,
        _ => {}
    }
}

/// The search of the lidar's clock offset against the odometry: ±`CLOCK_SEARCH_S` in
/// steps of `CLOCK_STEP_S`, then a parabola through the best and its neighbours.
const CLOCK_SEARCH_S: f64 = 0.2;
const CLOCK_STEP_S: f64 = 0.005;

/// The correction of the lidar's clock offset against the odometry's, seconds (added to
/// its stamps, beyond the configured `time_offset_s`): the offset at which the two tracks'
/// turns line up best ([`turn_agreement`], over the same steps at every offset),
/// with the wider of the intervals the cost's curvature and a delete-a-block jackknife
/// give; `None` when the cost has no interior minimum in the search.
fn clock_offset(steps_at: &dyn Fn(i64, std::ops::Range<usize>) -> Vec<MotionStep>, poses: usize) -> Option<Interval> {
    let search = |centre: f64| (centre - CLOCK_SEARCH_S, centre + CLOCK_SEARCH_S);
    let (best, curvature_sigma) = clock_minimum(&|dt| steps_at(dt, 0..0), search(0.0)).ok()?;
    // The curvature treats every step as independent; neighbouring steps share their errors,
    // so the interval is also the delete-a-block jackknife's, whichever is wider. Each
    // reduced search stays near the whole log's minimum (the jackknife measures how that
    // minimum moves, not which of two far minima a reduced log prefers); one whose
    // minimum leaves that neighbourhood counts at its edge.
    let k = CLOCK_JACKKNIFE_BLOCKS;
    let near = (best - CLOCK_JACKKNIFE_REACH_S, best + CLOCK_JACKKNIFE_REACH_S);
    let reduced: Vec<f64> = (0..k)
        .map(|b| match clock_minimum(&|dt| steps_at(dt, b * poses / k..(b + 1) * poses / k), near) {
            Ok((m, _)) => m.clamp(near.0, near.1),
            Err(edge) => edge.unwrap_or(best),
        })
        .collect();
    let sigma = curvature_sigma.max(jackknife_sigma(&reduced, false));
    Some(Interval::of(best, sigma))
}

/// Blocks of SLAM poses left out in turn for the clock's jackknife.
const CLOCK_JACKKNIFE_BLOCKS: usize = 10;
/// How far from the whole log's minimum a reduced search looks, seconds.
const CLOCK_JACKKNIFE_REACH_S: f64 = 0.05;

/// The least turn-agreement cost over the search (the parabola's vertex through the best
/// grid offset and its neighbours), with the curvature's standard error. `Err(Some(edge))`
/// when the least cost is at an edge of the search, `Err(None)` when a grid offset has no
/// cost or the cost is flat at its least.
fn clock_minimum(steps_at: &dyn Fn(i64) -> Vec<MotionStep>, (from, to): (f64, f64)) -> Result<(f64, f64), Option<f64>> {
    let n = ((to - from) / CLOCK_STEP_S).round() as i64;
    let mut costs = Vec::new();
    for k in 0..=n {
        let dt = from + k as f64 * CLOCK_STEP_S;
        let (_, c, m) = turn_agreement(&steps_at(crate::offset_ns(dt))).ok_or(None)?;
        costs.push((dt, c, m));
    }
    let best = (0..costs.len()).min_by(|&a, &b| costs[a].1.total_cmp(&costs[b].1)).ok_or(None)?;
    if best == 0 || best + 1 >= costs.len() {
        return Err(Some(costs[best].0));
    }
    let ((x0, y0, _), (_, y1, m), (_, y2, _)) = (costs[best - 1], costs[best], costs[best + 1]);
    let h = CLOCK_STEP_S;
    let a = (y0 - 2.0 * y1 + y2) / (2.0 * h * h);
    if a.is_nan() || a <= 0.0 {
        return Err(None);
    }
    let vertex = x0 + h - (y2 - y0) / (4.0 * a * h);
    // Σ r² ≈ a (δ − δ₀)² + min: var(δ) = σ² / a with σ² = min / (m − 2).
    let sigma2 = y1 / (m.saturating_sub(2).max(1)) as f64;
    Ok((vertex, (sigma2 / a).sqrt()))
}

/// A correction's interval moved by the configured value it corrects.
fn shifted(i: Interval, by: f64) -> Interval {
    Interval { value: i.value + by, low: i.low + by, high: i.high + by }
}

/// No change smaller than its interval is claimed: a configured value inside the
/// estimate's interval stays.
fn claim(i: Interval, configured: f64) -> f64 {
    if i.contains(configured) {
        configured
    } else {
        i.value
    }
}

/// What the lidar–odometry comparison gave.
struct Estimate {
    motion: LidarOdometry,
    odometry: String,
    clock: Option<Interval>,
}

/// The true mount `Δ ∘ M′` from the configured one and `Δ` (yaw, x, y), with intervals.
fn corrected(e: &LidarOdometry, m: &Mount3) -> (Interval, Option<[Interval; 2]>) {
    let phi = e.yaw.value;
    let yaw = Interval { value: m.yaw + phi, low: m.yaw + e.yaw.low, high: m.yaw + e.yaw.high };
    // x, y = Δ's translation + R_φ (the configured translation): the yaw's uncertainty
    // moves the second term by up to |t_M′| times its half-width.
    let swing = m.x.hypot(m.y) * e.yaw.half_width();
    let lever = e.lever.map(|[dx, dy]| {
        let (rx, ry) = (phi.cos() * m.x - phi.sin() * m.y, phi.sin() * m.x + phi.cos() * m.y);
        let shift =
            |i: Interval, by: f64| Interval { value: i.value + by, low: i.low + by - swing, high: i.high + by + swing };
        [shift(dx, rx), shift(dy, ry)]
    });
    (yaw, lever)
}

fn sensors_of(
    est: &Estimate,
    lidar: &str,
    configured: &Mount3,
    undetermined: &mut Vec<String>,
) -> Vec<SensorCalibration> {
    let (e, odometry) = (&est.motion, &est.odometry);
    let (yaw, lever) = corrected(e, configured);
    if est.clock.is_none() {
        undetermined.push(format!(
            "`{lidar}`'s clock offset against the odometry: the fit's cost has no minimum within ±{CLOCK_SEARCH_S} s"
        ));
    }
    if lever.is_none() {
        undetermined.push(format!(
            "`{lidar}`'s x and y: the log's turns do not fix them (a straight drive never shows a lever arm)"
        ));
    }
    let base = SensorCalibration {
        name: lidar.to_string(),
        kind: SensorKind::Lidar,
        x: lever.map(|l| l[0]),
        y: lever.map(|l| l[1]),
        yaw: Some(yaw),
        z: None,
        roll: None,
        pitch: None,
        time_offset_s: est.clock,
        scale: None,
        wheel_base: None,
        cost_before: e.cost_before_m,
        cost_after: e.cost_after_m,
        steps: [e.steps, e.turning_steps],
        clock_curve: Vec::new(),
        yaw_curve: Vec::new(),
    };
    let wheels = SensorCalibration {
        name: odometry.to_string(),
        kind: SensorKind::WheelOdometry,
        x: None,
        y: None,
        yaw: None,
        time_offset_s: None,
        scale: Some(e.scale),
        wheel_base: e.wheel_base,
        ..base.clone()
    };
    vec![base, wheels]
}

/// `calibration.toml`: the lidar's `[[sensor]]` table with the corrected mount, ready to
/// paste, and the odometry's scale as a comment (fusemap has no key for it: the
/// estimator learns it).
fn calibration_toml(est: &Estimate, name: &str, topic: &str, m: &Mount3, configured_offset: f64) -> String {
    let (e, odometry) = (&est.motion, &est.odometry);
    let (yaw, lever) = corrected(e, m);
    let mut s = String::new();
    let q = |v: &str| serde_json::to_string(v).unwrap_or_default();
    let _ = writeln!(
        s,
        "# The lidar's mount from its motion (SLAM) against the wheel odometry's, {} steps ({} turning);\n\
         # residual RMS {:.4} m before, {:.4} m after. 95 % intervals:",
        e.steps, e.turning_steps, e.cost_before_m, e.cost_after_m
    );
    let _ = writeln!(s, "#   yaw {:.5} rad ({:.5} .. {:.5})", yaw.value, yaw.low, yaw.high);
    match lever {
        Some([x, y]) => {
            let _ = writeln!(
                s,
                "#   x {:.4} m ({:.4} .. {:.4}), y {:.4} m ({:.4} .. {:.4})",
                x.value, x.low, x.high, y.value, y.low, y.high
            );
        }
        None => {
            let _ = writeln!(s, "#   x, y: not determined by this log (too few turns); kept as configured");
        }
    }
    if let Some(c) = est.clock {
        let _ = writeln!(s, "#   time_offset_s {:.4} s ({:.4} .. {:.4}), against the odometry", c.value, c.low, c.high);
    }
    let _ = writeln!(s, "[[sensor]]\nkind = \"lidar\"\nname = {}\ntopic = {}", q(name), q(topic));
    // Always written: a table pasted without it would reset the clock to 0.
    let _ = writeln!(s, "time_offset_s = {}", est.clock.map_or(configured_offset, |c| claim(c, configured_offset)));
    let (x, y) = lever.map_or((m.x, m.y), |[x, y]| (claim(x, m.x), claim(y, m.y)));
    let _ = writeln!(s, "\n[sensor.base_from_sensor]");
    for (k, v) in [("x", x), ("y", y), ("z", m.z), ("roll", m.roll), ("pitch", m.pitch), ("yaw", claim(yaw, m.yaw))] {
        let _ = writeln!(s, "{k} = {v}");
    }
    let _ = writeln!(
        s,
        "\n# The wheel odometry {}: it reports {:.4} × the distance driven (95 %: {:.4} .. {:.4}).\n\
         # fusemap has no key for it: the estimator learns the scale (estimator.odometry_scale_prior_sigma).",
        q(odometry),
        e.scale.value,
        e.scale.low,
        e.scale.high
    );
    if let Some(b) = e.wheel_base {
        let _ = writeln!(
            s,
            "# Its true wheel base is {:.4} × the one it assumes (95 %: {:.4} .. {:.4}).",
            b.value, b.low, b.high
        );
    }
    s
}
