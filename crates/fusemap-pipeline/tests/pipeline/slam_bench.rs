//! The SLAM generalisation bench (`fusemap slam-bench`) as acceptance tests: every
//! corrected CARMEN log of `../shared/datasets` turned into a raw log with odometry of a
//! known error, mapped with the default configuration, scored against the corrected poses.
//! Tuning logs and held-out logs alike must meet the bounds; each test prints its table
//! (`-- --nocapture`). Skips with a notice without `../shared`.

use fusemap_core::config::Config;
use fusemap_io::testdata::dataset;
use fusemap_pipeline::slam_bench::{run_case, table_row, CaseResult, Drift, BENCH_LOGS, TABLE_HEADER};

/// Runs `logs` (names; all when empty) with `drift`, printing the table.
fn bench(logs: &[&str], drift: Drift, distinct_stamps: bool) -> Option<Vec<CaseResult>> {
    let plan = Config::default().validate().unwrap();
    // One directory per bench call (tests run in parallel), removed at the end.
    let scratch = fusemap_io::testdata::temp_dir(&format!(
        "slam-bench-{}{}",
        drift.name(),
        if distinct_stamps { "-distinct" } else { "" }
    ));
    let mut out = Vec::new();
    for log in BENCH_LOGS.iter().filter(|l| logs.is_empty() || logs.contains(&l.name)) {
        let path = dataset(log.path)?;
        let r = run_case(log, &path, drift, distinct_stamps, &plan, &scratch).unwrap();
        out.push(r);
    }
    eprintln!("{TABLE_HEADER}");
    for r in &out {
        eprintln!("{}", table_row(r));
    }
    Some(out)
}

/// Every log with mild drift, run once per test binary: its own test and the equal-stamp
/// test (which compares two of its cases with distinct-stamp runs) both read it.
fn mild_drift_cases() -> Option<&'static [CaseResult]> {
    static MILD: std::sync::OnceLock<Option<Vec<CaseResult>>> = std::sync::OnceLock::new();
    MILD.get_or_init(|| bench(&[], Drift::Mild, false)).as_deref()
}

/// Asserts every case's revisit mean against its drift's bound.
fn assert_revisits(results: &[CaseResult]) {
    let failed: Vec<String> = results
        .iter()
        .filter(|r| r.slam.revisit.scored > 0 && r.slam.revisit.translation_mean_m > r.drift.revisit_bound_m())
        .map(|r| format!("{} {}: {:.4} m", r.log, r.drift.name(), r.slam.revisit.translation_mean_m))
        .collect();
    assert!(failed.is_empty(), "revisit mean above the bound: {failed:?}");
}

#[test]
fn zero_drift_revisits_within_10_cm() {
    if let Some(r) = bench(&[], Drift::Zero, false) {
        assert_revisits(&r);
    }
}

#[test]
fn mild_drift_revisits_within_15_cm() {
    if let Some(r) = mild_drift_cases() {
        assert_revisits(r);
    }
}

/// Every log but Örebro, whose case is its own test below (not met yet).
#[test]
fn strong_drift_revisits_within_25_cm() {
    let logs: Vec<&str> = BENCH_LOGS.iter().map(|l| l.name).filter(|n| *n != "orebro").collect();
    if let Some(r) = bench(&logs, Drift::Strong, false) {
        assert_revisits(&r);
    }
}

/// Not met yet (run with `-- --ignored`): Örebro's last ten scans return to its start
/// after 220 m at about a metre a scan, and no search of them against the first submap
/// reaches the score threshold, so the loop stays open (revisit mean 0.31 m).
#[test]
#[ignore = "not met: orebro strong drift revisit mean 0.31 m, the return to the start stays open"]
fn strong_drift_revisits_within_25_cm_on_orebro() {
    if let Some(r) = bench(&["orebro"], Drift::Strong, false) {
        assert_revisits(&r);
    }
}

/// Not met yet (kept as the target, run with `-- --ignored`): with perfect odometry SLAM
/// moves the trajectory 0.11–0.46 m RMS from the corrected poses on the long logs
/// (docs/SLAM.md has the table and what is known of why).
#[test]
#[ignore = "not met: zero-drift ATE 0.11-0.46 m on csail, acapulco, fhw, freiburg-campus, infinite-corridor"]
fn zero_drift_ate_within_10_cm() {
    if let Some(r) = bench(&[], Drift::Zero, false) {
        let failed: Vec<String> =
            r.iter().filter(|r| r.slam.ate_m > 0.10).map(|r| format!("{}: {:.3} m", r.log, r.slam.ate_m)).collect();
        assert!(failed.is_empty(), "ATE above 0.10 m: {failed:?}");
    }
}

/// Logs whose stamps are all one number (printed with `%g`) are placed in file order: they
/// score as well as the same log with distinct stamps (revisit mean within 1 cm or 10 %),
/// and SLAM keeps a pose for every scan (`run_case` checks the count).
#[test]
fn equal_stamp_logs_score_as_well_as_with_distinct_stamps() {
    let logs = ["csail", "orebro"];
    let (Some(mild), Some(distinct)) = (mild_drift_cases(), bench(&logs, Drift::Mild, true)) else {
        return;
    };
    for d in &distinct {
        let e = mild.iter().find(|r| r.log == d.log).expect("the mild run holds every log");
        let (a, b) = (e.slam.revisit.translation_mean_m, d.slam.revisit.translation_mean_m);
        assert!(a <= (b * 1.1).max(b + 0.01), "{}: equal stamps {a:.4} m vs distinct {b:.4} m", e.log);
    }
}
