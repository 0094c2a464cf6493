//! The SLAM generalisation bench: every corrected CARMEN log turned into a raw one with
//! odometry of a known error, mapped with SLAM as a user's log would be, and scored
//! against the corrected poses.
//!
//! A corrected log's poses are GMapping's output, not ground truth: errors of a few
//! centimetres are within their own uncertainty, errors of metres are not. Each case:
//!
//! 1. the log's pose lines (scans and `ODOM` lines, in file order) are taken as the
//!    reference, and their increments corrupted by an [`OdometryErrorModel`] and
//!    integrated ([`Drift`]: none, mild, strong);
//! 2. the result is written into both pose fields of every scan line and onto the `ODOM`
//!    lines, the `NEFF` lines dropped, so that the default run takes the log as raw and runs
//!    SLAM ([`PoseLog`]);
//! 3. the run's optimised scan poses are scored against the reference: local relations
//!    (consecutive scans), revisit relations (a scan and an earlier one within 5 m, 60 s or,
//!    when the stamps cannot tell scans apart, 30 m of path before), and the absolute
//!    trajectory error after a rigid alignment; the corrupted odometry (SLAM off) beside.
//!
//! The logs are split in two: the four places whose raw logs are the SLAM benchmark's
//! (tuned on in earlier work) are the tuning set; the other seven are held out.

use crate::recording::Inventory;
use crate::run::prepare;
use crate::{PipelineError, Stage};
use fusemap_core::config::Plan;
use fusemap_core::geometry::Pose2;
use fusemap_core::metrics::{
    absolute_trajectory_error, consecutive_relations, revisit_relations, score_index_relations, IndexRelation,
    RelationScore, RevisitRule,
};
use fusemap_core::sim::OdometryErrorModel;
use fusemap_core::slam::SlamReport;
use fusemap_io::log::carmen::rewrite::{PoseLineKind, PoseLog};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One corrected log of the bench.
#[derive(Clone, Copy, Debug)]
pub struct BenchLog {
    /// Short name.
    pub name: &'static str,
    /// Path under `shared/datasets/`.
    pub path: &'static str,
    /// In the tuning set (else held out).
    pub tuning: bool,
}

/// Every corrected CARMEN log of `shared/datasets`.
pub const BENCH_LOGS: [BenchLog; 11] = [
    BenchLog { name: "intel", path: "intel/intel-corrected.log.gz", tuning: true },
    BenchLog { name: "aces", path: "aces/aces-corrected.log.gz", tuning: true },
    BenchLog { name: "freiburg-079", path: "freiburg-079/freiburg-079-corrected.log.gz", tuning: true },
    BenchLog { name: "csail", path: "csail/csail-corrected.log.gz", tuning: true },
    BenchLog { name: "acapulco", path: "acapulco/acapulco-corrected.log.gz", tuning: false },
    BenchLog { name: "fhw", path: "fhw/fhw-corrected.log.gz", tuning: false },
    BenchLog { name: "freiburg-101", path: "freiburg-101/freiburg-101-corrected.log.gz", tuning: false },
    BenchLog { name: "freiburg-campus", path: "freiburg-campus/freiburg-campus-corrected.log.gz", tuning: false },
    BenchLog { name: "infinite-corridor", path: "infinite-corridor/infinite-corridor-corrected.log.gz", tuning: false },
    BenchLog { name: "orebro", path: "orebro/orebro-corrected.log.gz", tuning: false },
    BenchLog { name: "seattle", path: "seattle/seattle-corrected.log.gz", tuning: false },
];

/// How wrong the odometry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Drift {
    /// The corrected poses as odometry: SLAM must not make them worse.
    Zero,
    /// [`OdometryErrorModel::mild`].
    Mild,
    /// [`OdometryErrorModel::strong`].
    Strong,
}

impl Drift {
    /// All three, in order.
    pub const ALL: [Drift; 3] = [Drift::Zero, Drift::Mild, Drift::Strong];

    /// The error model.
    pub fn model(self) -> OdometryErrorModel {
        match self {
            Drift::Zero => OdometryErrorModel::ZERO,
            Drift::Mild => OdometryErrorModel::mild(),
            Drift::Strong => OdometryErrorModel::strong(),
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Drift::Zero => "zero",
            Drift::Mild => "mild",
            Drift::Strong => "strong",
        }
    }

    /// The acceptance bound of the revisit relations' mean error, metres.
    pub fn revisit_bound_m(self) -> f64 {
        match self {
            Drift::Zero => 0.10,
            Drift::Mild => 0.15,
            Drift::Strong => 0.25,
        }
    }
}

/// A trajectory's scores.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TrackScore {
    /// Consecutive scans.
    pub local: RelationScore,
    /// Revisits.
    pub revisit: RelationScore,
    /// Absolute trajectory error after a rigid alignment (RMS, metres).
    pub ate_m: f64,
}

impl TrackScore {
    fn of(local: &[IndexRelation], revisit: &[IndexRelation], estimate: &[Pose2], truth: &[Pose2]) -> Self {
        Self {
            local: score_index_relations(local, estimate),
            revisit: score_index_relations(revisit, estimate),
            ate_m: absolute_trajectory_error(estimate, truth),
        }
    }
}

/// One case's result.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// The log.
    pub log: &'static str,
    /// In the tuning set.
    pub tuning: bool,
    /// The drift.
    pub drift: Drift,
    /// Stamps replaced by distinct ones.
    pub distinct_stamps: bool,
    /// Scans in the log.
    pub scans: usize,
    /// Distance driven by the reference, metres.
    pub path_m: f64,
    /// End-point error of the corrupted odometry, metres.
    pub odometry_end_error_m: f64,
    /// The SLAM run's scan poses.
    pub slam: TrackScore,
    /// The corrupted odometry (SLAM off).
    pub odometry: TrackScore,
    /// SLAM's counts and timings.
    pub counts: SlamReport,
    /// Wall time of the run (reading, SLAM), seconds.
    pub seconds: f64,
}

/// A case's seed: the same odometry for the same log and drift on every machine.
fn seed(log: &str, drift: Drift) -> u64 {
    log.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)) ^ drift as u64
}

/// Each scan's stamp in seconds when the stamps tell the scans apart (strictly
/// increasing), else `None`.
fn usable_seconds(stamps: &[f64]) -> Option<Vec<f64>> {
    stamps.windows(2).all(|w| w[1] > w[0]).then(|| stamps.to_vec())
}

/// Runs one case: `log` (a corrected CARMEN log) with `drift`, written to `workdir`,
/// mapped with `plan` (SLAM as the plan says; the default runs it on a raw log).
/// `distinct_stamps`: every pose line stamped 0.1 s after the last instead of as written.
pub fn run_case(
    log: &BenchLog,
    path: &Path,
    drift: Drift,
    distinct_stamps: bool,
    plan: &Plan,
    workdir: &Path,
) -> Result<CaseResult, PipelineError> {
    let t0 = Instant::now();
    let pose_log = PoseLog::read(path, plan.limits.decompressed_mib.saturating_mul(1 << 20))?;
    let reference: Vec<Pose2> = pose_log.poses.iter().map(|p| p.pose).collect();
    let odometry = drift.model().corrupt(&reference, seed(log.name, drift));
    let suffix = if distinct_stamps { "-distinct" } else { "" };
    let raw: PathBuf = workdir.join(format!("{}-{}{suffix}.log", log.name, drift.name()));
    pose_log.write(&odometry, distinct_stamps.then_some(0.1), &raw)?;
    let scan = |p: &&fusemap_io::log::carmen::rewrite::PoseLine| p.kind == PoseLineKind::Scan;
    let is_scan: Vec<bool> = pose_log.poses.iter().map(|p| scan(&p)).collect();
    let pick = |v: &[Pose2]| -> Vec<Pose2> { v.iter().zip(&is_scan).filter(|(_, s)| **s).map(|(p, _)| *p).collect() };
    let (truth, raw_scans) = (pick(&reference), pick(&odometry));
    let stamps: Vec<f64> = pose_log.poses.iter().filter(scan).map(|p| p.stamp_s).collect();
    let seconds = usable_seconds(&stamps);
    let local = consecutive_relations(&truth);
    let revisit = revisit_relations(&truth, seconds.as_deref(), &RevisitRule::default());
    let inv = Inventory::read(&raw)?;
    let (_, chosen, _) = prepare(plan, &inv)?;
    let Some(slam) = chosen.slam else {
        return Err(PipelineError::refused(
            Stage::Benchmark,
            format!("{}: SLAM did not run on the raw log", raw.display()),
        ));
    };
    let estimate: Vec<Pose2> = slam.scan_poses.iter().map(|s| s.1).collect();
    if estimate.len() != truth.len() {
        return Err(PipelineError::refused(
            Stage::Benchmark,
            format!("{}: SLAM gave {} scan poses for {} scans", raw.display(), estimate.len(), truth.len()),
        ));
    }
    // FUSEMAP_BENCH_DUMP=DIR: every scan's reference, odometry and SLAM pose, one line each.
    if let Ok(dir) = std::env::var("FUSEMAP_BENCH_DUMP") {
        let lines: String = (0..truth.len())
            .map(|k| {
                let [t, o, e] = [truth[k], raw_scans[k], estimate[k]];
                format!("{k} {} {} {} {} {} {} {} {} {}\n", t.x, t.y, t.theta, o.x, o.y, o.theta, e.x, e.y, e.theta)
            })
            .collect();
        let name = format!("{}-{}{suffix}", log.name, drift.name());
        let write = |file: String, text: String| {
            let path = Path::new(&dir).join(file);
            std::fs::write(&path, text).map_err(|e| PipelineError::Read(fusemap_io::Error::io(&path, e)))
        };
        write(format!("{name}.txt"), lines)?;
        let graph = serde_json::json!({ "nodes": slam.nodes, "edges": slam.edges, "open": slam.open_loops });
        write(format!("{name}.graph.json"), graph.to_string())?;
    }
    let path_m = truth.windows(2).map(|w| w[0].translation().distance(w[1].translation())).sum();
    let end = |v: &[Pose2]| v.last().map_or(Pose2::IDENTITY, |p| *p);
    let _ = std::fs::remove_file(&raw);
    Ok(CaseResult {
        log: log.name,
        tuning: log.tuning,
        drift,
        distinct_stamps,
        scans: truth.len(),
        path_m,
        odometry_end_error_m: end(&raw_scans).translation().distance(end(&truth).translation()),
        slam: TrackScore::of(&local, &revisit, &estimate, &truth),
        odometry: TrackScore::of(&local, &revisit, &raw_scans, &truth),
        counts: slam.counts,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Whether a case meets the acceptance bounds: revisit mean within the drift's bound, and
/// with zero drift an ATE of at most 0.10 m.
pub fn meets_bounds(r: &CaseResult) -> bool {
    let revisit_ok = r.slam.revisit.scored == 0 || r.slam.revisit.translation_mean_m <= r.drift.revisit_bound_m();
    let ate_ok = r.drift != Drift::Zero || r.slam.ate_m <= 0.10;
    revisit_ok && ate_ok
}

/// The table header of [`table_row`].
pub const TABLE_HEADER: &str = "| log | set | drift | scans | path (m) | odometry end error (m) | local (m) | revisit (m) | revisit relations | ATE (m) | SLAM off: local / revisit / ATE (m) | closures | s | bound |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---|";

/// One result as a markdown table row.
pub fn table_row(r: &CaseResult) -> String {
    format!(
        "| {}{} | {} | {} | {} | {:.0} | {:.2} | {:.4} | {:.4} | {} | {:.4} | {:.4} / {:.3} / {:.3} | {}/{} | {:.1} | {} |",
        r.log,
        if r.distinct_stamps { " (distinct stamps)" } else { "" },
        if r.tuning { "tuning" } else { "held out" },
        r.drift.name(),
        r.scans,
        r.path_m,
        r.odometry_end_error_m,
        r.slam.local.translation_mean_m,
        r.slam.revisit.translation_mean_m,
        r.slam.revisit.scored,
        r.slam.ate_m,
        r.odometry.local.translation_mean_m,
        r.odometry.revisit.translation_mean_m,
        r.odometry.ate_m,
        r.counts.loop_accepted,
        r.counts.loop_searches,
        r.seconds,
        if meets_bounds(r) { "met" } else { "**not met**" },
    )
}
