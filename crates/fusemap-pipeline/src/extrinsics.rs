//! Where each sensor sits on the robot: `base_from_sensor` from the log (TF, or CARMEN
//! `ROBOTLASER1` laser poses) or the config, the two checked against each other.
//!
//! Extrinsics come before probabilities (the design document's §4.2): 2 cm of mount error
//! is a double wall no `p_occ` hides, so a mount the config gives that disagrees with the
//! log's beyond the tolerances is reported.

use crate::recording::ScanTopic;
use crate::PipelineError;
use fusemap_core::config::{ExtrinsicsSource, LogConfig};
use fusemap_core::geometry::{normalize_angle, Mount3, Pose3};
use fusemap_io::log::Transform;
use serde::Serialize;
use std::collections::{HashMap, VecDeque};

/// The transform `base_from_frame` through a list of transforms taken as a tree (either
/// direction per edge), breadth first from `base`.
pub fn chain(transforms: &[Transform], base: &str, frame: &str) -> Option<Pose3> {
    let mut edges: HashMap<&str, Vec<(&str, Pose3)>> = HashMap::new();
    for t in transforms {
        let p = Pose3::new(t.translation, t.rotation);
        edges.entry(t.parent.as_str()).or_default().push((t.child.as_str(), p));
        edges.entry(t.child.as_str()).or_default().push((t.parent.as_str(), p.inverse()));
    }
    let mut seen: HashMap<&str, Pose3> = HashMap::from([(base, Pose3::IDENTITY)]);
    let mut queue = VecDeque::from([base]);
    while let Some(f) = queue.pop_front() {
        let here = seen[f];
        if f == frame {
            return Some(here);
        }
        for (next, p) in edges.get(f).into_iter().flatten() {
            if !seen.contains_key(next) {
                seen.insert(next, here.compose(p));
                queue.push_back(next);
            }
        }
    }
    None
}

/// What was decided about one sensor's mount.
#[derive(Debug, Clone, Serialize)]
pub struct ExtrinsicsReport {
    /// `tf` (static TF, else the first dynamic transforms), `scan_line` (CARMEN
    /// ROBOTLASER1), `config` or `identity`.
    pub source: String,
    /// The mount used.
    pub base_from_sensor: Mount3,
    /// The log's own mount, when it has one.
    pub from_log: Option<Mount3>,
    /// |translation difference| between log and config, metres.
    pub translation_difference_m: Option<f64>,
    /// |yaw difference| between log and config, degrees.
    pub yaw_difference_deg: Option<f64>,
}

/// The log's mount of `frame`: static TF first, then the first dynamic transforms.
pub fn from_tf(
    tf_static: &[Transform],
    tf_dynamic: &[Transform],
    base: &str,
    frame: &str,
) -> Option<(Mount3, &'static str)> {
    if frame.is_empty() {
        return None;
    }
    if frame == base {
        return Some((Mount3::default(), "tf"));
    }
    chain(tf_static, base, frame).or_else(|| chain(tf_dynamic, base, frame)).map(|p| (p.to_mount(), "tf"))
}

/// Resolves the mount of the sensor of `frame` (`name` for messages). `config_mount` is
/// the configured mount, if any; `scans` what the first pass saw of a lidar's topic.
pub fn resolve(
    name: &str,
    cfg: &LogConfig,
    config_mount: Option<Mount3>,
    log_mount: Option<(Mount3, &'static str)>,
    notes: &mut Vec<String>,
) -> Result<ExtrinsicsReport, PipelineError> {
    let (mut dt, mut dyaw) = (None, None);
    if let (Some((m, log_name)), Some(c)) = (log_mount, config_mount) {
        let t = (m.x - c.x).hypot(m.y - c.y);
        let y = normalize_angle(m.yaw - c.yaw).abs().to_degrees();
        dt = Some(t);
        dyaw = Some(y);
        if t > cfg.extrinsics_tolerance_m || y > cfg.extrinsics_tolerance_deg {
            notes.push(format!(
                "the log's mount of `{name}` ({log_name}: x {:.3}, y {:.3}, yaw {:.2}°) differs from the config's \
                 (x {:.3}, y {:.3}, yaw {:.2}°) by {t:.3} m and {y:.2}° (tolerances {} m, {}°)",
                m.x,
                m.y,
                m.yaw.to_degrees(),
                c.x,
                c.y,
                c.yaw.to_degrees(),
                cfg.extrinsics_tolerance_m,
                cfg.extrinsics_tolerance_deg
            ));
        }
    }
    let (source, mount) = match (cfg.extrinsics, log_mount, config_mount) {
        (ExtrinsicsSource::Config, _, Some(c)) | (ExtrinsicsSource::Auto, None, Some(c)) => ("config".to_string(), c),
        (ExtrinsicsSource::Config, _, None) | (ExtrinsicsSource::Auto, None, None) => {
            ("identity".to_string(), Mount3::default())
        }
        (ExtrinsicsSource::Auto | ExtrinsicsSource::Tf, Some((m, n)), _) => (n.to_string(), m),
        (ExtrinsicsSource::Tf, None, _) => {
            return Err(PipelineError::Refused(format!(
                "log.extrinsics = \"tf\" but the log has no transform {} → `{name}`",
                cfg.base_frame
            )))
        }
    };
    Ok(ExtrinsicsReport {
        source,
        base_from_sensor: mount,
        from_log: log_mount.map(|m| m.0),
        translation_difference_m: dt,
        yaw_difference_deg: dyaw,
    })
}

/// A lidar's mount from the log: TF of its frame, else CARMEN laser poses on its lines.
pub fn lidar_mount_from_log(
    tf_static: &[Transform],
    tf_dynamic: &[Transform],
    base: &str,
    frame: &str,
    topic: &ScanTopic,
) -> Option<(Mount3, &'static str)> {
    from_tf(tf_static, tf_dynamic, base, frame).or_else(|| {
        topic.first_laser_pose.map(|(robot, laser)| {
            let p = robot.inverse() * laser;
            (Mount3 { x: p.x, y: p.y, yaw: p.theta, ..Default::default() }, "scan_line")
        })
    })
}
