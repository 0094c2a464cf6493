use super::*;
use crate::slam::pose_graph::{Edge, EdgeKind, Loss};
use crate::slam::test_world::World;

/// A deterministic pseudo-random sequence in [-1, 1) (a 64-bit LCG), so the tests' noise
/// is the same on every machine.
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// True poses at 10 Hz: `loops` times around the room's free ring at 0.5 m/s, turning in
/// place at 45°/s at the corners.
fn ring_poses(loops: usize) -> Vec<Pose2> {
    let corners = [(1.0, 1.0), (11.0, 1.0), (11.0, 7.2), (1.0, 7.2)];
    let mut out = vec![Pose2::new(1.0, 1.0, 0.0)];
    for _ in 0..loops {
        for k in 0..4 {
            let (x1, y1) = corners[(k + 1) % 4];
            let last = *out.last().unwrap();
            let heading = (y1 - last.y).atan2(x1 - last.x);
            // Turn to the heading, 4.5° per scan …
            let mut th = last.theta;
            while normalize_angle(heading - th).abs() > 1e-9 {
                th += normalize_angle(heading - th).clamp(-4.5f64.to_radians(), 4.5f64.to_radians());
                out.push(Pose2::new(last.x, last.y, normalize_angle(th)));
            }
            // … then drive 5 cm per scan.
            let d = (x1 - last.x).hypot(y1 - last.y);
            let n = (d / 0.05).round() as usize;
            for i in 1..=n {
                let f = i as f64 / n as f64;
                out.push(Pose2::new(last.x + f * (x1 - last.x), last.y + f * (y1 - last.y), heading));
            }
        }
    }
    out
}

/// Odometry of `truth`: each increment scaled by 1.03 and turned by 0.6° per metre (a
/// wheel-radius difference), with a little noise.
fn odometry(truth: &[Pose2], seed: u64) -> Vec<Pose2> {
    let mut noise = Noise(seed);
    let mut out = vec![truth[0]];
    for w in truth.windows(2) {
        let d = w[0].inverse().compose(w[1]);
        let dist = d.x.hypot(d.y);
        let step = Pose2::new(
            d.x * 1.03 + 0.002 * noise.next(),
            d.y * 1.03 + 0.002 * noise.next(),
            d.theta * 1.02 + dist * 0.6f64.to_radians() + 0.002 * noise.next(),
        );
        out.push(out.last().unwrap().compose(step));
    }
    out
}

struct Run {
    result: SlamResult,
    truth: Vec<Pose2>,
}

/// Runs SLAM over `truth` with `track` as the pose track, scans of `beams` beams.
fn run(truth: &[Pose2], track: &[Option<Pose2>], beams: usize) -> Run {
    run_with(SlamParams::default(), truth, track, beams)
}

fn run_with(p: SlamParams, truth: &[Pose2], track: &[Option<Pose2>], beams: usize) -> Run {
    run_observed(p, truth, track, beams, |_, _| {})
}

/// [`run_with`], calling `after(slam, i)` after the `i`-th scan.
fn run_observed(
    p: SlamParams,
    truth: &[Pose2],
    track: &[Option<Pose2>],
    beams: usize,
    mut after: impl FnMut(&mut Slam, usize),
) -> Run {
    let world = World::room();
    let mut noise = Noise(7);
    let mut slam = Slam::new(p);
    for (i, (pose, track)) in truth.iter().zip(track).enumerate() {
        // ±1 cm of range noise.
        let hits = world.noisy_scan(*pose, beams, 30.0, || 0.01 * noise.next());
        let stamp = Stamp(1_000_000_000 + i as i64 * 100_000_000);
        slam.add_scan(ScanInput { stamp, track: *track, origin: Point2::new(0.0, 0.0), hits: &hits, misses: &[] });
        after(&mut slam, i);
    }
    Run { result: slam.finish(), truth: truth.to_vec() }
}

/// Mean and largest distance of the SLAM poses from the truth (the first pose is the
/// track's, which is the truth's, so the frames agree).
fn errors(r: &Run) -> (f64, f64) {
    assert_eq!(r.result.trajectory.len(), r.truth.len(), "every scan has a pose");
    let e: Vec<f64> =
        r.result.trajectory.iter().zip(&r.truth).map(|((_, p), t)| (p.x - t.x).hypot(p.y - t.y)).collect();
    (e.iter().sum::<f64>() / e.len() as f64, e.iter().cloned().fold(0.0, f64::max))
}

fn track_errors(track: &[Pose2], truth: &[Pose2]) -> f64 {
    track.iter().zip(truth).map(|(p, t)| (p.x - t.x).hypot(p.y - t.y)).sum::<f64>() / truth.len() as f64
}

#[test]
fn two_loops_with_drifting_odometry_are_closed_and_follow_the_truth() {
    let truth = ring_poses(2);
    let odo = odometry(&truth, 1);
    let r = run(&truth, &odo.iter().map(|p| Some(*p)).collect::<Vec<_>>(), 360);
    let (mean, max) = errors(&r);
    let odo_mean = track_errors(&odo, &truth);
    let rep = &r.result.report;
    assert!(odo_mean > 0.3, "the odometry drifts: {odo_mean}");
    assert!(mean < 0.03 && max < 0.1, "SLAM error mean {mean} m, max {max} m (odometry {odo_mean} m)");
    assert!(rep.loop_accepted > 0, "{rep:?}");
    assert_eq!(rep.matched + rep.degenerate + rep.predicted, truth.len() as u64);
    assert!(rep.optimisation_failures.is_empty(), "{:?}", rep.optimisation_failures);
}

#[test]
fn a_scan_with_too_few_returns_keeps_its_prediction_and_is_counted() {
    let truth = ring_poses(1)[..300].to_vec();
    let track: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
    // Every scan but the first 100 has 8 beams: too few to match (min_points 20).
    let world = World::room();
    let mut slam = Slam::new(SlamParams::default());
    for (i, (pose, t)) in truth.iter().zip(&track).enumerate() {
        let hits = world.scan(*pose, if i < 100 { 360 } else { 8 }, 30.0);
        let stamp = Stamp(i as i64 * 100_000_000);
        let outcome =
            slam.add_scan(ScanInput { stamp, track: *t, origin: Point2::new(0.0, 0.0), hits: &hits, misses: &[] });
        if i >= 100 {
            assert_eq!(outcome, ScanOutcome::Predicted, "scan {i}");
        }
    }
    let result = slam.finish();
    assert!(result.report.predicted >= 200, "{:?}", result.report);
    // The predictions follow the (here exact) track.
    let last = result.trajectory.last().unwrap().1;
    let t = truth.last().unwrap();
    assert!((last.x - t.x).hypot(last.y - t.y) < 0.05, "{last:?} vs {t:?}");
}

#[test]
fn a_robot_that_never_moves_gives_one_pose() {
    let truth = vec![Pose2::new(6.0, 4.0, 0.3); 300];
    let track: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
    let r = run(&truth, &track, 360);
    let (mean, max) = errors(&r);
    assert!(mean < 0.01 && max < 0.02, "mean {mean}, max {max}");
    // Nodes only by time (every 5 s of 30 s).
    assert!(r.result.report.nodes <= 7, "{:?}", r.result.report);
}

#[test]
fn a_log_that_starts_mid_turn_is_followed() {
    // Turning in place at 60°/s from the first scan, with odometry that under-reads the
    // turn by 10 %.
    let truth: Vec<Pose2> =
        (0..120).map(|i| Pose2::new(6.0, 4.0, normalize_angle(0.2 + i as f64 * 6f64.to_radians()))).collect();
    let track: Vec<Option<Pose2>> = (0..120)
        .map(|i| Some(Pose2::new(6.0, 4.0, normalize_angle(0.2 + 0.9 * i as f64 * 6f64.to_radians()))))
        .collect();
    let r = run(&truth, &track, 360);
    let worst = r
        .result
        .trajectory
        .iter()
        .zip(&truth)
        .map(|((_, p), t)| normalize_angle(p.theta - t.theta).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1f64.to_radians(), "heading error up to {} deg", worst.to_degrees());
    let (_, max) = errors(&r);
    assert!(max < 0.05, "{max}");
}

#[test]
fn odometry_that_jumps_is_left_out_and_the_scans_stay_on_the_truth() {
    let truth = ring_poses(1);
    let mut odo = odometry(&truth, 3);
    // At scan 150 the odometry jumps 0.8 m sideways and stays there (a reset, a glitch).
    for p in odo.iter_mut().skip(150) {
        *p = Pose2::new(0.0, 0.8, 0.0).compose(*p);
    }
    let r = run(&truth, &odo.iter().map(|p| Some(*p)).collect::<Vec<_>>(), 360);
    let (mean, max) = errors(&r);
    let rep = &r.result.report;
    assert!(rep.odometry_edges_rejected >= 1, "{rep:?}");
    assert!(rep.moving_prediction_used >= 1, "{rep:?}");
    assert!(rep.moving_prediction_searched >= rep.moving_prediction_used, "{rep:?}");
    assert!(mean < 0.05 && max < 0.15, "mean {mean}, max {max}");
}

/// Odometry of `truth` that jumps by `offset` (world frame) from scan `from` on, or on
/// every odd scan when `alternate`.
fn jumping_track(truth: &[Pose2], offset: f64, from: usize, alternate: bool) -> Vec<Option<Pose2>> {
    let odo = odometry(truth, 3);
    let shifted = |i: usize| if alternate { i % 2 == 1 } else { i >= from };
    odo.iter()
        .enumerate()
        .map(|(i, p)| Some(if shifted(i) { Pose2::new(p.x + offset, p.y - offset, p.theta) } else { *p }))
        .collect()
}

#[test]
fn a_track_that_teleports_is_not_followed_and_the_submaps_stay_small() {
    // An odometry reset of 10¹⁷ m, a GNSS jump of 1,000 km that stays, and a track
    // alternating by ±10¹⁷ m: no scan can have moved that far, so the jump is taken as a
    // gap of the track (matched from the previous pose), counted, and never drawn into a
    // submap (a grid spanning it would need 10³⁶ cells).
    // At 10¹⁷ m the odometry's own increments are lost to rounding (its values are 16 m
    // apart), so every step that rounds to one is another jump.
    let truth = ring_poses(1);
    let all = truth.len() as u64 - 1;
    for (offset, alternate, jumps) in [(1e6, false, 1..=1), (1e17, false, 1..=all), (1e17, true, all..=all)] {
        let r = run(&truth, &jumping_track(&truth, offset, 150, alternate), 360);
        let (mean, max) = errors(&r);
        let rep = &r.result.report;
        let case = format!("offset {offset}, alternate {alternate}");
        assert!(jumps.contains(&rep.track_jumps), "{case}: {} jumps", rep.track_jumps);
        assert!(mean < 0.05 && max < 0.2, "{case}: mean {mean}, max {max}");
        let mib = rep.submap_peak_bytes as f64 / (1 << 20) as f64;
        assert!(mib < 16.0, "{case}: the submaps held {mib:.1} MiB");
    }
}

#[test]
fn a_non_finite_track_pose_is_refused_and_counted() {
    let truth = ring_poses(1)[..50].to_vec();
    let mut track: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
    track[20] = Some(Pose2::new(f64::NAN, 0.0, 0.0));
    track[21] = None;
    let r = run(&truth, &track, 360);
    assert_eq!(r.result.report.refused, 1);
    assert_eq!(r.result.report.without_track, 1);
    // The refused scan has no pose; the others do.
    assert_eq!(r.result.trajectory.len(), truth.len() - 1);
}

/// The largest heading error of a run, degrees.
fn worst_heading_deg(r: &Run) -> f64 {
    let worst = r
        .result
        .trajectory
        .iter()
        .zip(&r.truth)
        .map(|((_, p), t)| normalize_angle(p.theta - t.theta).abs())
        .fold(0.0, f64::max);
    worst.to_degrees()
}

/// At rest for 20 scans, a turn in place of `steps` × `deg_per_scan`, at rest for 20 more.
fn turn_in_place(steps: usize, deg_per_scan: f64) -> Vec<Pose2> {
    let mut th = 0.3;
    let mut out = vec![Pose2::new(6.0, 4.0, th); 20];
    for _ in 0..steps {
        th += deg_per_scan.to_radians();
        out.push(Pose2::new(6.0, 4.0, normalize_angle(th)));
    }
    out.extend(vec![Pose2::new(6.0, 4.0, normalize_angle(th)); 20]);
    out
}

#[test]
fn odometry_held_through_a_fast_turn_is_not_taken_for_a_standstill() {
    // Turning at 15° a scan, odometry latched on the scan lines: it repeats its value for
    // four scans, then jumps by the whole turn since (as the MIT CSAIL log's does).
    let truth = turn_in_place(36, 15.0);
    let track: Vec<Option<Pose2>> =
        (0..truth.len()).map(|i| Some(if (25..29).contains(&i) { truth[24] } else { truth[i] })).collect();
    let r = run(&truth, &track, 360);
    let rep = &r.result.report;
    // At rest the reading repeats too: 19 scans before the turn, 4 held in it, 20 after.
    assert_eq!(rep.held_readings, 19 + 4 + 20, "{rep:?}");
    let worst = worst_heading_deg(&r);
    assert!(worst < 1.0, "heading error up to {worst} deg: {rep:?}");
    // No node was made of a scan matched without a reading: the nodes are the first scan
    // and one per fresh reading of the turn. (In this clean world the constant-velocity
    // hypothesis follows the turn even when the held readings are taken for a standstill,
    // but then the held scans of the turn become nodes too.)
    assert!(rep.nodes <= 1 + 36 - 4, "{rep:?}");
}

#[test]
fn a_match_lost_by_a_bad_prediction_is_searched_again_wider() {
    // The robot starts turning at 20° a scan; its odometry reads 1.8 times the turn. At the
    // first turning scan neither the track (36°) nor the constant velocity (0°) is within
    // reach of the 6° window (and the likelihood field's slope around it) of the truth.
    let truth = turn_in_place(9, 20.0);
    let mut track = vec![Some(truth[0])];
    for w in truth.windows(2) {
        let d = w[0].inverse().compose(w[1]);
        let last = track.last().unwrap().unwrap();
        track.push(Some(last.compose(Pose2::new(0.0, 0.0, 1.8 * d.theta))));
    }
    let r = run(&truth, &track, 360);
    let rep = &r.result.report;
    assert!(rep.rescued >= 1 && rep.rescue_searched >= rep.rescued, "{rep:?}");
    let worst = worst_heading_deg(&r);
    assert!(worst < 1.0, "heading error up to {worst} deg: {rep:?}");
    // Without the wider search the same log loses the turn.
    let off = run_with(SlamParams { rescue_score_ratio: 0.0, ..SlamParams::default() }, &truth, &track, 360);
    assert_eq!(off.result.report.rescue_searched, 0);
    let lost = worst_heading_deg(&off);
    assert!(lost > 5.0, "without the rescue: heading error up to {lost} deg");
}

/// Loop-closure batches (each search its own task, the costliest first), the scan
/// matcher's halves and the insertion into the two active submaps run on every thread of
/// the pool, and the optimisations beside the matching on a thread of their own; their
/// results are taken in a fixed order, at fixed nodes, so the trajectory is the same to
/// the bit on 1, 2 and 4 threads.
#[cfg(feature = "parallel")]
#[test]
fn the_trajectory_is_bit_identical_on_one_two_and_four_threads() {
    let truth = ring_poses(2);
    let odo = odometry(&truth, 5);
    let track: Vec<Option<Pose2>> = odo.iter().map(|p| Some(*p)).collect();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let r = pool.install(|| run(&truth, &track, 360));
        assert!(r.result.report.loop_searches > 0, "the batches ran");
        assert!(r.result.report.optimisations_deferred > 0, "optimisations ran beside the matching");
        r.result.trajectory.iter().map(|(_, p)| [p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()]).collect::<Vec<_>>()
    };
    let one = on(1);
    assert_eq!(one, on(2), "2 threads");
    assert_eq!(one, on(4), "4 threads");
}

/// Adds `share` × (the closures accepted so far) wrong closures: a random node tied to a
/// random finished submap it did not go into, at the place of another random node (a
/// confident match to the wrong place, as a repetitive building gives).
fn inject_false_closures(slam: &mut Slam, share: f64, rng: &mut crate::sim::SplitMix64) -> usize {
    let accepted = slam.graph.edges().iter().filter(|e| e.kind == EdgeKind::LoopClosure).count();
    let want = (share * accepted as f64).round() as usize;
    let finished: Vec<usize> = (0..slam.finished.len()).filter(|&s| slam.finished[s]).collect();
    let mut added = 0;
    while added < want && !finished.is_empty() {
        let n = (rng.next_u64() % slam.nodes.len() as u64) as usize;
        let m = (rng.next_u64() % slam.nodes.len() as u64) as usize;
        let s = finished[(rng.next_u64() % finished.len() as u64) as usize];
        let wrong = slam.nodes[m].local.compose(Pose2::new(0.0, 0.0, rng.uniform(-0.5, 0.5)));
        if slam.nodes[n].submaps.contains(&s) || wrong.translation().distance(slam.nodes[n].local.translation()) < 1.0 {
            continue;
        }
        let e = Edge {
            from: slam.submap_graph[s],
            to: slam.nodes[n].graph,
            measurement: slam.submaps.all()[s].local_pose.inverse().compose(wrong),
            information: information_diag(slam.p.loop_closure_sigma_m, slam.p.loop_closure_sigma_rad),
            loss: Loss::Huber(slam.p.loop_closure_huber),
            kind: EdgeKind::LoopClosure,
        };
        slam.graph.add_edge(e).unwrap();
        added += 1;
    }
    added
}

/// The robust back end (Huber, then dynamic covariance scaling; odometry and matches as
/// known inliers): wrong closures, 5 % and 20 % of those accepted, added at random poses
/// half-way and at the end, move the trajectory by at most 5 cm (ATE between the runs).
#[test]
fn injected_false_closures_do_not_bend_the_trajectory() {
    let truth = ring_poses(2);
    let odo = odometry(&truth, 1);
    let track: Vec<Option<Pose2>> = odo.iter().map(|p| Some(*p)).collect();
    let run_injecting = |share: f64| {
        let mut rng = crate::sim::SplitMix64::new(11);
        let mut injected = 0;
        let r = run_observed(SlamParams::default(), &truth, &track, 360, |slam, i| {
            if share > 0.0 && (i == truth.len() / 2 || i + 1 == truth.len()) {
                injected += inject_false_closures(slam, share, &mut rng);
            }
        });
        (r.result, injected)
    };
    let (clean, _) = run_injecting(0.0);
    assert!(clean.report.loop_accepted > 10, "{:?}", clean.report);
    for share in [0.05, 0.2] {
        let (bent, injected) = run_injecting(share);
        assert!(injected > 0, "{share}: closures were injected");
        let moved = clean
            .trajectory
            .iter()
            .zip(&bent.trajectory)
            .map(|((_, a), (_, b))| (a.x - b.x).powi(2) + (a.y - b.y).powi(2))
            .sum::<f64>()
            / clean.trajectory.len() as f64;
        let moved = moved.sqrt();
        eprintln!("share {share} injected {injected} moved {moved}");
        assert!(moved <= 0.05, "{share}: {injected} wrong closures moved the trajectory by {moved:.3} m RMS");
    }
}

#[test]
fn the_nodes_points_count_in_the_bytes_slam_holds() {
    // Once around the room: every node's points (8 bytes each in f32) are in
    // `held_bytes`, beside the submaps' and the loop search's grids.
    let truth = ring_poses(1);
    let track: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
    let mut checked = 0;
    run_observed(SlamParams::default(), &truth, &track, 360, |slam, _| {
        let points: usize = slam.nodes.iter().map(|n| n.points.len()).sum();
        let grids = slam.submaps.bytes() + slam.grids.bytes();
        assert!(
            slam.held_bytes() >= grids + 8 * points,
            "{} held, {grids} in grids, {points} points",
            slam.held_bytes()
        );
        assert!(slam.held_bytes() <= grids + 8 * points + 200 * slam.nodes.len() + 4 * points);
        checked += usize::from(!slam.nodes.is_empty());
    });
    assert!(checked > 100, "{checked} scans with nodes");
}
