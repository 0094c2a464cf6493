//! `fusemap validate`: the design document's §5 on a log — the lidar-only (M1),
//! camera-only (M2) and fused (M3) maps from the log's earlier part, each sensor's held-out
//! hit rate on each, their entropies and the verdict. The job is the library's
//! ([`fusemap_pipeline::validate`]); this prints its table. The verdict is information:
//! the exit status is 0 whatever it says.

use crate::progress;
use anyhow::Result;
use fusemap_pipeline::validate::{ValidateJob, Validation, VALIDATE_NPZ};
use std::fmt::Write;
use std::path::Path;

/// `fusemap validate [--config C] --out DIR LOG`.
pub fn run(config: Option<&Path>, log: &Path, out: &Path) -> Result<()> {
    let job = ValidateJob::plan(config, log, out)?;
    let run = job.run(&mut progress::reporter())?;
    print!("{}", run.summary);
    print!("{}", table(&run.validation));
    println!("validation    {}", super::shown(&out.join(VALIDATE_NPZ)));
    println!("outputs       {}", super::shown(out));
    super::fail_without_map(&run.summary, out)
}

/// The validation as a table: a row per map, a column per held-out sensor's hit rate.
pub fn table(v: &Validation) -> String {
    let mut s = String::new();
    let held: Vec<&str> = v.held_out.iter().map(|h| h.sensor.as_str()).collect();
    let _ = writeln!(
        s,
        "validation    {:.0} % of the log held out; hit rates of its points on each map",
        100.0 * v.holdout_share
    );
    let mut head = format!("  {:<4} {:<24} {:>9}", "map", "sensors", "entropy");
    for h in &held {
        let _ = write!(head, " {:>12}", fusemap_io::text::printable(h));
    }
    let _ = writeln!(s, "{head}");
    for m in &v.maps {
        let names = fusemap_io::text::printable(&m.sensors.join(", ")).into_owned();
        let mut row = format!("  {:<4} {:<24} {:>9.4}", m.name, names, m.mean_entropy_nats);
        for h in &held {
            let rate = m.hit_rates.iter().find(|r| r.sensor == *h).and_then(|r| r.hit.rate);
            let _ = write!(row, " {:>12}", rate.map_or("-".to_string(), |r| format!("{r:.3}")));
        }
        let _ = writeln!(s, "{row}");
    }
    for m in &v.lidar_motion {
        let a = &m.agreement;
        let _ = writeln!(
            s,
            "  `{}`'s direction of travel (SLAM) against the pose sensors': {:+.2}° ± {:.2}° over {} straight steps",
            fusemap_io::text::printable(&m.lidar),
            a.median_deg,
            a.standard_error_deg,
            a.steps
        );
    }
    for n in &v.not_built {
        let _ = writeln!(s, "  not built: {}", fusemap_io::text::printable(n));
    }
    let code = serde_json::to_value(v.judgement.verdict).ok().and_then(|j| j.as_str().map(String::from));
    let _ = writeln!(
        s,
        "verdict       {}: {}",
        code.unwrap_or_default(),
        fusemap_io::text::printable(&v.judgement.sentence)
    );
    s
}
