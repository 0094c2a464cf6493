//! What a log's streams and pose sensors say before any map is made: per stream, stamps
//! going backwards or repeated, header stamps far from the receive time, pauses (each
//! with what it means for the scans or the pose track); the GNSS fixes' quality; the wheel
//! odometry against the gyro. `fusemap doctor` prints them under its timing table, and
//! every mapping run keeps them (`summary.json`'s `log.log_findings`, `report.html`'s
//! findings), so the page a user sends a colleague holds them without a second command.

use crate::recording::Inventory;
use crate::sensors::Bound;
use crate::sync::limits;
use crate::track::{ChosenTrack, Track};
use fusemap_core::config::{LogConfig, Plan, PoseSource, SensorKind};
use fusemap_core::time::{Stamp, StreamTiming, TimingLimits};
use std::collections::BTreeMap;

/// What the mapper makes of the streams, for the findings' consequences: the scans it
/// poses from a pose track, that track's stream, and whether SLAM runs over it. Default:
/// no stream has a role (the scans are posed by their own lines, or nothing is bound).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Roles<'a> {
    /// The first lidar's topic, when its scans are posed from a timed pose track.
    pub scans: Option<&'a str>,
    /// The pose track's stream (an odometry topic, `/tf`), when it is one.
    pub track: Option<&'a str>,
    /// SLAM corrects the track.
    pub slam: bool,
}

/// The stream a pose track of `source` is built from, when it is one stream.
pub(crate) fn track_topic(source: PoseSource, bound: &Bound) -> Option<String> {
    match source {
        PoseSource::Odometry => bound.first(SensorKind::WheelOdometry).map(|b| b.topic.clone()),
        PoseSource::Tf => Some("/tf".to_string()),
        _ => None,
    }
}

/// The findings of the log `inv`, with the roles `map` gives its streams (`chosen`
/// posing the first lidar's scans, SLAM over it or not), in `fusemap doctor`'s words and
/// order: GNSS fix quality, odometry against the gyro, then stream by stream.
pub(crate) fn log_findings(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: &ChosenTrack,
    slam: bool,
) -> Vec<String> {
    let mut findings = Vec::new();
    // The doctor's text beside them is not kept: the run's report has its own tables.
    let mut text = String::new();
    let _ = crate::pose_sensors_report::gnss_quality(plan, inv, &mut text, &mut findings);
    let _ = crate::pose_sensors_report::odometry_vs_gyro(inv, &mut text, &mut findings);
    let track = track_topic(chosen.source, bound);
    let roles = match (&chosen.track, bound.lidars.first()) {
        (Track::Timed(_), Some(first)) => Roles { scans: Some(&first.topic), track: track.as_deref(), slam },
        _ => Roles::default(),
    };
    let limits = limits(&plan.log);
    stream_findings(&timing_rows(inv, limits), roles, &plan.log, limits, &mut findings);
    findings
}

/// The timing of one topic: `backwards` and the delays in log order, the rest in time order.
fn timing(header: &[Stamp], receive: &[Option<Stamp>], limits: TimingLimits) -> StreamTiming {
    let in_log_order = StreamTiming::analyze(header, receive, limits);
    let mut sorted = header.to_vec();
    sorted.sort_unstable();
    let in_time_order = StreamTiming::analyze(&sorted, &[], limits);
    StreamTiming { regressions: in_log_order.regressions, delay: in_log_order.delay, ..in_time_order }
}

/// "once", "3 times".
fn times(n: u64) -> String {
    if n == 1 {
        "once".into()
    } else {
        format!("{n} times")
    }
}

/// What a topic is to the mapper.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    /// The scans that are mapped, posed from a pose track.
    ScansOnTrack,
    /// The pose track.
    PoseTrack,
    /// Anything else.
    Other,
}

/// A row of the timing table: topic, kind and its timing.
pub(crate) type Row = (String, &'static str, StreamTiming);

/// Every stream's timing: the scans, each pose sensor's messages, and the dynamic TF.
pub(crate) fn timing_rows(log: &Inventory, limits: TimingLimits) -> Vec<Row> {
    fn add<T>(
        rows: &mut Vec<Row>,
        kind: &'static str,
        streams: &BTreeMap<String, Vec<T>>,
        stamps: impl Fn(&T) -> (Stamp, Option<Stamp>),
        limits: TimingLimits,
    ) {
        for (topic, items) in streams {
            let (header, receive): (Vec<Stamp>, Vec<Option<Stamp>>) = items.iter().map(&stamps).unzip();
            rows.push((topic.clone(), kind, timing(&header, &receive, limits)));
        }
    }
    let mut rows: Vec<Row> = Vec::new();
    for (topic, scans) in &log.scans {
        rows.push((topic.clone(), "scan", timing(&scans.stamps, &scans.receive, limits)));
    }
    add(&mut rows, "odometry", &log.odom, |o| (o.stamp, o.receive_stamp), limits);
    add(&mut rows, "gnss", &log.gnss, |o| (o.stamp, o.receive_stamp), limits);
    add(&mut rows, "pose", &log.poses, |o| (o.stamp, o.receive_stamp), limits);
    add(&mut rows, "imu", &log.imu, |o| (o.stamp, o.receive_stamp), limits);
    if !log.tf_dynamic.is_empty() {
        let h: Vec<Stamp> = log.tf_dynamic.iter().map(|t| t.stamp).collect();
        rows.push(("/tf".into(), "tf", timing(&h, &[], limits)));
    }
    rows
}

/// Findings per stream: stamps going backwards or repeated, header stamps far from the
/// receive time, pauses; each with what it means for the scans or the pose track.
pub(crate) fn stream_findings(
    rows: &[Row],
    roles: Roles,
    cfg: &LogConfig,
    limits: TimingLimits,
    findings: &mut Vec<String>,
) {
    for (topic, kind, t) in rows {
        let role = if roles.scans == Some(topic.as_str()) {
            Role::ScansOnTrack
        } else if roles.track == Some(topic.as_str()) {
            Role::PoseTrack
        } else {
            Role::Other
        };
        if t.regressions > 0 {
            let consequence = match role {
                Role::ScansOnTrack => ": the scans are mapped in stamp order",
                Role::PoseTrack => ": the pose track takes its samples in stamp order",
                Role::Other => "",
            };
            findings.push(format!("{topic} stamps go backwards {}{consequence}", times(t.regressions)));
        }
        if t.duplicates > 0 {
            let consequence =
                if role == Role::PoseTrack { ": the pose track uses the first sample of each stamp" } else { "" };
            findings.push(format!("{topic} repeats a stamp {}{consequence}", times(t.duplicates)));
        }
        if let Some(d) = t.delay {
            let spread = d.max_s - d.min_s;
            if d.far > 0 && d.far == d.count && spread <= limits.far_delay_s {
                // Every delay is far and they spread less than the limit: all have one sign.
                let (near, far) = (d.min_s.abs().min(d.max_s.abs()), d.min_s.abs().max(d.max_s.abs()));
                findings.push(format!(
                    "{topic}: every header stamp is {near:.3} to {far:.3} s {} the log's receive time: the stamps \
                     and the log count time from different origins (a CARMEN logger counts from the start of the \
                     log), which is no clock fault, but the delay cannot be judged",
                    if d.mean_s < 0.0 { "later than" } else { "earlier than" },
                ));
            } else if d.far > 0 {
                findings.push(format!(
                    "{topic}: {} header stamps are more than {:.1} s from the log's receive time (largest {:.3} s): check the sensor's clock",
                    d.far, limits.far_delay_s, d.max_s.abs().max(d.min_s.abs())
                ));
            }
        }
        if *kind != "scan" && t.gaps > 0 {
            let consequence = if role == Role::PoseTrack && roles.slam {
                ": SLAM interpolates the odometry across them as its scan matcher's first guess".to_string()
            } else if role == Role::PoseTrack {
                format!(
                    ": a scan inside one gets a pose only if the robot moved at most {} m and {}° across it",
                    cfg.gap_bridge_motion_m, cfg.gap_bridge_motion_deg
                )
            } else {
                String::new()
            };
            findings.push(format!(
                "{topic} pauses longer than {:.2} s {} (longest {:.2} s){consequence}",
                limits.gap_s,
                times(t.gaps),
                t.max_gap_s
            ));
        }
    }
}
