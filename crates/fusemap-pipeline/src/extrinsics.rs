//! Where each sensor sits on the robot: `base_from_sensor` from the log (TF, or CARMEN
//! `ROBOTLASER1` laser poses) or the config, the two checked against each other.
//!
//! Extrinsics come before probabilities (the design document's §4.2): 2 cm of mount error
//! is a double wall no `p_occ` hides, so a mount the config gives that disagrees with the
//! log's beyond the tolerances is reported.

use crate::recording::ScanTopic;
use crate::sensors::BoundSensor;
use crate::{PipelineError, Stage};
use fusemap_core::config::{ExtrinsicsSource, LogConfig};
use fusemap_core::frames::{FrameTree, FrameTreeLimits, LookupError};
use fusemap_core::geometry::{normalize_angle, Mount3, Pose3};
use fusemap_core::time::Stamp;
use fusemap_io::log::Transform;
use serde::Serialize;

/// What was decided about one sensor's mount.
#[derive(Debug, Clone, Default, Serialize)]
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

/// The log's frame tree (`/tf_static` and `/tf`), with what it refused in plain words:
/// a second parent, a loop, a static transform given twice with different values.
pub fn frame_tree(cfg: &LogConfig, tf_static: &[Transform], tf_dynamic: &[Transform]) -> (FrameTree, Vec<String>) {
    let mut tree = FrameTree::new(FrameTreeLimits {
        max_gap_s: cfg.max_pose_gap_s,
        bridge_motion_m: cfg.gap_bridge_motion_m,
        bridge_motion_deg: cfg.gap_bridge_motion_deg,
        ..FrameTreeLimits::default()
    });
    // Each refusal is counted by the tree; the first few are spelt out.
    let mut first = Vec::new();
    for t in tf_static {
        let p = Pose3 { translation: t.translation, rotation: t.rotation };
        if let Err(e) = tree.add_static(&t.parent, &t.child, p) {
            if first.len() < 3 {
                first.push(format!("/tf_static {} → {}: {e}", t.parent, t.child));
            }
        }
    }
    for t in tf_dynamic {
        let p = Pose3 { translation: t.translation, rotation: t.rotation };
        if let Err(e) = tree.add_dynamic(t.stamp, &t.parent, &t.child, p) {
            if first.len() < 3 {
                first.push(format!("/tf {} → {}: {e}", t.parent, t.child));
            }
        }
    }
    let mut notes = Vec::new();
    let refused = tree.rejected().total();
    if refused > 0 {
        notes.push(format!("{refused} transforms refused by the frame tree; first: {}", first.join("; ")));
    }
    (tree, notes)
}

/// The log's mount of `frame` from the frame tree: a static chain, else the chain at
/// `stamp` (a sensor on a moving mount gets the mount at its first scan).
pub fn from_tf(tree: &FrameTree, base: &str, frame: &str, stamp: Option<Stamp>) -> Option<(Mount3, &'static str)> {
    if frame.is_empty() {
        return None;
    }
    if frame == base {
        return Some((Mount3::default(), "tf"));
    }
    match tree.lookup_static(base, frame) {
        Ok(p) => Some((p.to_mount(), "tf")),
        Err(LookupError::DynamicEdge { .. }) => tree.lookup(base, frame, stamp?).ok().map(|p| (p.to_mount(), "tf")),
        Err(_) => None,
    }
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
            return Err(PipelineError::refused(
                Stage::Mounts,
                format!("log.extrinsics = \"tf\" but the log has no transform {} → `{name}`", cfg.base_frame),
            ))
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
    tree: &FrameTree,
    base: &str,
    frame: &str,
    topic: &ScanTopic,
) -> Option<(Mount3, &'static str)> {
    from_tf(tree, base, frame, topic.stamps.iter().min().copied()).or_else(|| {
        topic.first_laser_pose.map(|(robot, laser)| {
            let p = robot.inverse() * laser;
            (Mount3 { x: p.x, y: p.y, yaw: p.theta, ..Default::default() }, "scan_line")
        })
    })
}

/// The sensor's mount, resolved as a lidar's is: `log.extrinsics` decides between the
/// config and the log's TF, and a config mount that disagrees with TF is reported.
pub(crate) fn sensor_mount(
    s: &BoundSensor,
    cfg: &LogConfig,
    tree: &FrameTree,
    frame: &str,
    stamp: Option<Stamp>,
    notes: &mut Vec<String>,
) -> Result<Mount3, PipelineError> {
    let log_mount = from_tf(tree, &cfg.base_frame, frame, stamp);
    let name = if frame.is_empty() { s.sensor.name.as_str() } else { frame };
    Ok(resolve(name, cfg, s.sensor.base_from_sensor, log_mount, notes)?.base_from_sensor)
}
