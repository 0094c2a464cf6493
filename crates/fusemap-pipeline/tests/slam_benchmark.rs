//! The SLAM benchmark (Kümmerle et al. 2009) on the raw logs whose scan stamps match their
//! relations files: fusemap's mean translational error must be at most 1.5× Cartographer's
//! (Hess et al. 2016, Table II). Reads `../shared`; skips with a notice without it.
//!
//! Each log is its own test; `-- --nocapture` prints the table row.

use fusemap_core::config::Config;
use fusemap_core::geometry::Pose2;
use fusemap_core::metrics::{parse_relations, score_relations, RelationScore};
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::testdata::dataset;
use fusemap_pipeline::recording::Inventory;
use fusemap_pipeline::run::prepare;
use fusemap_pipeline::track::Track;

/// Relation stamps are written with microseconds (MIT CSAIL: 10 µs); the logs hold the
/// same instants rounded to nanoseconds, up to 5 µs off; the next scan is ≥ 200 µs away.
const TOLERANCE_NS: i64 = 100_000;

struct Scored {
    slam: RelationScore,
    track: RelationScore,
    odometry: RelationScore,
}

fn score(log: &str, relations: &str) -> Option<Scored> {
    let log = dataset(log)?;
    let rel = dataset(relations)?;
    let relations = parse_relations(&std::fs::read_to_string(&rel).unwrap()).unwrap();
    // FUSEMAP_SLAM_TOML: a `[slam]` table to try other settings without rebuilding.
    let mut config = Config::default();
    if let Ok(t) = std::env::var("FUSEMAP_SLAM_TOML") {
        config.slam = toml::from_str(&t).expect("FUSEMAP_SLAM_TOML is a [slam] table");
    }
    let plan = config.validate().unwrap();
    let inv = Inventory::read(&log).unwrap();
    let (bound, chosen, _) = prepare(&plan, &inv).unwrap();
    let slam = chosen.slam.as_ref().expect("SLAM runs on a raw log");
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
    if std::env::var("FUSEMAP_SLAM_DEBUG").is_ok() {
        let e = chosen.estimator.as_ref().map(|v| v.to_string()).unwrap_or_default();
        eprintln!("estimator: {}", &e[..e.len().min(3000)]);
    }
    let stamps = &inv.scans[&bound.lidars[0].topic].stamps;
    // The relations are between laser poses (the scans' origins); fusemap's trajectory is
    // the base frame's. Freiburg 079's laser sits 4 cm ahead of its base, the others' at it.
    let [x, y, yaw] = slam.sensor_in_base;
    let laser = Pose2::new(x, y, yaw);
    let Track::Timed(track) = &chosen.track else { panic!("SLAM gives a timed track") };
    let at = |t: &Stamp| track.pose_at(*t, SyncMode::Interpolate).ok().map(|p| (*t, p.compose(laser)));
    let mut tracked: Vec<_> = stamps.iter().filter_map(at).collect();
    tracked.sort_by_key(|s| s.0);
    let odo_plan = {
        let mut c = Config::default();
        c.slam.mode = fusemap_core::config::SlamMode::Off;
        c.validate().unwrap()
    };
    let (_, raw, _) = prepare(&odo_plan, &inv).unwrap();
    let mut odometry: Vec<_> = match &raw.track {
        Track::Timed(t) => stamps
            .iter()
            .filter_map(|s| t.pose_at(*s, SyncMode::Interpolate).ok().map(|p| (*s, p.compose(laser))))
            .collect(),
        Track::ScanLine => Vec::new(),
    };
    odometry.sort_by_key(|s| s.0);
    let scan_poses: Vec<(Stamp, Pose2)> = slam.scan_poses.iter().map(|&(t, p)| (t, p.compose(laser))).collect();
    if let Ok(dir) = std::env::var("FUSEMAP_SLAM_DUMP") {
        let name = log.file_name().unwrap().to_string_lossy().to_string();
        let lines: String = scan_poses.iter().map(|(t, p)| format!("{} {} {} {}\n", t.0, p.x, p.y, p.theta)).collect();
        std::fs::write(format!("{dir}/{name}.slam.txt"), lines).unwrap();
        let errs = fusemap_core::metrics::relation_errors(&relations, &scan_poses, TOLERANCE_NS);
        let lines: String = relations
            .iter()
            .zip(errs)
            .filter_map(|(r, e)| e.map(|e| format!("{} {} {} {}\n", r.t1.0, r.t2.0, e.x.hypot(e.y), e.theta)))
            .collect();
        std::fs::write(format!("{dir}/{name}.errors.txt"), lines).unwrap();
    }
    Some(Scored {
        slam: score_relations(&relations, &scan_poses, TOLERANCE_NS),
        track: score_relations(&relations, &tracked, TOLERANCE_NS),
        odometry: score_relations(&relations, &odometry, TOLERANCE_NS),
    })
}

fn check(name: &str, log: &str, relations: &str, cartographer: f64, graph_mapping: f64) {
    let Some(s) = score(log, relations) else { return };
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
