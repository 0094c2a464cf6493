//! The SLAM benchmark (Kümmerle et al. 2009) on the raw logs whose scan stamps match their
//! relations files, and on MIT Killian, whose relations are matched to its scans by order:
//! fusemap's mean translational error must be at most 1.5× Cartographer's (Hess et al.
//! 2016, Table II). Reads `../shared`; skips with a notice without it.
//!
//! Each log is its own test; `-- --nocapture` prints the table row. The figure asserted is
//! the one `fusemap map` then `fusemap relations` print: `trajectory.tum` as the map run
//! writes it, scored by [`score_trajectory`] with the CLI's defaults.

use fusemap_core::config::Config;
use fusemap_core::geometry::{normalize_angle, Pose2};
use fusemap_core::metrics::{score_trajectory, Relation, RelationMatching, RelationScore};
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::relations::read_relations;
use fusemap_io::testdata::{dataset, temp_dir};
use fusemap_io::trajectory::{read_tum, write_tum};
use fusemap_pipeline::recording::Inventory;
use fusemap_pipeline::run::{map_inventory, prepare};
use fusemap_pipeline::track::Track;

struct Scored {
    slam: RelationScore,
    track: RelationScore,
    odometry: RelationScore,
}

/// A log mapped with SLAM, and its poses (`map_from_base`, by stamp).
struct Run {
    relations: Vec<Relation>,
    /// How poses are found at the relation stamps: `fusemap relations`' defaults, at the
    /// laser.
    matching: RelationMatching,
    /// The scans' stamps, in order.
    stamps: Vec<Stamp>,
    /// The optimised scan poses.
    slam: Vec<(Stamp, Pose2)>,
    /// `trajectory.tum` as `fusemap map` writes it and `fusemap relations` reads it: the
    /// track SLAM corrected, with the pose each scan was mapped with.
    track: Vec<(Stamp, Pose2)>,
    /// The raw odometry (`[slam] mode = "off"`) at the scan stamps.
    odometry: Vec<(Stamp, Pose2)>,
}

impl Run {
    fn scored(&self, relations: &[Relation]) -> Scored {
        Scored {
            slam: score_trajectory(relations, &self.slam, &self.matching),
            track: score_trajectory(relations, &self.track, &self.matching),
            odometry: score_trajectory(relations, &self.odometry, &self.matching),
        }
    }
}

fn run(log: &str, relations: &str) -> Option<Run> {
    let log = dataset(log)?;
    let rel = dataset(relations)?;
    let relations = read_relations(&rel).unwrap();
    // FUSEMAP_SLAM_TOML: a `[slam]` table to try other settings without rebuilding.
    let mut config = Config::default();
    if let Ok(t) = std::env::var("FUSEMAP_SLAM_TOML") {
        config.slam = toml::from_str(&t).expect("FUSEMAP_SLAM_TOML is a [slam] table");
    }
    let plan = config.validate().unwrap();
    let inv = Inventory::read(&log).unwrap();
    let mapped = map_inventory(&plan, &inv, &mut |_| {}).unwrap();
    let slam = mapped.report.slam.as_ref().expect("SLAM runs on a raw log");
    eprintln!(
        "{}: {} scans ({} without a track pose, {} late), {} matched, {} degenerate, {} nodes, {} submaps, loop closures {}/{} accepted, {} optimisations, {} held readings, {} of {} rescue searches taken; matching {:.2} s, loop search {:.2} s, optimisation {:.2} s, total {:.2} s",
        log.display(),
        slam.counts.scans,
        slam.scans_without_pose,
        slam.scans_late,
        slam.counts.matched,
        slam.counts.degenerate,
        slam.counts.nodes,
        slam.counts.submaps,
        slam.counts.loop_accepted,
        slam.counts.loop_searches,
        slam.counts.optimisations,
        slam.counts.held_readings,
        slam.counts.rescued,
        slam.counts.rescue_searched,
        slam.counts.matching_s,
        slam.counts.loop_search_s,
        slam.counts.optimisation_s,
        slam.seconds
    );
    // The relations are between laser poses (the scans' origins); fusemap's trajectory is
    // the base frame's. Freiburg 079's laser sits 4 cm ahead of its base, the others' at
    // it: what a user gives `fusemap relations --sensor-in-base` from summary.json.
    let [x, y, yaw] = slam.sensor_in_base;
    let matching = RelationMatching { sensor_in_base: Pose2::new(x, y, yaw), ..RelationMatching::default() };
    // trajectory.tum written and read back by the functions `map` and `relations` use.
    let dir = temp_dir("slam-benchmark");
    let tum = dir.join("trajectory.tum");
    write_tum(&tum, &mapped.trajectory).unwrap();
    let track = read_tum(&tum).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let odo_plan = {
        let mut c = Config::default();
        c.slam.mode = fusemap_core::config::SlamMode::Off;
        c.validate().unwrap()
    };
    let (bound, raw, _) = prepare(&odo_plan, &inv).unwrap();
    let mut stamps = inv.scans[&bound.lidars[0].topic].stamps.clone();
    stamps.sort_unstable();
    let odometry: Vec<_> = match &raw.track {
        Track::Timed(t) => {
            stamps.iter().filter_map(|s| t.pose_at(*s, SyncMode::Interpolate).ok().map(|p| (*s, p))).collect()
        }
        Track::ScanLine(_) => Vec::new(),
    };
    if let Ok(dir) = std::env::var("FUSEMAP_SLAM_DUMP") {
        let name = log.file_name().unwrap().to_string_lossy().to_string();
        let lines: String =
            slam.scan_poses.iter().map(|(t, p)| format!("{} {} {} {}\n", t.0, p.x, p.y, p.theta)).collect();
        std::fs::write(format!("{dir}/{name}.slam.txt"), lines).unwrap();
        let at_laser: Vec<_> = track.iter().map(|&(t, p)| (t, p.compose(matching.sensor_in_base))).collect();
        let errs = fusemap_core::metrics::relation_errors(&relations, &at_laser, matching.tolerance_ns);
        let lines: String = relations
            .iter()
            .zip(errs)
            .filter_map(|(r, e)| e.map(|e| format!("{} {} {} {}\n", r.t1.0, r.t2.0, e.x.hypot(e.y), e.theta)))
            .collect();
        std::fs::write(format!("{dir}/{name}.errors.txt"), lines).unwrap();
    }
    Some(Run { relations, matching, stamps, slam: slam.scan_poses.clone(), track, odometry })
}

fn check(name: &str, log: &str, relations: &str, cartographer: f64, graph_mapping: f64) {
    let Some(run) = run(log, relations) else { return };
    report(name, &run.scored(&run.relations), cartographer, graph_mapping);
}

/// Prints the rows and asserts the acceptance bound.
fn report(name: &str, s: &Scored, cartographer: f64, graph_mapping: f64) {
    for (what, r) in [("odometry", &s.odometry), ("SLAM poses", &s.slam), ("track (estimator)", &s.track)] {
        eprintln!(
            "| {name} | {what} | {}/{} | {:.4} ± {:.4} | {:.3} ± {:.3} |",
            r.scored, r.relations, r.translation_mean_m, r.translation_std_m, r.rotation_mean_deg, r.rotation_std_deg
        );
    }
    eprintln!("| {name} | Cartographer | | {cartographer:.4} | | graph mapping {graph_mapping:.4} |");
    assert_eq!(s.track.unmatched, 0, "{name}: every relation stamp is a scan stamp");
    assert!(
        s.track.translation_mean_m <= 1.5 * cartographer,
        "{name}: mean translational error {:.4} m > 1.5 × Cartographer's {cartographer} m",
        s.track.translation_mean_m
    );
}

#[test]
fn intel() {
    check("Intel", "rosbag1-slam-benchmark/intel.orig.bag", "slam-benchmark-relations/intel.relations", 0.0229, 0.031);
}

#[test]
fn freiburg_079() {
    check(
        "Freiburg 079",
        "rosbag1-slam-benchmark/fr079.orig.bag",
        "slam-benchmark-relations/fr079.relations",
        0.0452,
        0.056,
    );
}

#[test]
fn aces() {
    check("ACES", "rosbag1-slam-benchmark/aces.orig.bag", "slam-benchmark-relations/aces.relations", 0.0375, 0.044);
}

#[test]
fn mit_csail() {
    check("MIT CSAIL", "mit-csail-raw/mit-csail.clf", "slam-benchmark-relations/mit-csail.relations", 0.0319, 0.004);
}

/// MIT Killian Court: the bag's stamps are synthetic (10⁹ s + 0.1 s × the scan's index),
/// its relations name the raw log's real scan stamps. The relations are matched to the
/// bag's scans by order ([`by_order`]).
#[test]
fn mit_killian() {
    let Some(run) =
        run("rosbag1-slam-benchmark/mit-killian.clf2bag.bag", "slam-benchmark-relations/mit-killian.relations")
    else {
        return;
    };
    let relations = by_order(&run);
    report("MIT Killian (matched by order)", &run.scored(&relations), 0.0395, 0.050);
}

/// The pose of a stamp-sorted track at exactly `t`.
fn pose_of(track: &[(Stamp, Pose2)], t: Stamp) -> Option<Pose2> {
    track.binary_search_by_key(&t, |s| s.0).ok().map(|i| track[i].1)
}

/// Mean absolute heading error of `track` over `relations` (NaN when nothing scored).
fn heading_error(relations: &[Relation], track: &[(Stamp, Pose2)], matching: &RelationMatching) -> f64 {
    score_trajectory(relations, track, matching).rotation_mean_deg
}

/// The relations re-stamped onto the bag's scans by order.
///
/// 1. The raw log's scans came every P ≈ 0.44 s, so each gap between consecutive relation
///    stamps is a whole number of scans: P is fitted to the gaps (least squares over the
///    rounded counts) and every gap must round unambiguously (within a quarter scan). The
///    relation stamps become scan indices up to one offset `i0` (the first one's index).
/// 2. The offset is read off the data, never off SLAM's score: the raw odometry fits the
///    relations' headings best at one offset; in this bag the odometry runs `lag` scans
///    ahead of the laser (the shift at which the SLAM track's heading increments, made
///    from the laser, best follow the odometry's), and the relations are laser poses, so
///    `i0` = the odometry's best offset + `lag`.
fn by_order(run: &Run) -> Vec<Relation> {
    let stamps = &run.stamps;
    let mut real: Vec<i64> = run.relations.iter().flat_map(|r| [r.t1.0, r.t2.0]).collect();
    real.sort_unstable();
    real.dedup();
    let gaps: Vec<f64> = real.windows(2).map(|w| (w[1] - w[0]) as f64 * 1e-9).collect();
    let shortest = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    let short: Vec<f64> = gaps.iter().copied().filter(|g| *g < 3.5 * shortest).collect();
    let mut period = short.iter().sum::<f64>() / short.iter().map(|g| (g / shortest).round()).sum::<f64>();
    for _ in 0..3 {
        let (num, den) = gaps.iter().fold((0.0, 0.0), |(a, b), g| {
            let n = (g / period).round();
            (a + g * n, b + n * n)
        });
        period = num / den;
    }
    let worst = gaps.iter().map(|g| (g / period - (g / period).round()).abs()).fold(0.0, f64::max);
    assert!(worst < 0.25, "a gap of {worst} scans off a whole number at {period} s a scan: no order to match");
    let mut index = vec![0usize];
    for g in &gaps {
        index.push(index.last().unwrap() + (g / period).round() as usize);
    }
    let span = *index.last().unwrap();
    assert!(
        span < stamps.len(),
        "{span} scans between the first and last relation stamps, {} in the bag",
        stamps.len()
    );
    let restamp = |i0: usize| -> Vec<Relation> {
        let at = |t: Stamp| stamps[i0 + index[real.binary_search(&t.0).unwrap()]];
        run.relations.iter().map(|r| Relation { t1: at(r.t1), t2: at(r.t2), ..*r }).collect()
    };
    let offsets = 0..stamps.len() - span;
    let odometry_best = offsets
        .clone()
        .min_by(|a, b| {
            heading_error(&restamp(*a), &run.odometry, &run.matching).total_cmp(&heading_error(
                &restamp(*b),
                &run.odometry,
                &run.matching,
            ))
        })
        .unwrap();
    // Heading increments scan to scan, of the scans both tracks have.
    let both: Vec<(f64, f64)> = stamps
        .iter()
        .filter_map(|t| Some((pose_of(&run.track, *t)?.theta, pose_of(&run.odometry, *t)?.theta)))
        .collect();
    let (laser, odometry): (Vec<f64>, Vec<f64>) =
        both.windows(2).map(|w| (normalize_angle(w[1].0 - w[0].0), normalize_angle(w[1].1 - w[0].1))).unzip();
    let rms_at = |lag: i64| -> f64 {
        let n = laser.len() as i64 - lag.abs();
        let sum: f64 = (0..n)
            .map(|k| {
                let (l, o) = if lag >= 0 { (k + lag, k) } else { (k, k - lag) };
                (laser[l as usize] - odometry[o as usize]).powi(2)
            })
            .sum();
        (sum / n as f64).sqrt()
    };
    let lag = (-3..=3).min_by(|a, b| rms_at(*a).total_cmp(&rms_at(*b))).unwrap();
    let i0 = odometry_best as i64 + lag;
    eprintln!(
        "MIT Killian by order: {} relation stamps over {span} scans of {period:.5} s (worst gap {worst:.3} scans off), odometry best at scan {odometry_best}, the laser {lag} scan(s) behind the odometry: first relation stamp = scan {i0} of {}",
        real.len(),
        stamps.len()
    );
    assert!((0..(stamps.len() - span) as i64).contains(&i0), "offset {i0} outside the bag");
    restamp(i0 as usize)
}
