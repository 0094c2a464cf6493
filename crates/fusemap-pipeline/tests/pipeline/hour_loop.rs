//! The simulator's hour-long loop (issue 22): the production line driven lap after lap for
//! an hour (about 60 laps, 2.9 km), mapped with wheel odometry and the lidar only (no
//! RTK, no IMU), SLAM on. The odometry has the simulator's 3 % scale error and slips in the
//! floor grooves; the truth is known, so the revisit relations (scans within 5 m of each
//! other at least 60 s apart) and the ATE are measured against it rather than against
//! another SLAM's output.
//!
//! Five minutes on two cores, so it is not part of the suite; run it by hand:
//! `cargo test --release -p fusemap-pipeline --test pipeline hour_loop -- --ignored --nocapture`.

use fusemap_core::geometry::Pose2;
use fusemap_core::metrics::{absolute_trajectory_error, revisit_relations, score_index_relations, RevisitRule};
use fusemap_pipeline::recording::Inventory;
use fusemap_sim::{simulate, Scenario};
use std::path::Path;
use std::time::Instant;

/// Lidar and odometry: the lidar table of `configs/production_line.toml`, poses from the
/// odometry topic alone.
const CONFIG: &str = r#"
[[sensor]]
kind = "lidar"
name = "laser"
topic = "/scan"
max_range = 20.0
[sensor.filters.shadow]
enabled = true

[log]
pose_source = "odometry"
"#;

#[test]
#[ignore = "an hour of simulated laps: about five minutes on two cores; run by hand with --release -- --ignored"]
fn an_hour_of_laps_with_odometry_and_lidar_only_keeps_revisits_within_10_cm() {
    let mut scenario = Scenario::default();
    scenario.robot.duration_s = 3600.0;
    scenario.camera.enabled = false;
    let rec = simulate(&scenario).expect("the scenario simulates");
    let dir = fusemap_io::testdata::temp_dir("hour-loop");
    let bag = dir.join("bag");
    fusemap_sim::bag::write_bag(&rec, &bag, true).expect("the bag is written");
    let inv = Inventory::read(&bag).expect("the bag reads back");
    let cfg = fusemap_io::config_file::parse_config_str(CONFIG, Path::new("hour_loop.toml")).expect("config");
    let plan = cfg.validate().expect("valid config");

    let t0 = Instant::now();
    let run = fusemap_pipeline::map_inventory(&plan, &inv, &mut |_| {}).expect("the run maps");
    let seconds = t0.elapsed().as_secs_f64();
    assert!(run.notes.iter().any(|n| n.starts_with("SLAM corrected")), "SLAM ran: {:?}", run.notes);

    // One pose a second, each with the truth at its stamp.
    let (mut est, mut truth, mut secs) = (Vec::<Pose2>::new(), Vec::<Pose2>::new(), Vec::<f64>::new());
    let mut next = f64::NEG_INFINITY;
    for &(stamp, pose) in &run.trajectory {
        let s = stamp.as_secs_f64();
        if s < next {
            continue;
        }
        let Some(t) = rec.truth_at(stamp) else { continue };
        next = s + 1.0;
        est.push(pose);
        truth.push(t);
        secs.push(s);
    }
    assert!(est.len() > 3000, "one pose a second over the hour: {}", est.len());
    let revisits = revisit_relations(&truth, Some(&secs), &RevisitRule::default());
    let score = score_index_relations(&revisits, &est);
    let ate = absolute_trajectory_error(&est, &truth);
    println!(
        "hour loop: {} poses, {} revisit relations: mean {:.4} ± {:.4} m (max {:.3} m); ATE {:.4} m; mapped in {seconds:.1} s",
        est.len(),
        score.scored,
        score.translation_mean_m,
        score.translation_std_m,
        score.translation_max_m,
        ate
    );
    for n in &run.notes {
        println!("note: {n}");
    }
    assert!(score.scored > 1000 && score.unmatched == 0, "{score:?}");
    assert!(score.translation_mean_m <= 0.10, "revisit mean {} m", score.translation_mean_m);
}
