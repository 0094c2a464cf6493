//! `fusemap slam-bench`: the SLAM generalisation bench
//! ([`fusemap_pipeline::slam_bench`]) over the corrected CARMEN logs of `shared/datasets`,
//! printed as a markdown table (or one JSON object a case).

use anyhow::{bail, Context, Result};
use fusemap_pipeline::slam_bench::{meets_bounds, run_case, table_row, Drift, BENCH_LOGS, TABLE_HEADER};
use std::path::Path;

/// Runs every case of `logs` × `drifts` (all when empty), with `config`'s parameters.
pub fn run(
    shared: &Path,
    config: Option<&Path>,
    logs: &[String],
    drifts: &[String],
    distinct_stamps: bool,
    json: bool,
) -> Result<()> {
    let plan = super::plan_of(config)?;
    for l in logs {
        if !BENCH_LOGS.iter().any(|b| b.name == l) {
            let names: Vec<&str> = BENCH_LOGS.iter().map(|b| b.name).collect();
            bail!("--logs: no bench log `{l}` (the bench has {})", names.join(", "));
        }
    }
    let mut chosen = Vec::new();
    for d in drifts {
        match Drift::ALL.iter().find(|x| x.name() == d) {
            Some(x) => chosen.push(*x),
            None => bail!("--drift: `{d}` is not one of zero, mild, strong"),
        }
    }
    if chosen.is_empty() {
        chosen = Drift::ALL.to_vec();
    }
    let work = std::env::temp_dir().join(format!("fusemap-slam-bench-{}", std::process::id()));
    std::fs::create_dir_all(&work).with_context(|| format!("creating {}", work.display()))?;
    // The rewritten logs go, whether the bench ends or fails part-way.
    let failed = run_cases(shared, logs, &chosen, distinct_stamps, &plan, &work, json);
    let _ = std::fs::remove_dir_all(&work);
    let failed = failed?;
    if !json {
        println!("\n{failed} case(s) outside the acceptance bounds");
    }
    Ok(())
}

/// Runs and prints every case; the number outside the acceptance bounds.
fn run_cases(
    shared: &Path,
    logs: &[String],
    drifts: &[Drift],
    distinct_stamps: bool,
    plan: &fusemap_core::config::Plan,
    work: &Path,
    json: bool,
) -> Result<usize> {
    if !json {
        println!("{TABLE_HEADER}");
    }
    let mut failed = 0;
    for log in BENCH_LOGS.iter().filter(|b| logs.is_empty() || logs.iter().any(|l| l == b.name)) {
        let path = shared.join("datasets").join(log.path);
        for &drift in drifts {
            let r = run_case(log, &path, drift, distinct_stamps, plan, work)
                .with_context(|| format!("{} with {} drift", log.name, drift.name()))?;
            failed += usize::from(!meets_bounds(&r));
            if json {
                println!("{}", serde_json::to_string(&r)?);
            } else {
                println!("{}", table_row(&r));
            }
        }
    }
    Ok(failed)
}
