//! A lidar's frame, its mount and its sensor model — and, when one scan topic carries
//! several frame ids (two lasers publishing on one topic, a driver that renamed its frame
//! mid-log), a mount for each of those frames, so that every scan is placed from the
//! sensor that took it (REP 105: a measurement is expressed in its `header.frame_id`).

use crate::extrinsics::{lidar_mount_from_log, resolve, ExtrinsicsReport};
use crate::recording::Inventory;
use crate::sensors::BoundLidar;
use crate::{PipelineError, Stage};
use fusemap_core::config::LogConfig;
use fusemap_core::frames::FrameTree;
use fusemap_core::geometry::PlanarMount;
use fusemap_core::sensor::LidarModel;
use fusemap_io::text::printable;
use std::collections::BTreeMap;

/// A bound lidar's frame, its resolved mount and its sensor model: the frame the config
/// names, else the topic's most common one.
pub(crate) fn lidar_setup(
    b: &BoundLidar,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    notes: &mut Vec<String>,
) -> Result<(String, ExtrinsicsReport, LidarModel), PipelineError> {
    let topic = &inv.scans[&b.topic];
    let frame = b.lidar.frame.clone().or_else(|| topic.frame().map(str::to_string)).unwrap_or_default();
    let (ext, model) = frame_model(b, &frame, inv, tree, cfg, notes)?;
    if ext.source == "identity" && !frame.is_empty() && frame != cfg.base_frame {
        notes.push(format!(
            "lidar `{}`: no mount in the config or the log for `{}`; assumed at `{}`'s origin, facing forward \
             (give [sensor.base_from_sensor] if it is not)",
            b.lidar.name,
            printable(&frame),
            printable(&cfg.base_frame)
        ));
    }
    Ok((frame, ext, model))
}

/// The mount and sensor model of the lidar `b` when its scans say `frame`.
fn frame_model(
    b: &BoundLidar,
    frame: &str,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    notes: &mut Vec<String>,
) -> Result<(ExtrinsicsReport, LidarModel), PipelineError> {
    let topic = &inv.scans[&b.topic];
    let log_mount = lidar_mount_from_log(tree, &cfg.base_frame, frame, topic);
    let config_mount = b.lidar.mount_given.then_some(b.lidar.mount);
    let ext: ExtrinsicsReport = resolve(frame, cfg, config_mount, log_mount, notes)?;
    let planar: PlanarMount = ext.base_from_sensor.to_planar(b.lidar.max_tilt).map_err(|e| {
        PipelineError::refused(Stage::Mounts, format!("mount of lidar `{}` ({}): {e}", b.lidar.name, ext.source))
    })?;
    let mut params = *b.lidar.model.params();
    if !b.lidar.explicit {
        // Defaults suited to a typical indoor 2D lidar rather than the document's 10 m corridor.
        params.max_range = 40.0;
    }
    Ok((ext, LidarModel::new(params, planar)))
}

/// The other frame ids of the lidar's topic (besides `main`), each with its own mount and
/// model, and a note saying so. Empty when the config pins the lidar's `frame` or gives
/// its mount (both say: every scan of this topic is this one sensor). A frame whose mount
/// cannot be resolved keeps the main frame's, and the note says which.
pub(crate) fn other_frames(
    b: &BoundLidar,
    main: &str,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    notes: &mut Vec<String>,
) -> BTreeMap<String, (ExtrinsicsReport, LidarModel)> {
    let topic = &inv.scans[&b.topic];
    let others: Vec<&String> = topic.frames.keys().filter(|f| !f.is_empty() && *f != main).collect();
    if others.is_empty() {
        return BTreeMap::new();
    }
    let list = others.iter().map(|f| format!("`{}`", printable(f))).collect::<Vec<_>>().join(", ");
    if b.lidar.frame.is_some() || b.lidar.mount_given {
        notes.push(format!(
            "`{}` carries several frame ids ({list} besides `{}`): the config gives lidar `{}` one frame or mount, \
             which every scan is mapped with",
            printable(&b.topic),
            printable(main),
            b.lidar.name
        ));
        return BTreeMap::new();
    }
    let mut out = BTreeMap::new();
    let mut kept_main = Vec::new();
    for f in others {
        // Without a transform of its own the frame has no mount to use: `resolve` would
        // fall back to identity, which is a guess; the main frame's mount is the better one.
        if lidar_mount_from_log(tree, &cfg.base_frame, f, topic).is_none() {
            kept_main.push(format!("`{}` (no transform from `{}`)", printable(f), printable(&cfg.base_frame)));
            continue;
        }
        let mut scratch = Vec::new();
        match frame_model(b, f, inv, tree, cfg, &mut scratch) {
            Ok(m) => {
                out.insert(f.clone(), m);
            }
            Err(e) => kept_main.push(format!("`{}` ({e})", printable(f))),
        }
    }
    let mut note = format!(
        "`{}` carries several frame ids ({list} besides `{}`): each scan is mapped with the mount of its own frame",
        printable(&b.topic),
        printable(main)
    );
    for (f, (ext, _)) in &out {
        let m = &ext.base_from_sensor;
        note += &format!(
            "; `{}` from {}: x {:.3} m, y {:.3} m, yaw {:.2}°",
            printable(f),
            ext.source,
            m.x,
            m.y,
            m.yaw.to_degrees()
        );
    }
    if !kept_main.is_empty() {
        note += &format!("; with the main frame's mount, as theirs cannot be used: {}", kept_main.join(", "));
    }
    notes.push(note);
    out
}
