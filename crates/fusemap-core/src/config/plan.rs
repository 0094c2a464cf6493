//! The `[[sensor]]` tables planned: the keys every kind shares (name, topic, clock
//! offset) checked here, then each enabled table by its kind — lidars (`sensor.rs`),
//! cameras (`camera.rs`) and the pose sensors (`pose_sensor.rs`).

use super::camera::{plan_camera, PlannedCamera};
use super::pose_sensor::plan_pose_sensor;
use super::sensor::{plan_lidar, PlannedLidar, PlannedSensor, SensorConfig, SensorKind};
use super::{err, finite, FieldError};

/// The `[[sensor]]` tables, validated and sorted by what the run does with them.
pub(super) struct PlannedSensors {
    pub lidars: Vec<PlannedLidar>,
    pub cameras: Vec<PlannedCamera>,
    pub others: Vec<PlannedSensor>,
}

/// Validates the `[[sensor]]` tables into lidars, cameras and the other sensors. `prior`
/// is the map's prior (lidar probabilities must straddle it; camera free evidence must be
/// below it).
pub(super) fn plan_sensors(tables: &[SensorConfig], prior: f64) -> Result<PlannedSensors, FieldError> {
    let mut lidars = Vec::new();
    let mut cameras = Vec::new();
    let mut others = Vec::new();
    let mut names: Vec<String> = Vec::new();
    for (i, s) in tables.iter().enumerate() {
        let f = |name: &str| format!("sensor[{i}].{name}");
        if let Some(k) = s.foreign_keys().first() {
            return Err(err(f(k), format!("not a key of a `{}` sensor", s.kind.as_str())));
        }
        let name = sensor_name(tables, i, &names)?;
        names.push(name.clone());
        check_topic(tables, i)?;
        let offset = finite(&f("time_offset_s"), s.time_offset_s)?;
        if offset.abs() > 3600.0 {
            return Err(err(f("time_offset_s"), format!("must be within ±3600 s, got {offset}")));
        }
        if !s.enabled {
            continue;
        }
        if s.kind == SensorKind::Lidar {
            lidars.push(plan_lidar(i, s, name, prior)?);
            continue;
        }
        if s.kind == SensorKind::Camera {
            cameras.push(plan_camera(i, s, name, prior)?);
            continue;
        }
        others.push(plan_pose_sensor(i, s, name, offset)?);
    }
    Ok(PlannedSensors { lidars, cameras, others })
}

/// The name of table `i`: its `name`, else its kind's default numbered by the tables of
/// that kind before it; refused when empty or taken by an earlier table (`names`).
fn sensor_name(tables: &[SensorConfig], i: usize, names: &[String]) -> Result<String, FieldError> {
    let (s, f) = (&tables[i], |name: &str| format!("sensor[{i}].{name}"));
    let same_kind = tables[..i].iter().filter(|o| o.kind == s.kind).count();
    let name = match &s.name {
        Some(n) if n.trim().is_empty() => return Err(err(f("name"), "must not be empty")),
        Some(n) => n.clone(),
        None if same_kind == 0 => s.kind.default_name().to_string(),
        None => format!("{}{}", s.kind.default_name(), same_kind + 1),
    };
    if names.contains(&name) {
        return Err(err(f("name"), format!("`{name}` is used by two sensors")));
    }
    Ok(name)
}

/// Table `i`'s topic: not empty, and not read by an earlier enabled table of its kind.
fn check_topic(tables: &[SensorConfig], i: usize) -> Result<(), FieldError> {
    let (s, f) = (&tables[i], |name: &str| format!("sensor[{i}].{name}"));
    let Some(t) = &s.topic else { return Ok(()) };
    if t.trim().is_empty() {
        return Err(err(f("topic"), "must not be empty (leave it out to look for the usual topic)"));
    }
    let same = |o: &SensorConfig| o.enabled && o.kind == s.kind && o.topic.as_ref() == Some(t);
    if let Some(j) = tables[..i].iter().position(same).filter(|_| s.enabled) {
        return Err(err(
            f("topic"),
            format!("`{t}` is read by sensor[{j}] already: one `{}` table per topic", s.kind.as_str()),
        ));
    }
    Ok(())
}

/// The sensor a kind gets when the config lists none of it: looked for under its usual
/// topic, with default noise figures.
/// `None` for [`SensorKind::Lidar`], whose default is [`PlannedLidar`]'s, and for
/// [`SensorKind::Camera`], which is mapped only when the config lists it.
pub fn auto_sensor(kind: SensorKind) -> Option<PlannedSensor> {
    let mut s = plan_sensors(&[SensorConfig::new(kind)], 0.5).ok()?.others.pop()?;
    s.explicit = false;
    Some(s)
}
