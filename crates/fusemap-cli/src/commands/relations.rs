//! `fusemap relations --relations FILE --trajectory FILE.tum`: a trajectory scored by the
//! SLAM benchmark's relation errors (Kümmerle et al. 2009, "On measuring the accuracy of
//! SLAM algorithms"), the figures Hess et al. 2016 report in Table II.

use anyhow::{bail, Result};
use fusemap_core::metrics::score_relations;
use std::path::Path;

/// `fusemap relations`: reads both files, matches each relation's stamps to the nearest
/// trajectory pose within `tolerance_ms`, and prints the table (or one JSON object).
/// Fails when no relation could be scored: a mean over nothing would look like a result.
pub fn run(relations: &Path, trajectory: &Path, tolerance_ms: f64, json: bool) -> Result<()> {
    if !(tolerance_ms.is_finite() && tolerance_ms >= 0.0) {
        bail!("--tolerance-ms must be a finite number of milliseconds, at least 0 (got {tolerance_ms})");
    }
    // `as` saturates: an absurdly large tolerance becomes "any sample", not a wrap-around.
    let tolerance_ns = (tolerance_ms * 1e6).round() as i64;
    let rel = fusemap_io::relations::read_relations(relations)?;
    let traj = fusemap_io::trajectory::read_tum(trajectory)?;
    let score = score_relations(&rel, &traj, tolerance_ns);
    if score.scored == 0 {
        bail!(
            "{}: none of its {} relations has both stamps among the {} poses of {} (within {tolerance_ms} ms)",
            relations.display(),
            score.relations,
            traj.len(),
            trajectory.display()
        );
    }
    if json {
        println!("{}", serde_json::to_string(&score)?);
        return Ok(());
    }
    println!("relations        {}", score.relations);
    println!("scored           {}", score.scored);
    println!("unmatched        {}  (no pose within {tolerance_ms} ms of a stamp)", score.unmatched);
    println!(
        "translation (m)  {:.6} ± {:.6}  (max {:.6})",
        score.translation_mean_m, score.translation_std_m, score.translation_max_m
    );
    println!(
        "rotation (deg)   {:.6} ± {:.6}  (max {:.6})",
        score.rotation_mean_deg, score.rotation_std_deg, score.rotation_max_deg
    );
    Ok(())
}
