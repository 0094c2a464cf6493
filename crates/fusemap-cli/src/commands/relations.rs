//! `fusemap relations --relations FILE --trajectory FILE.tum`: a trajectory scored by the
//! SLAM benchmark's relation errors (Kümmerle et al. 2009, "On measuring the accuracy of
//! SLAM algorithms"), the figures Hess et al. 2016 report in Table II.

use anyhow::{bail, Result};
use fusemap_core::geometry::Pose2;
use fusemap_core::metrics::{score_trajectory, RelationMatching};
use std::path::Path;

/// `fusemap relations`: reads both files and scores the trajectory by
/// [`score_trajectory`] (the nearest pose within `tolerance_ms`, else interpolated across a
/// gap of at most `max_gap_ms`, optionally moved to the sensor), the rule the SLAM-benchmark
/// tests assert with, and prints the table (or one JSON object).
/// Fails when no relation could be scored: a mean over nothing would look like a result.
pub fn run(
    relations: &Path,
    trajectory: &Path,
    tolerance_ms: f64,
    max_gap_ms: f64,
    sensor: Option<&str>,
    json: bool,
) -> Result<()> {
    for (flag, v) in [("--tolerance-ms", tolerance_ms), ("--max-gap-ms", max_gap_ms)] {
        if !(v.is_finite() && v >= 0.0) {
            bail!("{flag} must be a finite number of milliseconds, at least 0 (got {v})");
        }
    }
    // `as` saturates: an absurdly large tolerance becomes "any sample", not a wrap-around.
    let mut matching = RelationMatching {
        tolerance_ns: (tolerance_ms * 1e6).round() as i64,
        max_gap_ns: (max_gap_ms * 1e6).round() as i64,
        ..RelationMatching::default()
    };
    if let Some(text) = sensor {
        matching.sensor_in_base = parse_pose(text)?;
    }
    let rel = fusemap_io::relations::read_relations(relations)?;
    let traj = fusemap_io::trajectory::read_tum(trajectory)?;
    let score = score_trajectory(&rel, &traj, &matching);
    if score.scored == 0 {
        bail!(
            "{}: none of its {} relations has both stamps among the {} poses of {} (within {tolerance_ms} ms, or between two poses at most {max_gap_ms} ms apart)",
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
    println!(
        "unmatched        {}  (no pose within {tolerance_ms} ms of a stamp, nor two at most {max_gap_ms} ms apart around it)",
        score.unmatched
    );
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

/// `X,Y,YAW` as a pose.
fn parse_pose(text: &str) -> Result<Pose2> {
    let v: Vec<f64> = text.split(',').map(|f| f.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| {
        anyhow::anyhow!("--sensor-in-base: `{text}` is not three numbers X,Y,YAW (metres, radians): {e}")
    })?;
    match v[..] {
        [x, y, yaw] if v.iter().all(|c| c.is_finite()) => Ok(Pose2::new(x, y, yaw)),
        _ => bail!("--sensor-in-base: `{text}` is not three finite numbers X,Y,YAW (metres, radians)"),
    }
}

#[cfg(test)]
mod tests {
    use super::parse_pose;

    #[test]
    fn a_sensor_pose_is_three_finite_numbers() {
        let p = parse_pose("0.04, 0,-1.5").unwrap();
        assert_eq!((p.x, p.y, p.theta), (0.04, 0.0, -1.5));
        for bad in ["0.04,0", "a,b,c", "1,2,3,4", "1,NaN,0", ""] {
            assert!(parse_pose(bad).unwrap_err().to_string().contains("--sensor-in-base"), "{bad}");
        }
    }
}
