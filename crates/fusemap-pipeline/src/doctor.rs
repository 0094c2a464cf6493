//! The log doctor: what is wrong with a log's timing, before blaming the map (the design
//! document's §4.3 habits, built in): per topic, message count, rate and jitter, time
//! span, header-stamp delay against the log's receive time, stamp regressions and gaps;
//! for the scan topic, the share of scans that get a pose under each sync mode; then
//! findings in plain words.
//!
//! The figures of a topic's row, over its header stamps:
//!
//! * `rate` = (messages − 1) / `span`, `span` = latest − earliest stamp;
//! * `period jitter` = standard deviation of the periods between successive distinct
//!   stamps in time order;
//! * `delay` = receive time − header stamp (smallest, mean, largest), where the format
//!   records a receive time (ROS log time, CARMEN `logger_ts`);
//! * `backwards` = stamps earlier than the one before them in the order the log holds
//!   them (log-time order for ROS containers, file order for CARMEN);
//! * `duplicates` = stamps equal to an earlier one;
//! * `gaps` = pauses between successive stamps in time order longer than
//!   `log.max_pose_gap_s`.
//!
//! Everything but `backwards` is taken in time order, as the mapper takes a pose track
//! and the scans it poses from one: a message that arrives late does not open a pause.
//! The doctor uses the mapper's own functions (the first pass, the sensor binding, the
//! pose track), so what it says is what `fusemap map` will do.

use crate::job::{plan_of, JobError};
use crate::log_findings::{stream_findings, timing_rows, track_topic, Roles, Row};
use crate::recording::Inventory;
use crate::sync::Skipped;
use crate::sync::{limits, sync_mode};
use crate::track::Track;
use crate::PipelineError;
use fusemap_core::config::{LogConfig, Plan, SyncConfig};
use fusemap_core::geometry::quaternion_yaw;
use fusemap_core::time::{PoseTrack, Stamp, SyncMode, TimingLimits};
use fusemap_io::text::{printable, table_cell};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How the scan topic gets its poses.
struct Sync {
    topic: String,
    scans: u64,
    source: String,
    /// For a pose track: its topic, its counters, the configured mode and the shares.
    track: Option<TrackSync>,
}

struct TrackSync {
    topic: Option<String>,
    configured: SyncMode,
    interpolate: Skipped,
    nearest: Skipped,
    nearest_tolerance_s: f64,
    /// When `fusemap map` would run SLAM over the track: why, and how it poses the scans
    /// the track alone leaves without a pose.
    slam: Option<SlamCover>,
}

/// How SLAM poses the scans its pose track cannot (`slam.rs` does the same).
struct SlamCover {
    reason: String,
    /// Scans in a pause of the track: SLAM interpolates across it for the matcher's guess.
    in_pauses: u64,
    /// Scans before the track's first or after its last pose: matched from the scan before.
    outside: u64,
}

impl SlamCover {
    fn count(reason: String, track: &dyn PoseTrack, stamps: &[Stamp], offset: i64, mode: SyncMode) -> Self {
        let samples = track.samples();
        let mut cover = Self { reason, in_pauses: 0, outside: 0 };
        for s in stamps {
            let t = Stamp(s.0.saturating_add(offset));
            if track.pose_at(t, mode).is_err() {
                if crate::slam::across_gap(&samples, t).is_some() {
                    cover.in_pauses += 1;
                } else {
                    cover.outside += 1;
                }
            }
        }
        cover
    }

    /// The finding: every scan gets a pose, and how.
    fn finding(&self, topic: &str, scans: u64, source: &str) -> String {
        format!(
            "SLAM poses all {scans} scans on {topic}, also the {} that {source} alone leaves without a pose: {} in its \
             pauses, across which SLAM interpolates it as the scan matcher's first guess, and {} before its first or \
             after its last pose, matched from the scan before",
            self.in_pauses + self.outside,
            self.in_pauses,
            self.outside
        )
    }
}

/// What the doctor found.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The report as text (deterministic, for snapshot tests).
    pub text: String,
    /// Why `fusemap map` would refuse the log, when it would: a script running the doctor
    /// must see that as a failure, not only read it in the findings.
    pub refusal: Option<String>,
}

/// `fusemap doctor [--config C] LOG`, planned: the configuration read and checked once.
pub struct DoctorJob {
    /// The validated configuration (its `[log]` limits judge the timing).
    pub plan: Plan,
    /// The log.
    pub log: PathBuf,
}

impl DoctorJob {
    /// The configuration's plan (or the defaults') for the log at `log`.
    pub fn plan(config: Option<&Path>, log: &Path) -> Result<Self, JobError> {
        Ok(Self { plan: plan_of(config)?, log: log.to_path_buf() })
    }

    /// The report ([`report`]); a reader's error names its file.
    pub fn run(&self) -> Result<Report, JobError> {
        report(&self.plan, &self.log).map_err(|e| match e {
            PipelineError::Read(e) => JobError::File(e),
            e => JobError::Pipeline(e),
        })
    }
}

/// The doctor's report on the log at `path`.
pub fn report(plan: &Plan, path: &Path) -> Result<Report, PipelineError> {
    let log = Inventory::read_with(path, &plan.limits)?;
    let cfg = &plan.log;
    let limits = limits(cfg);
    let mut out = String::new();
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    writeln!(out, "log: {} ({})", printable(&name), log.format)?;
    writeln!(out)?;
    let rows = timing_rows(&log, limits);
    write_table(&mut out, &rows, limits)?;
    write_frames_and_skipped(&mut out, &log)?;

    let Posed { sync, notes, refusal } = how_posed(plan, &log);
    let mut findings: Vec<String> = Vec::new();

    if let Some(why) = &refusal {
        findings.push(format!("cannot be mapped: {why}"));
    }

    crate::pose_sensors_report::gnss_quality(plan, &log, &mut out, &mut findings)?;
    crate::pose_sensors_report::odometry_vs_gyro(&log, &mut out, &mut findings)?;

    if let Some(cut) = &log.truncated {
        findings.push(format!("the log is cut short (`fusemap map` maps it up to the cut): {cut}"));
    }
    findings.extend(log.malformed_note());
    let roles = sync
        .as_ref()
        .and_then(|s| {
            let tr = s.track.as_ref()?;
            Some(Roles { scans: Some(&s.topic), track: tr.topic.as_deref(), slam: tr.slam.is_some() })
        })
        .unwrap_or_default();
    stream_findings(&rows, roles, cfg, limits, &mut findings);
    if let Some(s) = &sync {
        write_sync(&mut out, s, cfg, &mut findings)?;
    }
    findings.extend(notes);
    writeln!(out)?;
    writeln!(out, "findings:")?;
    if findings.is_empty() {
        writeln!(out, "- no clock faults found")?;
    }
    for f in findings {
        writeln!(out, "- {}", printable(&f))?;
    }
    Ok(Report { text: out, refusal })
}

/// The timing table, one row a stream.
fn write_table(out: &mut String, rows: &[Row], limits: TimingLimits) -> Result<(), PipelineError> {
    writeln!(
        out,
        "| topic | kind | messages | rate Hz | period jitter ms | span s | delay min ms | delay mean ms | delay max ms | backwards | duplicates | gaps > {:.2} s |",
        limits.gap_s
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for (topic, kind, t) in rows {
        let ms = |s: f64| format!("{:.1}", s * 1e3);
        let (dmin, dmean, dmax) =
            t.delay.map_or(("-".into(), "-".into(), "-".into()), |d| (ms(d.min_s), ms(d.mean_s), ms(d.max_s)));
        writeln!(
            out,
            "| {} | {kind} | {} | {:.2} | {:.1} | {:.1} | {dmin} | {dmean} | {dmax} | {} | {} | {} |",
            table_cell(topic),
            t.count,
            t.rate_hz,
            t.jitter_s * 1e3,
            t.span_s,
            t.regressions,
            t.duplicates,
            t.gaps
        )?;
    }
    Ok(())
}

/// The static transforms and the record types the reader skipped.
fn write_frames_and_skipped(out: &mut String, log: &Inventory) -> Result<(), PipelineError> {
    if !log.tf_static.is_empty() {
        writeln!(out)?;
        for t in &log.tf_static {
            writeln!(
                out,
                "static transform {} -> {}: translation ({:.3}, {:.3}, {:.3}), yaw {:.2}°",
                printable(&t.parent),
                printable(&t.child),
                t.translation[0],
                t.translation[1],
                t.translation[2],
                quaternion_yaw(t.rotation).to_degrees()
            )?;
        }
    }
    for (t, n) in &log.stats.skipped_by_type {
        writeln!(out, "skipped {n} records of type {}", printable(t))?;
    }
    Ok(())
}

/// How `fusemap map` would pose the scans: the sync of the first lidar's scans to the
/// pose track (and SLAM over it), the notes of binding and choosing, or why it would refuse.
struct Posed {
    sync: Option<Sync>,
    notes: Vec<String>,
    refusal: Option<String>,
}

/// Binds the sensors and chooses the pose track as `fusemap map` does.
fn how_posed(plan: &Plan, log: &Inventory) -> Posed {
    let cfg = &plan.log;
    let mut notes = Vec::new();
    let mut sync = None;
    let mut refusal = None;
    match crate::run::prepare_track(plan, log) {
        Ok((bound, _, _)) if bound.lidars.is_empty() => {
            refusal = Some("every [[sensor]] of kind lidar is disabled".to_string());
        }
        Ok((bound, chosen, _)) => {
            notes.extend(bound.notes.iter().cloned());
            let topic = bound.lidars[0].topic.clone();
            let stamps = &log.scans[&topic].stamps;
            let offset = crate::offset_ns(bound.lidars[0].lidar.time_offset_s);
            match &chosen.track {
                Track::Timed(track) => {
                    let configured = sync_mode(cfg, stamps);
                    let nearest_cfg = LogConfig { sync: SyncConfig::Nearest, ..cfg.clone() };
                    let nearest = sync_mode(&nearest_cfg, stamps);
                    let tally = |mode: SyncMode| {
                        let mut skipped = Skipped::default();
                        for s in stamps {
                            if let Err(why) = track.pose_at(Stamp(s.0.saturating_add(offset)), mode) {
                                skipped.count(why);
                            }
                        }
                        skipped
                    };
                    let topic_of_track = track_topic(chosen.source, &bound);
                    let (slam_on, reason) = crate::slam::applies(plan, log, &bound, &chosen);
                    let slam = slam_on.then(|| SlamCover::count(reason, track.as_ref(), stamps, offset, configured));
                    sync = Some(Sync {
                        topic: topic.clone(),
                        scans: stamps.len() as u64,
                        source: chosen.name.clone(),
                        track: Some(TrackSync {
                            slam,
                            topic: topic_of_track,
                            configured,
                            interpolate: tally(SyncMode::Interpolate),
                            nearest: tally(nearest),
                            nearest_tolerance_s: match nearest {
                                SyncMode::Nearest { tolerance_s } => tolerance_s,
                                SyncMode::Interpolate => 0.0,
                            },
                        }),
                    });
                }
                Track::ScanLine(_) => {
                    sync = Some(Sync {
                        topic: topic.clone(),
                        scans: stamps.len() as u64,
                        source: chosen.name.clone(),
                        track: None,
                    })
                }
            }
            notes.extend(chosen.notes.iter().cloned());
            match crate::map_pass::check_streams(plan, log, &bound, &chosen.track) {
                Ok(n) => notes.extend(n),
                Err(e) => refusal = Some(e.to_string()),
            }
            refusal = refusal.or_else(|| unobservable(log, &bound));
        }
        Err(e) => refusal = Some(e.to_string()),
    }
    Posed { sync, notes, refusal }
}

/// Why `map` would write no map for want of readings, when it would: no lidar's topic
/// holds a reading its model takes as evidence.
fn unobservable(log: &Inventory, bound: &crate::sensors::Bound) -> Option<String> {
    let blind = |b: &crate::sensors::BoundLidar| {
        log.scans.get(&b.topic).is_none_or(|t| !t.readings.could_observe(&b.lidar.model))
    };
    if !bound.lidars.iter().all(blind) {
        return None;
    }
    let b = &bound.lidars[0];
    let (scans, r) = log.scans.get(&b.topic).map_or((0, Default::default()), |t| (t.stamps.len(), t.readings));
    if let Some((n, Some(why))) = log.scans.get(&b.topic).map(|t| &t.angle_faults).filter(|f| f.0 as usize == scans) {
        return Some(format!(
            "no cell would be observed: the angles of all {n} scans on `{}` are unusable; the first: {why}",
            b.topic
        ));
    }
    let p = b.lidar.model.params();
    Some(format!(
        "no cell would be observed: no reading of the {scans} scans on `{}` is a return within min_range = {} m and \
         max_range = {} m ({} readings below the messages' range_max{}; the others NaN, infinite, zero, negative or \
         no-returns)",
        b.topic,
        p.min_range,
        p.max_range,
        r.returns,
        if r.returns > 0 { format!(", from {} to {} m", r.nearest, r.farthest) } else { String::new() },
    ))
}

/// How the scans get their poses: the shares each sync mode poses, and what happens to the rest.
fn write_sync(out: &mut String, s: &Sync, cfg: &LogConfig, findings: &mut Vec<String>) -> Result<(), PipelineError> {
    writeln!(out)?;
    match &s.track {
        None => writeln!(
            out,
            "scans on {} are posed by the {}: no time synchronisation needed",
            printable(&s.topic),
            s.source
        )?,
        Some(tr) => {
            let share = |k: &Skipped| 100.0 * (s.scans - k.total()) as f64 / s.scans.max(1) as f64;
            if let Some(slam) = &tr.slam {
                writeln!(
                    out,
                    "scans on {} are posed by SLAM over {}, as `fusemap map` poses them ({}); {} alone gives a pose to:",
                    printable(&s.topic),
                    s.source,
                    slam.reason,
                    s.source
                )?;
            } else {
                writeln!(out, "scans on {} with a pose from {}:", printable(&s.topic), s.source)?;
            }
            writeln!(out, "  interpolate: {:.1} %", share(&tr.interpolate))?;
            writeln!(out, "  nearest within {:.0} ms: {:.1} %", tr.nearest_tolerance_s * 1e3, share(&tr.nearest))?;
            let skipped = if tr.configured == SyncMode::Interpolate { &tr.interpolate } else { &tr.nearest };
            let missing = skipped.total();
            if let Some(slam) = tr.slam.as_ref().filter(|_| missing > 0) {
                findings.push(slam.finding(&s.topic, s.scans, &s.source));
            } else if missing > 0 {
                let pct = 100.0 - share(skipped);
                // One decimal, or two when that would print a share that is not 0 as 0.0.
                let pct = if pct < 0.1 { format!("{pct:.2}") } else { format!("{pct:.1}") };
                let head = format!("{pct} % of scans on {} ({missing} of {})", s.topic, s.scans);
                if let SyncMode::Nearest { tolerance_s } = tr.configured {
                    findings.push(format!(
                        "{head} have no pose within {:.0} ms: raise the tolerance or use interpolation",
                        tolerance_s * 1e3
                    ));
                } else {
                    let mut why = Vec::new();
                    if skipped.before_first_pose > 0 {
                        why.push(format!("{} before the first pose", skipped.before_first_pose));
                    }
                    if skipped.after_last_pose > 0 {
                        why.push(format!("{} after the last pose", skipped.after_last_pose));
                    }
                    if skipped.in_pose_gap > 0 {
                        why.push(format!(
                            "{} in pauses of the pose track longer than {:.2} s across which the robot moved \
                             more than {} m or {}°",
                            skipped.in_pose_gap, cfg.max_pose_gap_s, cfg.gap_bridge_motion_m, cfg.gap_bridge_motion_deg
                        ));
                    }
                    findings.push(format!("{head} get no pose and are skipped: {}", why.join(", ")));
                }
            }
        }
    }
    Ok(())
}
