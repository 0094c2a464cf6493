//! One scan topic, two frame ids: each scan is placed from the mount of its own frame.
//! Every other scan of a simulated run is relabelled to a frame `laser_flipped` mounted
//! like the lidar but turned by 180° (a static transform says so), its beam angles turned
//! back by π: the same rays, described from another frame. Mapped with each frame's own
//! mount, the map is the original's; mapped with the lidar's mount for every scan (what a
//! reader that trusts the first frame id does), half the scans would be drawn backwards.

use fusemap_core::config::{Config, SlamMode};
use fusemap_core::grid::{CellIndex, Ternary};
use fusemap_io::log::ros2::writer::{OutMessage, Rosbag2Writer, Rosbag2WriterOptions};
use fusemap_pipeline::map_log;
use fusemap_sim::bag::to_out_message;
use fusemap_sim::{simulate, Scenario, SimMessage};
use std::collections::HashSet;
use std::f64::consts::PI;
use std::path::Path;

/// `q ⊗ (0, 0, 1, 0)`: the rotation `q` (x, y, z, w) turned by π about its z axis.
fn turned(q: [f64; 4]) -> [f64; 4] {
    let [x, y, z, w] = q;
    [y, -x, w, -z]
}

/// The occupied cells of the map of the bag at `path`, with SLAM in `slam` mode.
fn occupied(path: &Path, slam: SlamMode) -> (HashSet<CellIndex>, Vec<String>) {
    let mut cfg = Config::default();
    cfg.slam.mode = slam;
    let plan = cfg.validate().unwrap();
    let run = map_log(&plan, path, &mut |_| {}).unwrap();
    let raster = run.engine.grid().known_raster().expect("a map");
    let ternary = raster.ternary();
    let mut cells = HashSet::new();
    for row in 0..raster.height {
        for column in 0..raster.width {
            if ternary[raster.index(column, row)] == Ternary::Occupied {
                cells.insert(CellIndex::new(raster.first_cell.x + column as i64, raster.first_cell.y + row as i64));
            }
        }
    }
    (cells, run.notes)
}

#[test]
fn scans_of_two_frames_on_one_topic_are_each_placed_from_their_own_mount() {
    let mut s = Scenario::default();
    s.robot.duration_s = 20.0;
    let rec = simulate(&s).unwrap();
    let dir = fusemap_io::testdata::temp_dir("scan-frames");
    let write = |bag: &Path, relabel: bool| {
        let mut w =
            Rosbag2Writer::create_with(bag, Rosbag2WriterOptions { overwrite: true, ..Default::default() }).unwrap();
        let mut k = 0;
        for m in &rec.messages {
            let mut out = to_out_message(m);
            match (m, &mut out) {
                (SimMessage::Scan(_), OutMessage::LaserScan(scan)) => {
                    if relabel && k % 2 == 1 {
                        scan.header.frame_id = "laser_flipped".into();
                        scan.angle_min = (scan.angle_min as f64 - PI) as f32;
                        scan.angle_max = (scan.angle_max as f64 - PI) as f32;
                    }
                    k += 1;
                }
                (SimMessage::StaticTransform(t), OutMessage::Tf { transforms, .. }) => {
                    if relabel && t.child_frame_id == s.frames.laser {
                        let mut flipped = transforms[0].clone();
                        flipped.child_frame_id = "laser_flipped".into();
                        flipped.transform.rotation = turned(flipped.transform.rotation.to_array()).into();
                        transforms.push(flipped);
                    }
                }
                (SimMessage::Odometry(_), _) => {}
                _ => continue,
            }
            w.write(m.stamp(), m.topic(), &out).unwrap();
        }
        w.finish().unwrap();
        assert!(k > 100, "{k} scans");
    };
    let (one, two) = (dir.join("one"), dir.join("two"));
    write(&one, false);
    write(&two, true);
    // With SLAM off, the mapping pass alone; with it on, SLAM's matcher too places each
    // scan from its own frame's mount.
    for slam in [SlamMode::Off, SlamMode::On] {
        let (a, _) = occupied(&one, slam);
        let (b, notes) = occupied(&two, slam);
        let note = notes.iter().find(|n| n.contains("several frame ids")).expect("a note on the frames");
        assert!(note.contains("each scan is mapped with the mount of its own frame") && note.contains("laser_flipped"));
        // The same rays: the same walls, up to cells on the edge of a threshold (the turned
        // angles differ from the originals in their last float32 bits).
        let common = a.intersection(&b).count() as f64;
        let f1 = 2.0 * common / (a.len() + b.len()) as f64;
        assert!(a.len() > 500, "{slam:?}: {} occupied cells", a.len());
        assert!(f1 > 0.98, "{slam:?}: F1 {f1:.4} between the maps ({} and {} occupied cells)", a.len(), b.len());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A lidar frame the log has no transform for, and the config no mount: it is mapped at
/// the base's origin (identity), and a note says so, as it does for a camera.
#[test]
fn a_lidar_frame_without_a_mount_is_noted() {
    let mut s = Scenario::default();
    s.robot.duration_s = 10.0;
    s.camera.enabled = false;
    let mut rec = simulate(&s).unwrap();
    let laser = s.frames.laser.clone();
    rec.messages.retain(|m| !matches!(m, SimMessage::StaticTransform(t) if t.child_frame_id == laser));
    let dir = fusemap_io::testdata::temp_dir("lidar-without-mount");
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(&rec, &bag, true).unwrap();
    let (_, notes) = occupied(&bag, SlamMode::Off);
    let note = notes.iter().find(|n| n.contains("no mount in the config or the log")).expect("a note on the mount");
    assert!(note.contains(&format!("`{laser}`")) && note.contains("lidar `laser`"), "{note}");
    // With its mount in the log, no such note.
    let whole = simulate(&s).unwrap();
    let bag = dir.join("whole");
    fusemap_sim::bag::write_bag(&whole, &bag, true).unwrap();
    let (_, notes) = occupied(&bag, SlamMode::Off);
    assert!(!notes.iter().any(|n| n.contains("no mount in the config or the log")), "{notes:?}");
}

/// Contradictory scan stamps are noted: every scan at one instant, or scans at the
/// instant of the scan before them with other ranges.
#[test]
fn scans_sharing_a_stamp_are_noted() {
    let mut s = Scenario::default();
    s.robot.duration_s = 10.0;
    s.camera.enabled = false;
    let rec = simulate(&s).unwrap();
    let dir = fusemap_io::testdata::temp_dir("shared-stamps");
    let restamped = |name: &str, every: usize| {
        let mut r = rec.clone();
        let (mut k, mut previous) = (0, None);
        for m in &mut r.messages {
            if let SimMessage::Scan(scan) = m {
                if k % every == 0 {
                    if let Some(p) = previous {
                        scan.header.stamp = p;
                    }
                }
                previous = Some(scan.header.stamp);
                k += 1;
            }
        }
        let bag = dir.join(name);
        fusemap_sim::bag::write_bag(&r, &bag, true).unwrap();
        occupied(&bag, SlamMode::Off).1
    };
    let notes = restamped("pairs", 10);
    assert!(notes.iter().any(|n| n.contains("carry the stamp of the scan before them")), "{notes:?}");
    let notes = restamped("all", 1);
    assert!(notes.iter().any(|n| n.contains("carries the same header stamp")), "{notes:?}");
    let whole = dir.join("whole");
    fusemap_sim::bag::write_bag(&rec, &whole, true).unwrap();
    let notes = occupied(&whole, SlamMode::Off).1;
    assert!(!notes.iter().any(|n| n.contains("header stamp") || n.contains("stamp of the scan before")), "{notes:?}");
}
