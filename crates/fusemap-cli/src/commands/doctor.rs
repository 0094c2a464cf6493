//! `fusemap doctor LOG`: what is wrong with a log's timing, before blaming the map (the
//! design document's §4.3 habits, built in): per topic, message count, rate and jitter,
//! time span, header-stamp delay against the log's receive time, stamp regressions and
//! gaps; for the scan topic, the share of scans that get a pose under each sync mode;
//! then findings in plain words.

use super::log_map::{build_track, choose_scan_topic, load, scan_stream_timing, sync_mode, TrackCounts};
use anyhow::Result;
use fusemap_core::config::{Config, SyncConfig};
use fusemap_core::time::{Stamp, StreamTiming, SyncMode, TimingLimits};
use std::fmt::Write as _;
use std::path::Path;

/// `fusemap doctor`.
pub fn run(config: Option<&Path>, path: &Path) -> Result<()> {
    let cfg = match config {
        Some(p) => fusemap_io::config_file::load_config(p)?,
        None => Config::default(),
    };
    let plan = cfg.validate().map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    print!("{}", report(&plan.log, path)?);
    Ok(())
}

/// The doctor's report as text (deterministic, for snapshot tests).
pub fn report(cfg: &fusemap_core::config::LogConfig, path: &Path) -> Result<String> {
    let log = load(path)?;
    let limits = TimingLimits { gap_s: cfg.max_pose_gap_s, far_delay_s: cfg.far_delay_s };
    let mut out = String::new();
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    writeln!(out, "log: {name} ({})", log.format)?;
    writeln!(out)?;
    writeln!(
        out,
        "| topic | kind | messages | rate Hz | period jitter ms | span s | delay mean ms | delay max ms | backwards | duplicates | gaps > {:.2} s |",
        limits.gap_s
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut rows: Vec<(String, &str, StreamTiming)> = Vec::new();
    for (topic, scans) in &log.scans {
        rows.push((topic.clone(), "scan", scan_stream_timing(scans, cfg)));
    }
    for (topic, odom) in &log.odom {
        let h: Vec<Stamp> = odom.iter().map(|o| o.stamp).collect();
        let r: Vec<Option<Stamp>> = odom.iter().map(|o| o.receive_stamp).collect();
        rows.push((topic.clone(), "odometry", StreamTiming::analyze(&h, &r, limits)));
    }
    if !log.tf_dynamic.is_empty() {
        let h: Vec<Stamp> = log.tf_dynamic.iter().map(|t| t.stamp).collect();
        rows.push(("/tf".into(), "tf", StreamTiming::analyze(&h, &[], limits)));
    }
    for (topic, kind, t) in &rows {
        let (dm, dx) = t
            .delay
            .map_or(("-".into(), "-".into()), |d| (format!("{:.1}", d.mean_s * 1e3), format!("{:.1}", d.max_s * 1e3)));
        writeln!(
            out,
            "| {topic} | {kind} | {} | {:.2} | {:.1} | {:.1} | {dm} | {dx} | {} | {} | {} |",
            t.count,
            t.rate_hz,
            t.jitter_s * 1e3,
            t.span_s,
            t.regressions,
            t.duplicates,
            t.gaps
        )?;
    }
    if !log.tf_static.is_empty() {
        writeln!(out)?;
        for t in &log.tf_static {
            writeln!(
                out,
                "static transform {} -> {}: translation ({:.3}, {:.3}, {:.3})",
                t.parent, t.child, t.translation[0], t.translation[1], t.translation[2]
            )?;
        }
    }
    for (t, n) in &log.stats.skipped_by_type {
        writeln!(out, "skipped {n} records of type {t}")?;
    }

    let mut findings: Vec<String> = Vec::new();
    for (topic, kind, t) in &rows {
        if t.regressions > 0 {
            findings.push(format!("{topic} stamps go backwards {} times", t.regressions));
        }
        if t.duplicates > 0 {
            findings.push(format!("{topic} repeats a stamp {} times", t.duplicates));
        }
        if let Some(d) = t.delay {
            if d.far > 0 {
                findings.push(format!(
                    "{topic}: {} header stamps are more than {:.1} s from the log's receive time (largest {:.3} s): check the sensor's clock",
                    d.far, limits.far_delay_s, d.max_s.abs().max(d.min_s.abs())
                ));
            }
        }
        if *kind != "scan" && t.gaps > 0 {
            findings.push(format!(
                "{topic} pauses longer than {:.2} s {} times (longest {:.2} s): scans inside those pauses get no pose",
                limits.gap_s, t.gaps, t.max_gap_s
            ));
        }
    }

    let mut notes = Vec::new();
    if let Ok(topic) = choose_scan_topic(&log, cfg, &mut notes) {
        let scans = &log.scans[&topic];
        let mut counts = TrackCounts::default();
        match build_track(&log, cfg, scans, &mut counts) {
            Ok((_, super::log_map::Track::Buffer(buf), source)) => {
                let timing = scan_stream_timing(scans, cfg);
                let nearest_cfg = fusemap_core::config::LogConfig { sync: SyncConfig::Nearest, ..cfg.clone() };
                let nearest = sync_mode(&nearest_cfg, &timing);
                let configured = sync_mode(cfg, &timing);
                let share = |mode: SyncMode| {
                    let ok = scans.iter().filter(|s| buf.pose_at(s.scan.stamp, mode).is_ok()).count();
                    100.0 * ok as f64 / scans.len().max(1) as f64
                };
                let (si, sn) = (share(SyncMode::Interpolate), share(nearest));
                let tol = match nearest {
                    SyncMode::Nearest { tolerance_s } => tolerance_s,
                    SyncMode::Interpolate => 0.0,
                };
                writeln!(out)?;
                writeln!(out, "scans on {topic} with a pose from {source}:")?;
                writeln!(out, "  interpolate: {si:.1} %")?;
                writeln!(out, "  nearest within {:.0} ms: {sn:.1} %", tol * 1e3)?;
                let configured_share = if configured == SyncMode::Interpolate { si } else { sn };
                if configured_share < 99.95 {
                    let missing = 100.0 - configured_share;
                    if configured == SyncMode::Interpolate {
                        findings.push(format!(
                            "{missing:.1} % of scans on {topic} fall outside the pose track or in its gaps: they are skipped"
                        ));
                    } else {
                        findings.push(format!(
                            "{missing:.1} % of scans on {topic} have no pose within {:.0} ms: raise the tolerance or use interpolation",
                            tol * 1e3
                        ));
                    }
                }
                if counts.out_of_order + counts.duplicates > 0 {
                    findings.push(format!(
                        "the pose track drops {} samples that go backwards and {} repeated stamps",
                        counts.out_of_order, counts.duplicates
                    ));
                }
            }
            Ok((_, _, source)) => {
                writeln!(out)?;
                writeln!(out, "scans on {topic} are posed by the {source}: no time synchronisation needed")?;
            }
            Err(e) => findings.push(format!("no pose source: {e}")),
        }
    }
    findings.extend(notes);
    writeln!(out)?;
    writeln!(out, "findings:")?;
    if findings.is_empty() {
        writeln!(out, "- no clock faults found")?;
    }
    for f in findings {
        writeln!(out, "- {f}")?;
    }
    Ok(out)
}
