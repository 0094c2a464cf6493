//! Scans whose beam angles cannot be placed are refused and counted, never drawn: an
//! `angle_increment` of 0 or NaN (every beam on one bearing) and a `ranges` count that
//! disagrees with `angle_min … angle_max` (drawn over another field of view).

use fusemap_core::config::{Config, SlamMode};
use fusemap_io::log::ros2::writer::{OutMessage, Rosbag2Writer, Rosbag2WriterOptions};
use fusemap_pipeline::map_log;
use fusemap_sim::bag::to_out_message;
use fusemap_sim::{simulate, Scenario, SimMessage};

#[test]
fn scans_with_inconsistent_angles_are_refused_and_counted() {
    let mut s = Scenario::default();
    s.robot.duration_s = 10.0;
    let rec = simulate(&s).unwrap();
    let dir = fusemap_io::testdata::temp_dir("scan-angles");
    let mut scans = 0;
    let mut broken = [0u64; 3];
    let mut write = |bag: &std::path::Path, corrupt: bool| {
        let mut w =
            Rosbag2Writer::create_with(bag, Rosbag2WriterOptions { overwrite: true, ..Default::default() }).unwrap();
        let mut k = 0;
        for m in &rec.messages {
            let mut out = to_out_message(m);
            match (m, &mut out) {
                (SimMessage::Scan(_), OutMessage::LaserScan(scan)) => {
                    if corrupt {
                        match k % 10 {
                            3 => scan.angle_increment = 0.0,
                            5 => scan.angle_increment = f32::NAN,
                            7 => scan.ranges = scan.ranges.iter().chain(&scan.ranges).copied().collect(),
                            _ => {}
                        }
                        if matches!(k % 10, 3 | 5 | 7) {
                            broken[(k % 10 / 2 - 1) as usize] += 1;
                        }
                    }
                    scans += u64::from(corrupt);
                    k += 1;
                }
                (SimMessage::Scan(_) | SimMessage::Odometry(_) | SimMessage::StaticTransform(_), _) => {}
                _ => continue,
            }
            w.write(m.stamp(), m.topic(), &out).unwrap();
        }
        w.finish().unwrap();
    };
    let (clean, bad) = (dir.join("clean"), dir.join("bad"));
    write(&clean, false);
    write(&bad, true);
    let mut cfg = Config::default();
    cfg.slam.mode = SlamMode::Off;
    let plan = cfg.validate().unwrap();
    let a = map_log(&plan, &clean, &mut |_| {}).unwrap();
    let b = map_log(&plan, &bad, &mut |_| {}).unwrap();
    let refused: u64 = broken.iter().sum();
    assert!(broken.iter().all(|&n| n > 5), "{broken:?} of {scans}");
    assert_eq!(a.report.scans_skipped.bad_angles, 0);
    assert_eq!(b.report.scans_skipped.bad_angles, refused);
    assert_eq!(b.report.scans_used, a.report.scans_used - refused);
    let note = b.notes.iter().find(|n| n.contains("beam angles cannot be placed")).expect("a note");
    assert!(note.starts_with(&format!("{refused} scans of `/scan` refused")), "{note}");
    assert!(note.contains("angle_increment is 0"), "{note}");
    std::fs::remove_dir_all(&dir).unwrap();
}
