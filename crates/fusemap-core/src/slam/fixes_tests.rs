use super::*;
use crate::slam::test_world::World;
use crate::slam::{ScanInput, Slam, SlamResult};

const SCAN_NS: i64 = 100_000_000;

/// 30 m along the featureless corridor at 0.5 m/s (5 cm per scan, 10 Hz): the scans hold
/// the lateral position and the heading, nothing holds the distance travelled.
fn corridor_truth() -> Vec<Pose2> {
    (0..=600).map(|i| Pose2::new(-15.0 + 0.05 * i as f64, 0.2, 0.0)).collect()
}

/// Odometry reading 3 % long: 0.9 m short of the truth after the corridor.
fn long_odometry(truth: &[Pose2]) -> Vec<Pose2> {
    truth.iter().map(|t| Pose2::new(truth[0].x + 1.03 * (t.x - truth[0].x), t.y, t.theta)).collect()
}

/// The antenna, 0.3 m ahead of the base and 0.2 m to its left.
const ANTENNA: Point2 = Point2 { x: 0.3, y: 0.2 };

/// A fix every second, 40 ms after a scan (between nodes), from the true pose there; the
/// track's pose at that stamp is the odometry's, interpolated, with a loose covariance.
fn fixes(truth: &[Pose2], odo: &[Pose2], noise: f64) -> Vec<PositionFix> {
    (0..truth.len() - 1)
        .step_by(10)
        .enumerate()
        .map(|(k, i)| {
            let at = |p: &[Pose2]| p[i].interpolate(p[i + 1], 0.4);
            let truth_pose = at(truth);
            let wobble = if k % 2 == 0 { noise } else { -noise };
            let p = truth_pose.transform_point(ANTENNA);
            PositionFix {
                stamp: Stamp(i as i64 * SCAN_NS + 40_000_000),
                position: Point2::new(p.x + wobble, p.y - wobble),
                covariance: [[0.02f64.powi(2), 0.0], [0.0, 0.02f64.powi(2)]],
                antenna: ANTENNA,
                correlation_time_s: 0.0,
                track: Some((at(odo), [[0.25, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 1e-4]])),
            }
        })
        .collect()
}

/// A scan from `pose` whose beams start at a different bearing every scan (a real lidar's
/// are not locked to the robot's motion), with ±1 cm of range noise: in a uniform
/// corridor, beams at the same bearings would see the same scan everywhere, and a match
/// would lock onto its own sampling.
fn scan(world: &World, pose: Pose2, i: usize) -> Vec<Point2> {
    let jitter = (i as f64 * 0.618_033_988_75).fract() * 1f64.to_radians();
    let turned = Pose2::new(pose.x, pose.y, pose.theta + jitter);
    let back = Pose2::new(0.0, 0.0, jitter);
    world
        .scan(turned, 360, 8.0)
        .into_iter()
        .enumerate()
        .map(|(k, q)| {
            let r = q.x.hypot(q.y);
            let noise = 0.01 * ((k * 7 + i * 13) % 21) as f64 / 10.0 - 0.01;
            back.transform_point(Point2::new(q.x * (r + noise) / r, q.y * (r + noise) / r))
        })
        .collect()
}

fn run(p: SlamParams, truth: &[Pose2], odo: &[Pose2], fixes: &[PositionFix]) -> SlamResult {
    let world = World::corridor();
    let mut slam = Slam::new(p);
    slam.add_fixes(fixes);
    for (i, (pose, track)) in truth.iter().zip(odo).enumerate() {
        let hits = scan(&world, *pose, i);
        let stamp = Stamp(i as i64 * SCAN_NS);
        slam.add_scan(ScanInput {
            stamp,
            track: Some(*track),
            origin: Point2::new(0.0, 0.0),
            hits: &hits,
            misses: &[],
        });
    }
    slam.finish()
}

/// Mean and largest distance of the SLAM poses from the truth.
fn errors(r: &SlamResult, truth: &[Pose2]) -> (f64, f64) {
    assert_eq!(r.trajectory.len(), truth.len());
    let e: Vec<f64> = r.trajectory.iter().zip(truth).map(|((_, p), t)| (p.x - t.x).hypot(p.y - t.y)).collect();
    (e.iter().sum::<f64>() / e.len() as f64, e.iter().copied().fold(0.0, f64::max))
}

#[test]
fn fixes_hold_the_distance_a_corridor_cannot() {
    let truth = corridor_truth();
    let odo = long_odometry(&truth);
    let without = run(SlamParams::default(), &truth, &odo, &[]);
    let (drift_mean, drift_max) = errors(&without, &truth);
    assert!(
        drift_mean > 0.3 && drift_max > 0.8,
        "the corridor leaves the odometry's drift: {drift_mean} m, {drift_max} m"
    );
    // No closure along the corridor: each would fit anywhere in its window.
    assert_eq!(without.report.loop_accepted, 0, "{:?}", without.report);
    assert!(without.report.loop_degenerate > 0, "{:?}", without.report);

    let fixes = fixes(&truth, &odo, 0.01);
    let with = run(SlamParams::default(), &truth, &odo, &fixes);
    let rep = &with.report;
    assert_eq!(rep.fixes, fixes.len() as u64);
    assert_eq!(rep.fix_priors, fixes.len() as u64, "{rep:?}");
    assert!(rep.optimisation_failures.is_empty(), "{:?}", rep.optimisation_failures);
    let (mean, max) = errors(&with, &truth);
    eprintln!("corridor: odometry-only SLAM {drift_mean:.3} m mean, {drift_max:.3} m largest; with fixes {mean:.3} m, {max:.3} m");
    // The ends keep some of the stretch: a submap is tied to its first node stiffly, and
    // its other nodes to it by matches whose position along the corridor is the odometry's.
    assert!(mean < 0.06 && max < 0.25, "with fixes {mean} m (largest {max} m), without {drift_mean} m");
    // Fixes 30 m apart hold the graph: its first node is no longer held.
    assert!(!with.graph.is_fixed(with.scan_nodes[0]));
}

#[test]
fn the_lever_arm_is_applied() {
    let truth = corridor_truth();
    let odo = long_odometry(&truth);
    let good = fixes(&truth, &odo, 0.0);
    // The same fixes read as if the antenna were on the base: a bias of 0.36 m.
    let on_base: Vec<PositionFix> = good.iter().map(|f| PositionFix { antenna: Point2::new(0.0, 0.0), ..*f }).collect();
    let (exact, _) = errors(&run(SlamParams::default(), &truth, &odo, &good), &truth);
    let (biased, _) = errors(&run(SlamParams::default(), &truth, &odo, &on_base), &truth);
    eprintln!("lever arm applied {exact:.3} m mean error, forgotten {biased:.3} m");
    assert!(exact < 0.06, "exact fixes: {exact} m");
    assert!(biased > 0.25, "a forgotten lever arm: {biased} m");
}

#[test]
fn a_fix_between_two_nodes_goes_on_the_nearer_with_the_track_motion_between() {
    let mut graph = PoseGraph::new();
    let (a, b) = (graph.add_node(Pose2::new(0.0, 0.0, 0.0)), graph.add_node(Pose2::new(1.0, 0.0, 0.0)));
    let node = |stamp_ms: i64, x: f64, graph: usize| FixNode {
        stamp: Stamp(stamp_ms * 1_000_000),
        track: Some(Pose2::new(x, 0.0, 0.0)),
        graph,
    };
    // The track turned 90° between the first node and the fix, and moved 0.4 m.
    let at_fix = Pose2::new(0.4, 0.0, std::f64::consts::FRAC_PI_2);
    let fix = PositionFix {
        stamp: Stamp(400_000_000),
        position: at_fix.transform_point(ANTENNA),
        covariance: [[1e-4, 0.0], [0.0, 1e-4]],
        antenna: ANTENNA,
        correlation_time_s: 0.0,
        track: Some((at_fix, [[0.0; 3]; 3])),
    };
    let mut report = SlamReport::default();
    let mut priors = FixPriors::new();
    priors.add(&[fix], &mut report);
    let p = SlamParams::default();
    // Not yet: the fix is later than `upto`.
    priors.attach(Stamp(300_000_000), None, Some(node(0, 0.0, a)), true, &mut graph, &p, &mut report);
    assert!(graph.position_priors().is_empty());
    priors.attach(
        Stamp(1_000_000_000),
        Some(node(0, 0.0, a)),
        Some(node(1000, 1.0, b)),
        true,
        &mut graph,
        &p,
        &mut report,
    );
    let prior = graph.position_priors()[0];
    assert_eq!(prior.node, a, "0.4 s from the first node, 0.6 s from the second");
    // The antenna at the fix, in the first node's frame: 0.4 m ahead, turned 90°.
    let expected = Pose2::new(0.4, 0.0, std::f64::consts::FRAC_PI_2).transform_point(ANTENNA);
    assert!((prior.lever_arm.x - expected.x).abs() < 1e-12 && (prior.lever_arm.y - expected.y).abs() < 1e-12);
    assert_eq!((report.fixes, report.fix_priors), (1, 1));
    assert!((prior.information[0][0] - 1e4).abs() < 1e-6);
}

#[test]
fn a_fix_far_from_the_track_is_gated_and_a_fix_without_one_is_not_placed() {
    let truth = corridor_truth();
    let odo = long_odometry(&truth);
    let mut fixes = fixes(&truth, &odo, 0.01);
    fixes[20].position.y += 8.0;
    fixes[30].track = None;
    // A fix far from any node in time.
    fixes.push(PositionFix { stamp: Stamp(200 * SCAN_NS * 10), ..fixes[0] });
    let r = run(SlamParams::default(), &truth, &odo, &fixes);
    let rep = &r.report;
    assert_eq!((rep.fixes_gated, rep.fixes_unplaced), (1, 2), "{rep:?}");
    assert_eq!(rep.fix_priors, fixes.len() as u64 - 3);
    let (mean, _) = errors(&r, &truth);
    assert!(mean < 0.06, "{mean} m");
}

#[test]
fn fixes_are_ignored_when_turned_off_or_when_the_graph_is_not_in_their_frame() {
    let truth = corridor_truth();
    let odo = long_odometry(&truth);
    let fixes = fixes(&truth, &odo, 0.01);
    let off = run(SlamParams { fixes: false, ..SlamParams::default() }, &truth, &odo, &fixes);
    assert_eq!((off.report.fixes, off.report.fix_priors), (0, 0));
    // The first scan without a track pose: the graph starts at the origin, not in the
    // fixes' frame.
    let world = World::corridor();
    let mut slam = Slam::new(SlamParams::default());
    slam.add_fixes(&fixes);
    for (i, (pose, track)) in truth.iter().zip(&odo).enumerate() {
        let hits = scan(&world, *pose, i);
        let track = (i > 0).then_some(*track);
        slam.add_scan(ScanInput {
            stamp: Stamp(i as i64 * SCAN_NS),
            track,
            origin: Point2::new(0.0, 0.0),
            hits: &hits,
            misses: &[],
        });
    }
    let r = slam.finish();
    assert_eq!((r.report.fix_priors, r.report.fixes_unplaced), (0, fixes.len() as u64));
    // No scan at all: every fix is counted as unplaced.
    let mut slam = Slam::new(SlamParams::default());
    slam.add_fixes(&fixes);
    let r = slam.finish();
    assert_eq!(
        (r.report.fixes, r.report.fix_priors, r.report.fixes_unplaced),
        (fixes.len() as u64, 0, fixes.len() as u64)
    );
}

#[test]
fn the_antenna_covariance_follows_the_heading_uncertainty() {
    let pose = Pose2::new(1.0, 2.0, 0.0);
    let cov = [[0.0; 3], [0.0; 3], [0.0, 0.0, 0.01]];
    // An antenna 1 m ahead: a heading σ of 0.1 rad moves it 0.1 m sideways.
    let c = antenna_covariance(pose, cov, Point2::new(1.0, 0.0));
    assert!((c[0][0]).abs() < 1e-12 && (c[1][1] - 0.01).abs() < 1e-12, "{c:?}");
    assert_eq!(inverse2([[4.0, 0.0], [0.0, 0.25]]), Some([[0.25, 0.0], [0.0, 4.0]]));
    assert_eq!(inverse2([[1.0, 1.0], [1.0, 1.0]]), None);
}
