//! A simulated run written as a user's robot would record it: a rosbag2 directory (MCAP
//! storage, standard message types — scans, odometry, IMU, GNSS, the semantic camera's
//! label and depth `sensor_msgs/Image`s and `CameraInfo` — CDR, `/tf_static` latched) with the ground truth
//! beside it — the occupancy map as map_server PGM + YAML, the class of every occupied
//! cell as a palette PNG + YAML, and the true trajectory as TUM.
//!
//! Scenario files are TOML mapping one to one onto
//! [`crate::Scenario`]; unknown keys are errors naming their line.

use crate::recording::TRUTH_BYTES_PER_CELL;
use crate::{Scenario, SimMessage, SimRecording, TruthRasterError, TruthSemantic, CLASS_COLORS, CLASS_NAMES};
use fusemap_core::grid::logodds::logit;
use fusemap_core::grid::{GridGeometry, OccupancyParams, Raster};
use fusemap_io::config_file::{field_error, read_text, toml_error};
use fusemap_io::log::ros2::writer::{OutMessage, Rosbag2Writer, Rosbag2WriterOptions, WrittenBag};
use fusemap_io::Result;
use std::path::{Path, PathBuf};

/// Reads and validates a scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    let text = read_text(path)?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let s: Scenario = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    s.validate().map_err(|e| field_error(path, text, &e.field, e.message))?;
    Ok(s)
}

/// The message to write for a simulated one: the same struct, on its own.
pub fn to_out_message(m: &SimMessage) -> OutMessage {
    match m {
        SimMessage::Scan(s) => OutMessage::LaserScan(s.msg.clone()),
        SimMessage::Odometry(o) => OutMessage::Odometry(o.msg.clone()),
        SimMessage::Imu(i) => OutMessage::Imu(i.msg.clone()),
        SimMessage::Fix(f) => OutMessage::NavSatFix(f.msg.clone()),
        SimMessage::StaticTransform(t) => OutMessage::Tf { is_static: true, transforms: vec![t.msg.clone()] },
        SimMessage::Image(i) => OutMessage::Image(i.msg.clone()),
        SimMessage::CameraInfo(c) => OutMessage::CameraInfo(c.msg.clone()),
    }
}

/// Writes `rec` as a rosbag2 directory at `dir`: every message with its header stamp as
/// log time, the static mounts as one latched `/tf_static` message (as a ROS static
/// broadcaster publishes them).
pub fn write_bag(rec: &SimRecording, dir: &Path, overwrite: bool) -> Result<WrittenBag> {
    let mut w = Rosbag2Writer::create_with(dir, Rosbag2WriterOptions { overwrite, ..Default::default() })?;
    let statics: Vec<&SimMessage> =
        rec.messages.iter().filter(|m| matches!(m, SimMessage::StaticTransform(_))).collect();
    write_statics(&mut w, &statics)?;
    for m in rec.messages.iter().filter(|m| !matches!(m, SimMessage::StaticTransform(_))) {
        w.write(m.stamp(), m.topic(), &to_out_message(m))?;
    }
    w.finish()
}

/// The static transforms as one latched `/tf_static` message at the first one's stamp, as
/// a robot's recorder keeps them, ahead of every other message.
fn write_statics(w: &mut Rosbag2Writer, statics: &[&SimMessage]) -> Result<()> {
    let Some(first) = statics.first() else { return Ok(()) };
    let transforms = statics
        .iter()
        .filter_map(|m| match m {
            SimMessage::StaticTransform(t) => Some(t.msg.clone()),
            _ => None,
        })
        .collect();
    w.write(first.stamp(), first.topic(), &OutMessage::Tf { is_static: true, transforms })
}

/// Why [`simulate_to`] wrote no simulation.
#[derive(Debug, thiserror::Error)]
pub enum SimulationError {
    /// The simulator refused its scenario.
    #[error("scenario: {0}")]
    Scenario(#[from] crate::SimError),
    /// A file could not be written (the error names it).
    #[error(transparent)]
    Write(#[from] fusemap_io::Error),
}

/// Runs `scenario` and writes it as [`write_simulation`] does, each message into the bag
/// as the simulator makes it ([`crate::simulate_with`]) instead of holding the recording:
/// a run holds two chunks of camera images, not every image (730 MiB for the production
/// line's three minutes). The files are byte for byte those of [`crate::simulate`] then
/// [`write_simulation`]. Returns the recording, without its messages, and the files.
pub fn simulate_to(
    scenario: &Scenario,
    out: &Path,
    resolution: f64,
    overwrite: bool,
    memory_bytes: u64,
) -> std::result::Result<(SimRecording, SimulationFiles), SimulationError> {
    scenario.validate().map_err(crate::SimError::Invalid)?;
    // The truth is rastered after the run, when its messages are in the bag: nothing of the
    // recording is held beside it.
    let geometry = truth_geometry(out, resolution, &scenario.world.extent, 0, memory_bytes)?;
    std::fs::create_dir_all(out).map_err(|e| fusemap_io::Error::io(out, e))?;
    let dir = out.join("bag");
    let mut w = Rosbag2Writer::create_with(&dir, Rosbag2WriterOptions { overwrite, ..Default::default() })?;
    let statics = crate::static_transforms(scenario);
    write_statics(&mut w, &statics.iter().collect::<Vec<_>>())?;
    // The first failed write is kept and ends the writing; the simulator runs on (it cannot
    // be stopped half-way) and its messages are dropped.
    let mut failed = None;
    let rec = crate::simulate_with(scenario, &mut |m| {
        if failed.is_none() && !matches!(m, SimMessage::StaticTransform(_)) {
            failed = w.write(m.stamp(), m.topic(), &to_out_message(&m)).err();
        }
    })?;
    if let Some(e) = failed {
        return Err(e.into());
    }
    let bag = w.finish()?;
    let files = write_truth(&rec, out, geometry, bag)?;
    Ok((rec, files))
}

/// The true occupancy as a map raster: occupied where an object covers the cell, free
/// elsewhere inside the hall.
pub fn truth_raster(rec: &SimRecording, geometry: GridGeometry) -> Result<Raster, TruthRasterError> {
    let t = rec.truth_occupancy(geometry)?;
    let params = OccupancyParams::default();
    let (occ, free) = (logit(params.clamp_max) as f32, logit(params.clamp_min) as f32);
    let origin = geometry.cell_corner(t.first_cell);
    Ok(Raster {
        width: t.width,
        height: t.height,
        resolution: geometry.resolution(),
        origin,
        first_cell: t.first_cell,
        log_odds: t.occupied.iter().map(|&o| if o { occ } else { free }).collect(),
        known: vec![true; t.occupied.len()],
        params,
    })
}

/// Writes the semantic truth as a palette PNG (one pixel per cell, north up, the palette
/// the class table's colours, so the pixel value is the class id) and a YAML beside it
/// naming the image, resolution, origin (lower-left corner of the lower-left cell, as
/// map_server's) and the classes. Returns the YAML's path.
pub fn write_truth_semantic(yaml_path: &Path, t: &TruthSemantic) -> Result<PathBuf> {
    let png_path = yaml_path.with_extension("png");
    let fail = |m: String| fusemap_io::Error::format(yaml_path, fusemap_io::Location::File, m);
    let (Ok(w), Ok(h)) = (u32::try_from(t.width), u32::try_from(t.height)) else {
        return Err(fail(format!("a {} × {} raster is too large for PNG", t.width, t.height)));
    };
    if w == 0 || h == 0 || w > i32::MAX as u32 || h > i32::MAX as u32 {
        return Err(fail(format!("a {} × {} raster cannot be a PNG", t.width, t.height)));
    }
    let name = png_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| fail("the image's file name is not valid UTF-8".into()))?
        .to_string();
    fusemap_io::atomic::write_atomic(&png_path, |out| {
        let mut e = png::Encoder::new(out, w, h);
        e.set_color(png::ColorType::Indexed);
        e.set_depth(png::BitDepth::Eight);
        e.set_palette(CLASS_COLORS.concat());
        let mut writer = e.write_header().map_err(std::io::Error::from)?;
        let mut data = Vec::with_capacity(t.width * t.height);
        for row in (0..t.height).rev() {
            data.extend_from_slice(&t.class_ids[row * t.width..(row + 1) * t.width]);
        }
        writer.write_image_data(&data).map_err(std::io::Error::from)?;
        writer.finish().map_err(std::io::Error::from)
    })?;
    let origin = t.geometry.cell_corner(t.first_cell);
    let mut yaml = format!(
        "# fusemap simulator: true class of every occupied cell (pixel value = class id, 0 free)\n\
         image: {name}\nresolution: {}\norigin: [{}, {}, 0.0]\nclasses:\n",
        t.geometry.resolution(),
        origin.x,
        origin.y
    );
    for (id, (n, c)) in CLASS_NAMES.iter().zip(CLASS_COLORS).enumerate() {
        yaml += &format!("  - {{id: {id}, name: {n}, color: [{}, {}, {}]}}\n", c[0], c[1], c[2]);
    }
    fusemap_io::atomic::write_atomic(yaml_path, |out| std::io::Write::write_all(out, yaml.as_bytes()))?;
    Ok(yaml_path.to_path_buf())
}

/// What [`write_simulation`] wrote.
pub struct SimulationFiles {
    /// The rosbag2 directory.
    pub bag: WrittenBag,
    /// `truth.yaml` (map_server; `truth.pgm` beside it).
    pub truth_map: PathBuf,
    /// `truth_semantic.yaml` (`truth_semantic.png` beside it).
    pub truth_semantic: PathBuf,
    /// `truth.tum`.
    pub truth_trajectory: PathBuf,
}

/// Writes the bag (`out/bag`), the true map (`out/truth.yaml` + `.pgm`, at `resolution`),
/// the true classes (`out/truth_semantic.yaml` + `.png`) and the true trajectory
/// (`out/truth.tum`). The truth is rastered first: a resolution the world cannot be
/// rastered at (too many cells, not a resolution, or more bytes than `memory_bytes`
/// leaves beside the recording, [`TRUTH_BYTES_PER_CELL`] a cell) is an error before
/// anything is written, never a run without its truth.
pub fn write_simulation(
    rec: &SimRecording,
    out: &Path,
    resolution: f64,
    overwrite: bool,
    memory_bytes: u64,
) -> Result<SimulationFiles> {
    let geometry = truth_geometry(out, resolution, &rec.extent, rec.held_bytes(), memory_bytes)?;
    std::fs::create_dir_all(out).map_err(|e| fusemap_io::Error::io(out, e))?;
    let bag = write_bag(rec, &out.join("bag"), overwrite)?;
    write_truth(rec, out, geometry, bag)
}

/// The grid the truth is rastered on, checked before anything is written: the world's
/// `extent` at `resolution` fits the truth rasters, and their bytes with the `held` bytes
/// of the recording fit `memory_bytes`.
fn truth_geometry(
    out: &Path,
    resolution: f64,
    extent: &crate::Rect,
    held: u64,
    memory_bytes: u64,
) -> Result<GridGeometry> {
    let no_truth = |why: String| no_truth(out, resolution, why);
    let geometry = GridGeometry::centered(resolution).map_err(|e| no_truth(e.to_string()))?;
    let cells = crate::recording::truth_cells(extent, geometry).map_err(|e| no_truth(e.to_string()))?;
    let truth = cells.saturating_mul(TRUTH_BYTES_PER_CELL as u128);
    if truth.saturating_add(held as u128) > memory_bytes as u128 {
        return Err(no_truth(format!(
            "its {cells} cells take {} MiB while written, and with the recording's {} MiB that is over the \
             memory budget of {} MiB (limits.memory_mib)",
            truth >> 20,
            held >> 20,
            memory_bytes >> 20
        )));
    }
    Ok(geometry)
}

/// The error of a truth that cannot be rastered at `resolution`, and why.
fn no_truth(out: &Path, resolution: f64, why: String) -> fusemap_io::Error {
    fusemap_io::Error::format(
        &out.join("truth.yaml"),
        fusemap_io::Location::File,
        format!("no true map at resolution {resolution} m: {why}; give a coarser --resolution"),
    )
}

/// The truth beside a written bag: the true map, the true classes and the true trajectory.
fn write_truth(rec: &SimRecording, out: &Path, geometry: GridGeometry, bag: WrittenBag) -> Result<SimulationFiles> {
    let no_truth = |why: String| no_truth(out, geometry.resolution(), why);
    let raster = truth_raster(rec, geometry).map_err(|e| no_truth(e.to_string()))?;
    let semantic = rec.truth_semantic(geometry).map_err(|e| no_truth(e.to_string()))?;
    let truth_map = fusemap_io::map_server::write_map_server(&out.join("truth.yaml"), &raster)?;
    let truth_semantic = write_truth_semantic(&out.join("truth_semantic.yaml"), &semantic)?;
    let truth_trajectory = out.join("truth.tum");
    fusemap_io::trajectory::write_tum(&truth_trajectory, &rec.truth_trajectory)?;
    Ok(SimulationFiles { bag, truth_map, truth_semantic, truth_trajectory })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn scenario_files_fill_defaults_and_name_bad_keys_and_fields() {
        let dir = fusemap_io::testdata::temp_dir("scenario");
        let s = load_scenario(&write(&dir, "short.toml", "[robot]\nduration_s = 30.0\n")).unwrap();
        assert_eq!(s.robot.duration_s, 30.0);
        assert_eq!(s.lidar, Scenario::default().lidar);
        let e = load_scenario(&write(&dir, "typo.toml", "[robot]\nduration_s = 30.0\nspeeed = 1\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("typo.toml:3") && e.contains("speeed"), "{e}");
        let e = load_scenario(&write(&dir, "bad.toml", "[gnss]\nrate_hz = 0.0\n")).unwrap_err().to_string();
        // The simulator's check names the field apart from the message: the error points
        // at its line.
        assert!(e.contains("bad.toml:2") && e.contains("gnss.rate_hz"), "{e}");
        let cam = "[camera]\ndepth_encoding = \"16UC1\"\nlabel_encoding = \"mono16\"\ntime_offset_s = 0.04\n\
                   [camera.backlight]\nfloor_share = 0.4\n[person]\nwindows = [[0.0, 30.0]]\n";
        let s = load_scenario(&write(&dir, "camera.toml", cam)).unwrap();
        assert_eq!(s.camera.depth_encoding, crate::DepthEncoding::U16Millimetres);
        assert_eq!(s.camera.label_encoding, crate::LabelEncoding::Mono16);
        assert_eq!((s.camera.time_offset_s, s.camera.backlight.floor_share), (0.04, 0.4));
        assert_eq!((s.person.windows.clone(), s.camera.width), (vec![[0.0, 30.0]], 320));
        let e =
            load_scenario(&write(&dir, "enc.toml", "[camera]\ndepth_encoding = \"rgb8\"\n")).unwrap_err().to_string();
        assert!(e.contains("enc.toml:2"), "{e}");
    }

    #[test]
    fn the_semantic_truth_is_a_palette_png_with_its_yaml() {
        let mut s = Scenario::default();
        s.robot.duration_s = 0.5;
        s.camera.enabled = false;
        let rec = crate::simulate(&s).unwrap();
        let dir = fusemap_io::testdata::temp_dir("sim-semantic");
        let files = write_simulation(&rec, &dir, 0.1, false, u64::MAX).unwrap();
        let yaml = std::fs::read_to_string(files.truth_semantic).unwrap();
        assert!(yaml.contains("image: truth_semantic.png\nresolution: 0.1\n"), "{yaml}");
        assert!(yaml.contains("{id: 3, name: glass, color: [80, 200, 230]}"), "{yaml}");
        let t = rec.truth_semantic(GridGeometry::centered(0.1).unwrap()).unwrap();
        let mut reader =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.join("truth_semantic.png")).unwrap()))
                .read_info()
                .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width as usize, info.height as usize), (t.width, t.height));
        assert_eq!(info.color_type, png::ColorType::Indexed);
        // The top row is the highest y: the last raster row.
        let top = &buf[..t.width];
        assert_eq!(top, &t.class_ids[(t.height - 1) * t.width..]);
        assert!(buf.contains(&3) && buf.contains(&4) && buf.contains(&5) && buf.contains(&2));
    }

    /// The streamed simulation writes the same files, byte for byte, as the recording held
    /// whole and written after: over several chunks of camera frames, with a camera clock
    /// that runs early (its first frames come before the `/tf_static` stamp).
    #[test]
    fn a_streamed_simulation_writes_the_same_files() {
        let mut s = Scenario::default();
        s.robot.duration_s = 20.0;
        (s.camera.width, s.camera.height, s.camera.time_offset_s) = (64, 48, -0.04);
        let dir = fusemap_io::testdata::temp_dir("sim-streamed");
        let held = crate::simulate(&s).unwrap();
        let frames = held.messages.iter().filter(|m| matches!(m, SimMessage::CameraInfo(_))).count() as u64;
        assert!(frames > 2 * 4 * crate::camera::FRAMES_PER_THREAD_AND_CHUNK, "{frames} frames: several chunks");
        let statics = held.messages.iter().find(|m| matches!(m, SimMessage::StaticTransform(_))).unwrap();
        assert!(held.messages[0].stamp() < statics.stamp(), "a camera frame comes first");
        write_simulation(&held, &dir.join("held"), 0.1, false, u64::MAX).unwrap();
        let (rec, files) = simulate_to(&s, &dir.join("streamed"), 0.1, false, u64::MAX).unwrap();
        assert!(rec.messages.is_empty());
        assert_eq!(rec.truth_trajectory, held.truth_trajectory);
        assert_eq!(rec.camera_truth.stamps, held.camera_truth.stamps);
        assert_eq!(rec.camera_truth.backlit_floor_points, held.camera_truth.backlit_floor_points);
        assert_eq!(files.bag.message_count, held.messages.len() as u64 - 3);
        for f in ["bag/bag_0.mcap", "bag/metadata.yaml", "truth.pgm", "truth.yaml", "truth_semantic.png", "truth.tum"] {
            let (a, b) = (
                std::fs::read(dir.join("held").join(f)).unwrap(),
                std::fs::read(dir.join("streamed").join(f)).unwrap(),
            );
            assert!(a == b, "{f} differs");
        }
        // A scenario the simulator refuses is refused before anything is written.
        s.gnss.rate_hz = 0.0;
        let e = simulate_to(&s, &dir.join("refused"), 0.1, false, u64::MAX).err().expect("refused");
        assert!(matches!(e, SimulationError::Scenario(_)) && e.to_string().contains("gnss.rate_hz"), "{e}");
        assert!(!dir.join("refused").exists());
    }

    /// A resolution the world cannot be rastered at is an error before anything is
    /// written (it was a run without its truth map, exit 0).
    #[test]
    fn a_truth_too_fine_to_raster_is_an_error_before_anything_is_written() {
        let mut s = Scenario::default();
        s.robot.duration_s = 0.5;
        s.camera.enabled = false;
        let rec = crate::simulate(&s).unwrap();
        let dir = fusemap_io::testdata::temp_dir("sim-too-fine");
        for resolution in [1e-9, 0.0, f64::NAN] {
            let e = write_simulation(&rec, &dir.join("out"), resolution, false, u64::MAX)
                .err()
                .expect("refused")
                .to_string();
            assert!(e.contains("truth.yaml") && e.contains("no true map at resolution"), "{e}");
            assert!(!dir.join("out").exists(), "nothing written for {resolution}");
        }
    }

    /// The camera's topics read back by a reader that is not ours: the python `rosbags`
    /// library decodes a label image, a depth image and a CameraInfo of a simulated bag.
    #[test]
    fn rosbags_decodes_the_simulated_camera() {
        use crate::{simulate, SimImage};
        let Some(python) = fusemap_io::testdata::python_with(&["rosbags.rosbag2", "rosbags.typesys", "numpy"]) else {
            return;
        };
        let mut s = Scenario::default();
        s.robot.duration_s = 1.0;
        (s.camera.width, s.camera.height) = (64, 48);
        let rec = simulate(&s).unwrap();
        let tmp = fusemap_io::testdata::temp_dir("sim-camera");
        let dir = tmp.join("bag");
        write_bag(&rec, &dir, false).unwrap();
        let first = |topic: &str| {
            rec.messages
                .iter()
                .find_map(|m| match m {
                    SimMessage::Image(i) if i.topic == topic => Some(i.clone()),
                    _ => None,
                })
                .unwrap()
        };
        let (labels, depth): (SimImage, SimImage) = (first("/camera/labels"), first("/camera/depth"));
        let script = r#"
import json, sys
import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
store = get_typestore(Stores.ROS2_HUMBLE)
out = {}
with Reader(sys.argv[1]) as reader:
    for conn, t, raw in reader.messages():
        if conn.topic in out:
            continue
        msg = store.deserialize_cdr(raw, conn.msgtype)
        if conn.topic in ("/camera/labels", "/camera/depth"):
            dtype = np.uint8 if msg.encoding == "mono8" else np.float32
            px = np.frombuffer(msg.data.tobytes(), dtype=dtype).reshape(msg.height, msg.width)
            out[conn.topic] = {"type": conn.msgtype, "frame": msg.header.frame_id, "stamp": [msg.header.stamp.sec, msg.header.stamp.nanosec],
                "width": int(msg.width), "height": int(msg.height), "encoding": msg.encoding, "step": int(msg.step),
                "bytes": len(msg.data), "pixels": [None if np.isnan(v) else float(v) for v in (px[0, 0], px[24, 32], px[47, 63], px[40, 10])]}
        elif conn.topic == "/camera/camera_info":
            out[conn.topic] = {"type": conn.msgtype, "model": msg.distortion_model, "d": [float(v) for v in msg.d],
                "k": [float(v) for v in msg.k], "width": int(msg.width), "height": int(msg.height)}
print(json.dumps(out))
"#;
        let run = std::process::Command::new(&python).args(["-c", script]).arg(&dir).output().unwrap();
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let got: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        let px = |img: &SimImage, bytes: usize, (v, u): (usize, usize)| {
            let i = (v * img.width as usize + u) * bytes;
            let b = &img.data[i..i + bytes];
            let x = if bytes == 1 { f64::from(b[0]) } else { f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])) };
            if x.is_nan() {
                serde_json::Value::Null
            } else {
                serde_json::json!(x)
            }
        };
        for (topic, img, bytes, enc, ty) in [
            ("/camera/labels", &labels, 1, "mono8", "sensor_msgs/msg/Image"),
            ("/camera/depth", &depth, 4, "32FC1", "sensor_msgs/msg/Image"),
        ] {
            let g = &got[topic];
            assert_eq!(g["type"], ty, "{topic}");
            assert_eq!((g["width"].as_u64(), g["height"].as_u64()), (Some(64), Some(48)), "{topic}");
            assert_eq!((g["encoding"].as_str(), g["step"].as_u64()), (Some(enc), Some(64 * bytes as u64)), "{topic}");
            assert_eq!(g["bytes"].as_u64(), Some(64 * 48 * bytes as u64), "{topic}");
            assert_eq!(g["frame"], "camera_optical");
            assert_eq!(g["stamp"][0].as_i64(), Some(img.header.stamp.0.div_euclid(1_000_000_000)));
            for (k, p) in [(0, 0), (24, 32), (47, 63), (40, 10)].into_iter().enumerate() {
                let (want, read) = (px(img, bytes, p), &g["pixels"][k]);
                // JSON floats need not round-trip to the last bit: compare f32 values.
                let same = match (want.as_f64(), read.as_f64()) {
                    (Some(a), Some(b)) => (a as f32) == (b as f32),
                    (None, None) => read.is_null(),
                    _ => false,
                };
                assert!(same, "{topic} pixel {p:?}: wrote {want}, rosbags read {read}");
            }
        }
        // The floor fills the lower image at a depth of a few metres.
        assert!(got["/camera/depth"]["pixels"][2].as_f64().is_some_and(|d| d > 0.5 && d < 8.5));
        let info = &got["/camera/camera_info"];
        assert_eq!(info["type"], "sensor_msgs/msg/CameraInfo");
        assert_eq!((info["model"].as_str(), info["d"].as_array().map(Vec::len)), (Some("plumb_bob"), Some(5)));
        let k = s.camera.k_matrix();
        assert_eq!(info["k"], serde_json::json!(k));
        assert_eq!((info["width"].as_u64(), info["height"].as_u64()), (Some(64), Some(48)));
    }
}
