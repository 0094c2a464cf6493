//! Which of the log's topics feed which configured sensor.
//!
//! A sensor the config lists with a topic must find it in the log (a run that maps fewer
//! sensors than configured refuses, naming the missing topic and the ones the log has).
//! A kind the config does not list is looked for under its usual topic, then under the
//! log's only topic of that kind (CARMEN logs: `FLASER`, `ROBOTLASER1`, `RAWLASER1` for
//! the front laser, `ODOM`).

use crate::recording::Inventory;
use crate::{PipelineError, Stage};
use fusemap_core::config::{auto_sensor, Plan, PlannedLidar, PlannedSensor, SensorKind};
use fusemap_core::time::Stamp;
use std::collections::BTreeMap;

/// A lidar bound to its topic.
#[derive(Clone, Debug)]
pub struct BoundLidar {
    /// The plan's lidar.
    pub lidar: PlannedLidar,
    /// The topic it reads.
    pub topic: String,
}

/// A pose sensor bound to its topic.
#[derive(Clone, Debug)]
pub struct BoundSensor {
    /// The plan's sensor.
    pub sensor: PlannedSensor,
    /// The topic it reads.
    pub topic: String,
}

impl BoundSensor {
    /// `t` on the common clock: the sensor's `time_offset_s` added.
    pub fn stamp(&self, t: Stamp) -> Stamp {
        Stamp(t.0.saturating_add(crate::offset_ns(self.sensor.time_offset_s)))
    }
}

/// Every sensor of a run, bound to the log's topics.
#[derive(Clone, Debug, Default)]
pub struct Bound {
    /// The lidars, all mapped.
    pub lidars: Vec<BoundLidar>,
    /// The other sensors.
    pub sensors: Vec<BoundSensor>,
    /// What a user should know about the binding.
    pub notes: Vec<String>,
}

impl Bound {
    /// The first bound sensor of `kind`.
    pub fn first(&self, kind: SensorKind) -> Option<&BoundSensor> {
        self.sensors.iter().find(|s| s.sensor.kind == kind)
    }
}

/// Binds the plan's sensors to `topics` (topic name → message count, per kind).
pub fn bind(plan: &Plan, topics: &BTreeMap<SensorKind, BTreeMap<String, u64>>) -> Result<Bound, PipelineError> {
    let mut out = Bound::default();
    bind_lidars(plan, &LogTopics(topics), &mut out)?;
    bind_pose_sensors(plan, &LogTopics(topics), &mut out)?;
    // Cameras are planned apart (`Plan::cameras`) and bound when the run builds their
    // models from the log's images and camera info (`camera::build_camera`).
    Ok(out)
}

/// The log's topics by sensor kind, with their message counts.
struct LogTopics<'a>(&'a BTreeMap<SensorKind, BTreeMap<String, u64>>);

impl LogTopics<'_> {
    fn of(&self, k: SensorKind) -> &BTreeMap<String, u64> {
        static EMPTY: BTreeMap<String, u64> = BTreeMap::new();
        self.0.get(&k).unwrap_or(&EMPTY)
    }

    /// The topics of `k`, for an error message.
    fn list(&self, k: SensorKind) -> String {
        let v: Vec<&str> = self.of(k).keys().map(String::as_str).collect();
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    }
}

/// Each planned lidar to its topic (the configured one, else the usual one), one lidar a
/// topic; a note names the scan topics left unmapped.
fn bind_lidars(plan: &Plan, topics: &LogTopics, out: &mut Bound) -> Result<(), PipelineError> {
    let scans = topics.of(SensorKind::Lidar);
    for l in &plan.lidars {
        let topic = match &l.topic {
            Some(t) if scans.contains_key(t) => t.clone(),
            Some(t) => {
                return Err(PipelineError::refused(
                    Stage::Sensors,
                    format!(
                        "lidar `{}`: topic `{t}` is not in the log (its scan topics: {})",
                        l.name,
                        topics.list(SensorKind::Lidar)
                    ),
                ))
            }
            None => auto_topic(SensorKind::Lidar, scans).ok_or_else(|| match scans.len() {
                0 => PipelineError::refused(Stage::Sensors, "the log holds no laser scans"),
                _ => PipelineError::refused(
                    Stage::Sensors,
                    format!(
                        "the log has several scan topics ({}) and none is `/scan`: list the lidars as \
                     [[sensor]] tables with kind = \"lidar\" and their topics",
                        topics.list(SensorKind::Lidar)
                    ),
                ),
            })?,
        };
        if out.lidars.iter().any(|b| b.topic == topic) {
            return Err(PipelineError::refused(
                Stage::Sensors,
                format!("two lidars read topic `{topic}`: give each its own topic"),
            ));
        }
        out.lidars.push(BoundLidar { lidar: l.clone(), topic });
    }
    if plan.lidars.iter().all(|l| l.topic.is_none()) && scans.len() > out.lidars.len() {
        let unused: Vec<&str> =
            scans.keys().filter(|t| !out.lidars.iter().any(|b| &b.topic == *t)).map(String::as_str).collect();
        out.notes.push(format!(
            "scan topics not mapped (list them as [[sensor]] lidars to map them): {}",
            unused.join(", ")
        ));
    }
    Ok(())
}

/// The listed pose sensors to their topics; a kind not listed (nor disabled) bound to its
/// usual topic when the log has it.
fn bind_pose_sensors(plan: &Plan, topics: &LogTopics, out: &mut Bound) -> Result<(), PipelineError> {
    for kind in [SensorKind::WheelOdometry, SensorKind::Imu, SensorKind::Gnss, SensorKind::Pose] {
        let listed = plan.sensors.iter().filter(|s| s.kind == kind);
        let mut any = false;
        for s in listed {
            any = true;
            let topic = match &s.topic {
                Some(t) if topics.of(kind).contains_key(t) => t.clone(),
                Some(t) => {
                    return Err(PipelineError::refused(
                        Stage::Sensors,
                        format!(
                            "{} sensor `{}`: topic `{t}` is not in the log (its {} topics: {})",
                            kind.as_str(),
                            s.name,
                            kind.as_str(),
                            topics.list(kind)
                        ),
                    ))
                }
                None => auto_topic(kind, topics.of(kind)).ok_or_else(|| {
                    PipelineError::refused(
                        Stage::Sensors,
                        format!(
                            "{} sensor `{}`: no topic given and the log has no `{}` (its {} topics: {})",
                            kind.as_str(),
                            s.name,
                            kind.default_topic(),
                            kind.as_str(),
                            topics.list(kind)
                        ),
                    )
                })?,
            };
            out.sensors.push(BoundSensor { sensor: s.clone(), topic });
        }
        // A kind listed only as disabled is off, auto-detection included.
        if any || plan.disabled_kinds.contains(&kind) {
            continue;
        }
        if let (Some(topic), Some(sensor)) = (auto_topic(kind, topics.of(kind)), auto_sensor(kind)) {
            out.sensors.push(BoundSensor { sensor, topic });
        }
    }
    Ok(())
}

/// The usual topic of `kind`, else CARMEN's name for it, else the only topic.
fn auto_topic(kind: SensorKind, topics: &BTreeMap<String, u64>) -> Option<String> {
    if topics.contains_key(kind.default_topic()) {
        return Some(kind.default_topic().to_string());
    }
    let carmen: &[&str] = match kind {
        SensorKind::Lidar => &["FLASER", "ROBOTLASER1", "RAWLASER1"],
        SensorKind::WheelOdometry => &["ODOM"],
        _ => &[],
    };
    if let Some(t) = carmen.iter().find(|t| topics.contains_key(**t)) {
        return Some(t.to_string());
    }
    (topics.len() == 1).then(|| topics.keys().next().cloned()).flatten()
}

/// The topics of the first pass, by kind, with their message counts.
pub fn topics_by_kind(inv: &Inventory) -> BTreeMap<SensorKind, BTreeMap<String, u64>> {
    let mut m: BTreeMap<SensorKind, BTreeMap<String, u64>> = BTreeMap::new();
    for (t, s) in &inv.scans {
        m.entry(SensorKind::Lidar).or_default().insert(t.clone(), s.stamps.len() as u64);
    }
    for (t, v) in &inv.odom {
        m.entry(SensorKind::WheelOdometry).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.imu {
        m.entry(SensorKind::Imu).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.gnss {
        m.entry(SensorKind::Gnss).or_default().insert(t.clone(), v.len() as u64);
    }
    for (t, v) in &inv.poses {
        m.entry(SensorKind::Pose).or_default().insert(t.clone(), v.len() as u64);
    }
    m
}
