//! A camera's bad input in a real bag: images of the wrong size, unknown class ids, depth
//! holes, an unsupported encoding, frames without a pose, a missing or late CameraInfo,
//! a distorted one. Each is a counted skip or one clear error, never a panic.

use fusemap_core::time::Stamp;
use fusemap_pipeline::camera::CameraReport;
use fusemap_pipeline::recording::Inventory;
use fusemap_pipeline::run::map_inventory;
use fusemap_pipeline::scenario::production_line_plan;
use fusemap_pipeline::PipelineError;
use fusemap_sim::{simulate, Scenario, SimMessage, SimRecording};

fn short() -> SimRecording {
    let mut s = Scenario::default();
    s.robot.duration_s = 12.0;
    s.person.enabled = false;
    simulate(&s).unwrap()
}

fn run(name: &str, rec: &SimRecording) -> Result<fusemap_pipeline::MapRun, PipelineError> {
    let dir = fusemap_io::testdata::temp_dir(name);
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(rec, &bag, true).unwrap();
    let inv = Inventory::read(&bag).unwrap();
    map_inventory(&production_line_plan().unwrap(), &inv, &mut |_| {})
}

fn camera(run: &fusemap_pipeline::MapRun) -> &CameraReport {
    &run.report.cameras[0]
}

/// Applies `f` to every `k`-th image of `topic`.
fn every(rec: &mut SimRecording, topic: &str, k: usize, mut f: impl FnMut(&mut fusemap_sim::SimImage)) -> usize {
    let mut n = 0;
    for m in rec.messages.iter_mut() {
        if let SimMessage::Image(i) = m {
            if i.topic == topic {
                if n % k == 0 {
                    f(i);
                }
                n += 1;
            }
        }
    }
    n.div_ceil(k)
}

#[test]
fn a_clean_short_run_uses_every_frame() {
    let rec = short();
    let r = run("camera-clean", &rec).unwrap();
    let c = camera(&r);
    assert_eq!(c.frames_used, c.labels_read);
    assert_eq!((c.undecodable, c.frames_refused, c.labels_unpaired, c.depths_unpaired), (0, 0, 0, 0));
    assert_eq!(c.pixels.unknown_class, 0);
}

#[test]
fn bad_images_are_counted_and_skipped() {
    let mut rec = short();
    // Every 10th label image is half the size of its depth image.
    let resized = every(&mut rec, "/camera/labels", 10, |i| {
        i.width /= 2;
        i.height /= 2;
        i.step = i.width;
        let n = (i.width * i.height) as usize;
        i.data.to_mut().truncate(n);
    });
    // Every 7th label image carries an unknown class id (200) in its first row.
    every(&mut rec, "/camera/labels", 7, |i| {
        let w = i.width as usize;
        i.data.to_mut()[..w].fill(200)
    });
    // Every 5th depth image has NaN, 0 and negative depths in its last rows.
    every(&mut rec, "/camera/depth", 5, |i| {
        let (n, step) = (i.data.len(), i.step as usize);
        for (k, px) in i.data.to_mut()[n - 3 * step..].chunks_exact_mut(4).enumerate() {
            px.copy_from_slice(&[f32::NAN, 0.0, -1.0][k % 3].to_le_bytes());
        }
    });
    // Every 13th depth image claims an encoding we do not read.
    let rgb = every(&mut rec, "/camera/depth", 13, |i| i.encoding = "rgb8".into());
    let r = run("camera-bad-images", &rec).unwrap();
    let c = camera(&r);
    assert!(c.frames_refused >= resized as u64 - 1, "{c:?}");
    assert!(c.refused_example.as_deref().unwrap_or("").contains("size"), "{c:?}");
    assert_eq!(c.undecodable, rgb as u64, "{c:?}");
    assert!(c.undecodable_example.as_deref().unwrap().contains("rgb8"), "{c:?}");
    assert!(c.pixels.unknown_class > 0 && c.pixels.no_depth > 0, "{:?}", c.pixels);
    assert!(c.frames_used > 0 && c.frames_used < c.labels_read);
}

/// When every label image is malformed, the camera is left out with a note that says so
/// and why (not that the log has none), and the lidar's map is made.
#[test]
fn a_topic_of_only_malformed_images_drops_the_camera_for_that_reason() {
    let mut rec = short();
    let n = every(&mut rec, "/camera/labels", 1, |i| {
        i.data.to_mut().pop();
    });
    let r = run("camera-all-labels-malformed", &rec).unwrap();
    assert!(r.report.cameras.is_empty());
    assert!(r.report.lidars[0].scans_used > 100, "{:?}", r.report.lidars[0]);
    let note = r.notes.iter().find(|n| n.contains("camera `camera` is not mapped")).expect("a note on the camera");
    assert!(note.contains(&format!("{n} messages on `/camera/labels` are all malformed")), "{note}");
    assert!(note.contains("data"), "the first message's fault is given: {note}");
}

#[test]
fn frames_without_a_pose_are_counted() {
    let mut rec = short();
    let last = rec.messages.iter().map(|m| m.stamp()).max().unwrap();
    // The last three label and depth images are stamped a minute after the log ends.
    for topic in ["/camera/labels", "/camera/depth"] {
        let mut imgs: Vec<&mut fusemap_sim::SimImage> = rec
            .messages
            .iter_mut()
            .filter_map(|m| match m {
                SimMessage::Image(i) if i.topic == topic => Some(i),
                _ => None,
            })
            .collect();
        let n = imgs.len();
        for (k, i) in imgs[n - 3..].iter_mut().enumerate() {
            i.header.stamp = Stamp(last.0 + 60_000_000_000 + k as i64 * 100_000_000);
        }
    }
    rec.messages.sort_by_key(|m| m.stamp());
    let r = run("camera-no-pose", &rec).unwrap();
    assert_eq!(camera(&r).frames_skipped.after_last_pose, 3, "{:?}", camera(&r));
}

#[test]
fn a_missing_camera_info_is_one_clear_error_and_a_distorted_one_drops_the_camera() {
    let mut rec = short();
    rec.messages.retain(|m| !matches!(m, SimMessage::CameraInfo(_)));
    let e = run("camera-no-info", &rec).err().expect("refused").to_string();
    assert!(e.contains("/camera/camera_info") && e.contains("camera info"), "{e}");

    let mut rec = short();
    for m in rec.messages.iter_mut() {
        if let SimMessage::CameraInfo(i) = m {
            i.d = vec![0.1, 0.0, 0.0, 0.0, 0.0];
        }
    }
    let r = run("camera-distorted", &rec).unwrap();
    assert!(r.report.cameras.is_empty());
    let note = r.notes.iter().find(|n| n.contains("camera `camera` is not mapped")).expect("a note on the camera");
    assert!(note.contains("rectified") && note.contains("plumb_bob"), "{note}");
}

#[test]
fn a_late_camera_info_is_noted_and_used() {
    let mut rec = short();
    // Only camera-info messages after the first five seconds survive.
    let start = rec.messages.iter().map(|m| m.stamp()).min().unwrap();
    rec.messages.retain(|m| !matches!(m, SimMessage::CameraInfo(i) if i.header.stamp.0 < start.0 + 5_000_000_000));
    let r = run("camera-late-info", &rec).unwrap();
    assert!(r.notes.iter().any(|n| n.contains("after the first image")), "{:?}", r.notes);
    assert_eq!(camera(&r).frames_used, camera(&r).labels_read);
}

#[test]
fn a_camera_on_the_usual_topics_is_found_and_can_be_switched_off() {
    use fusemap_core::config::{Config, SensorConfig, SensorKind};
    let rec = short();
    let dir = fusemap_io::testdata::temp_dir("camera-auto");
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(&rec, &bag, true).unwrap();
    let inv = Inventory::read(&bag).unwrap();
    let plan = Config::default().validate().unwrap();
    let r = map_inventory(&plan, &inv, &mut |_| {}).unwrap();
    assert_eq!(r.report.cameras.len(), 1);
    assert!(r.report.cameras[0].frames_used > 0);
    assert!(r.notes.iter().any(|n| n.contains("camera found on `/camera/labels`")), "{:?}", r.notes);
    let off = Config {
        sensor: vec![SensorConfig { enabled: false, ..SensorConfig::new(SensorKind::Camera) }],
        ..Default::default()
    };
    let r = map_inventory(&off.validate().unwrap(), &inv, &mut |_| {}).unwrap();
    assert!(r.report.cameras.is_empty());
}

/// Label and depth images a few milliseconds apart with a scan stamped between them: the
/// frame enters the engine at the later stamp (its pose is the label's), never out of order.
#[test]
fn a_scan_between_a_label_and_its_depth_image_is_fine() {
    let mut rec = short();
    for m in rec.messages.iter_mut() {
        match m {
            SimMessage::Scan(s) => s.header.stamp = Stamp(s.header.stamp.0 + 1_000_000),
            SimMessage::Image(i) if i.topic == "/camera/depth" => i.header.stamp = Stamp(i.header.stamp.0 + 3_000_000),
            _ => {}
        }
    }
    rec.messages.sort_by_key(|m| m.stamp());
    let r = run("camera-between", &rec).unwrap();
    let c = camera(&r);
    assert_eq!(c.frames_used, c.frames_paired, "{c:?}");
    assert!(c.frames_used > 50);
}
