//! Logs SLAM cannot correct, or can only partly (issue 22's bad-input list): each must run
//! to the end without a panic and keep a finite pose for every scan; the hallway and the
//! corridor, which have no loop, must close none and say so in their findings; a closure
//! search over 10⁵ submaps must keep to its bounds and its work budget.

use super::test_world::World;
use super::{ScanInput, Slam, SlamParams, SlamResult};
use crate::geometry::{normalize_angle, Point2, Pose2};
use crate::sim::SplitMix64;
use crate::time::Stamp;

/// Runs SLAM over `truth` in `world`, the track being `odometry`, one scan per pose of
/// `beams` beams over 360° (±1 cm range noise), stamped by `stamp(i)` nanoseconds.
fn run(world: &World, truth: &[Pose2], odometry: &[Pose2], beams: usize, stamp: impl Fn(usize) -> i64) -> SlamResult {
    let mut rng = SplitMix64::new(11);
    let mut slam = Slam::new(SlamParams::default());
    for (i, (pose, odo)) in truth.iter().zip(odometry).enumerate() {
        let hits = world.noisy_scan(*pose, beams, 30.0, || rng.uniform(-0.01, 0.01));
        slam.add_scan(ScanInput {
            stamp: Stamp(stamp(i)),
            track: Some(*odo),
            origin: Point2::new(0.0, 0.0),
            hits: &hits,
            misses: &[],
        });
    }
    slam.finish()
}

/// 10 Hz stamps.
fn at_10_hz(i: usize) -> i64 {
    1_000_000_000 + i as i64 * 100_000_000
}

/// Odometry of `truth`: increments scaled by `scale` in translation and `turn_scale` in
/// rotation, turned by `bias_deg_per_m`, with a little white noise.
fn odometry(truth: &[Pose2], scale: f64, turn_scale: f64, bias_deg_per_m: f64, seed: u64) -> Vec<Pose2> {
    let mut rng = SplitMix64::new(seed);
    let mut out = vec![truth[0]];
    for w in truth.windows(2) {
        let d = w[0].inverse().compose(w[1]);
        let dist = d.x.hypot(d.y);
        let step = Pose2::new(
            d.x * scale + rng.uniform(-0.002, 0.002),
            d.y * scale + rng.uniform(-0.002, 0.002),
            d.theta * turn_scale + dist * bias_deg_per_m.to_radians() + rng.uniform(-0.001, 0.001),
        );
        out.push(out.last().unwrap().compose(step));
    }
    out
}

fn findings(r: &SlamResult) -> String {
    r.report.findings(true, SlamParams::default().loop_closure_global_after_m).join("\n")
}

/// Every scan has a finite pose, in input order with its stamp.
fn assert_every_scan_placed(r: &SlamResult, n: usize, stamp: impl Fn(usize) -> i64) {
    assert_eq!(r.trajectory.len(), n, "one pose per scan: {:?}", r.report);
    for (i, (s, p)) in r.trajectory.iter().enumerate() {
        assert_eq!(s.0, stamp(i), "scan {i}'s stamp");
        assert!(p.is_finite(), "scan {i}: {p:?}");
    }
}

/// A 200 m hallway, 4 m wide, with doorways and cabinets at irregular places: every
/// stretch looks different, and the path along it never comes back.
fn hallway() -> World {
    let mut rng = SplitMix64::new(3);
    let mut walls = vec![(Point2::new(-5.0, -2.0), Point2::new(205.0, -2.0))];
    let mut x = -5.0;
    while x < 205.0 {
        // A stretch of the upper wall, then a 1 m recess or a cabinet jutting out.
        let len = rng.uniform(1.5, 6.0);
        walls.push((Point2::new(x, 2.0), Point2::new(x + len, 2.0)));
        let depth = if rng.next_f64() < 0.5 { 1.0 } else { -0.6 };
        let w = rng.uniform(0.8, 2.0);
        let (a, b) = (x + len, x + len + w);
        walls.push((Point2::new(a, 2.0), Point2::new(a, 2.0 + depth)));
        walls.push((Point2::new(a, 2.0 + depth), Point2::new(b, 2.0 + depth)));
        walls.push((Point2::new(b, 2.0 + depth), Point2::new(b, 2.0)));
        // A pillar on the lower side now and then.
        if rng.next_f64() < 0.4 {
            let px = rng.uniform(a, b);
            walls.push((Point2::new(px, -2.0), Point2::new(px, -1.6)));
            walls.push((Point2::new(px, -1.6), Point2::new(px + 0.3, -1.6)));
            walls.push((Point2::new(px + 0.3, -1.6), Point2::new(px + 0.3, -2.0)));
        }
        x = b;
    }
    World { walls }
}

#[test]
fn a_log_that_never_revisits_a_place_closes_no_loop_and_says_so() {
    // 180 m straight along the hallway, 0.25 m a scan.
    let truth: Vec<Pose2> = (0..720).map(|i| Pose2::new(i as f64 * 0.25, 0.1, 0.0)).collect();
    let odo = odometry(&truth, 1.02, 1.0, 0.3, 1);
    let r = run(&hallway(), &truth, &odo, 360, at_10_hz);
    assert_every_scan_placed(&r, truth.len(), at_10_hz);
    let rep = &r.report;
    assert!(rep.longest_loop_m < 50.0, "only submaps seen again from nearby: {rep:?}");
    // Matching alone holds the scale and the heading far better than the odometry.
    let end = r.trajectory.last().unwrap().1;
    let (t, o) = (truth.last().unwrap(), odo.last().unwrap());
    let (e_slam, e_odo) = ((end.x - t.x).hypot(end.y - t.y), (o.x - t.x).hypot(o.y - t.y));
    assert!(e_odo > 3.0, "the odometry drifts: {e_odo} m");
    assert!(e_slam < 0.01 * e_odo, "end error {e_slam} m, odometry {e_odo} m: {rep:?}");
    let f = findings(&r);
    assert!(f.contains("no loop closed"), "{f}");
}

#[test]
fn a_robot_spinning_in_place_for_minutes_stays_in_place() {
    // Three minutes at 30°/s in the room (15 full turns), odometry reading the turn 5 %
    // high.
    let mut truth = vec![Pose2::new(6.0, 4.0, 0.3)];
    for _ in 0..1800 {
        let last = *truth.last().unwrap();
        truth.push(Pose2::new(6.0, 4.0, normalize_angle(last.theta + 3f64.to_radians())));
    }
    let odo = odometry(&truth, 1.0, 1.05, 0.0, 2);
    let r = run(&World::room(), &truth, &odo, 360, at_10_hz);
    assert_every_scan_placed(&r, truth.len(), at_10_hz);
    let rep = &r.report;
    let mut worst = (0.0f64, 0.0f64);
    for ((_, p), t) in r.trajectory.iter().zip(&truth) {
        worst.0 = worst.0.max((p.x - t.x).hypot(p.y - t.y));
        worst.1 = worst.1.max(normalize_angle(p.theta - t.theta).abs().to_degrees());
    }
    assert!(worst.0 < 0.05 && worst.1 < 1.0, "worst {:.3} m, {:.2}°: {rep:?}", worst.0, worst.1);
    // Submaps are bounded by turning too: 5,400° makes about 15, not one.
    assert!((10..=40).contains(&rep.submaps), "{rep:?}");
    assert!(rep.optimisation_failures.is_empty(), "{rep:?}");
}

#[test]
fn a_kilometre_of_featureless_corridor_keeps_the_odometry_along_it() {
    // 1 km at 0.5 m a scan between two straight walls 2 m apart: every match fits
    // anywhere along the corridor. The odometry over-reads by 1 % and turns 0.2°/m.
    let world = World {
        walls: vec![
            (Point2::new(-20.0, -1.0), Point2::new(1020.0, -1.0)),
            (Point2::new(-20.0, 1.0), Point2::new(1020.0, 1.0)),
        ],
    };
    let truth: Vec<Pose2> = (0..2000).map(|i| Pose2::new(i as f64 * 0.5, 0.2, 0.0)).collect();
    let odo = odometry(&truth, 1.01, 1.0, 0.2, 3);
    let r = run(&world, &truth, &odo, 360, at_10_hz);
    assert_every_scan_placed(&r, truth.len(), at_10_hz);
    let rep = &r.report;
    // Across the corridor and in heading the walls decide; along it only the odometry
    // can, and SLAM neither invents motion nor a loop closure.
    assert!(rep.longest_loop_m < 50.0, "{rep:?}");
    assert!(rep.degenerate as f64 > 0.5 * truth.len() as f64, "{rep:?}");
    let path_odo: f64 = odo.windows(2).map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y)).sum();
    let path_slam: f64 = r.trajectory.windows(2).map(|w| (w[1].1.x - w[0].1.x).hypot(w[1].1.y - w[0].1.y)).sum();
    assert!((path_slam - path_odo).abs() < 0.005 * path_odo, "path {path_slam} m, odometry {path_odo} m");
    // The walls hold the heading (the odometry's bias turns it by 200°), so the corridor
    // bends only as the heading's small errors add up along it.
    for ((_, p), t) in r.trajectory.iter().zip(&truth) {
        assert!(normalize_angle(p.theta - t.theta).abs() < 1f64.to_radians(), "heading: {p:?} vs {t:?}");
        assert!((p.y - t.y).abs() < 0.1 + 0.01 * t.x, "across the corridor: {p:?} vs {t:?}");
    }
    let f = findings(&r);
    assert!(f.contains("corridor"), "{f}");
}

#[test]
fn two_scans_per_stamp_keep_a_pose_each() {
    // Around the room's ring once; every stamp is given to two scans in a row.
    let mut truth = Vec::new();
    for (a, b) in [((1.0, 1.0), (11.0, 1.0)), ((11.0, 1.0), (11.0, 7.0)), ((11.0, 7.0), (1.0, 7.0))] {
        let th = f64::atan2(b.1 - a.1, b.0 - a.0);
        // Turn on the spot to the side's heading, 10° a scan, then drive it.
        while let Some(last) = truth.last().copied().filter(|p: &Pose2| normalize_angle(th - p.theta).abs() > 1e-9) {
            let step = normalize_angle(th - last.theta).clamp(-10f64.to_radians(), 10f64.to_radians());
            truth.push(Pose2::new(last.x, last.y, normalize_angle(last.theta + step)));
        }
        for i in 0..100 {
            let f = i as f64 / 100.0;
            truth.push(Pose2::new(a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1), th));
        }
    }
    let odo = odometry(&truth, 1.02, 1.0, 0.5, 4);
    let paired = |i: usize| 1_000_000_000 + (i / 2) as i64 * 100_000_000;
    let r = run(&World::room(), &truth, &odo, 360, paired);
    assert_every_scan_placed(&r, truth.len(), paired);
    let mean = r.trajectory.iter().zip(&truth).map(|((_, p), t)| (p.x - t.x).hypot(p.y - t.y)).sum::<f64>()
        / truth.len() as f64;
    assert!(mean < 0.05, "mean error {mean} m: {:?}", r.report);
}

/// A 2 × 1.5 m closet with a box in one corner: small submaps, every pose unique.
fn closet() -> World {
    let c = |x: f64, y: f64| Point2::new(x + 0.0131, y + 0.0277);
    let ring = |pts: &[Point2]| (0..pts.len()).map(|i| (pts[i], pts[(i + 1) % pts.len()])).collect::<Vec<_>>();
    let mut walls = ring(&[c(0.0, 0.0), c(2.0, 0.0), c(2.0, 1.5), c(0.0, 1.5)]);
    walls.extend(ring(&[c(1.6, 1.1), c(1.8, 1.1), c(1.8, 1.3), c(1.6, 1.3)]));
    World { walls }
}

/// SLAM after driving circles in the closet until a submap is finished, then given
/// `copies` more finished submaps just like it (the robot stayed there for days), and the
/// circle's next pose index. Batches run at every node, optimisations never (the copies
/// are tied to nothing), so each batch's searches can be counted.
fn closet_with_copies(p: SlamParams, copies: usize) -> (Slam, usize) {
    let p = SlamParams { loop_closure_batch_nodes: 1, optimize_every_n_nodes: usize::MAX, ..p };
    let mut slam = Slam::new(p);
    let mut i = 0;
    while !slam.finished.iter().any(|&f| f) {
        assert!(i < 2000, "no submap finished: {:?}", slam.report());
        add_circle_scan(&mut slam, i);
        i += 1;
    }
    let of = slam.finished.iter().position(|&f| f).expect("one finished");
    slam.copy_finished_submap(of, copies);
    (slam, i)
}

/// Scan `i` of circles of 0.3 m radius about the closet's middle, 5° a scan, 10 Hz.
fn add_circle_scan(slam: &mut Slam, i: usize) {
    let a = (5.0 * i as f64).to_radians();
    let pose = Pose2::new(1.0 + 0.3 * a.cos(), 0.75 + 0.3 * a.sin(), normalize_angle(a + std::f64::consts::FRAC_PI_2));
    let hits = closet().scan(pose, 180, 30.0);
    slam.add_scan(ScanInput {
        stamp: Stamp(at_10_hz(i)),
        track: Some(pose),
        origin: Point2::new(0.0, 0.0),
        hits: &hits,
        misses: &[],
    });
}

#[test]
fn a_closure_search_over_100000_submaps_keeps_to_its_bounds() {
    const COPIES: usize = 100_000;
    // Defaults: a node is searched against its few nearest submaps, and a submap just
    // finished by a few earlier nodes, however many submaps lie near.
    let d = SlamParams::default();
    let (mut slam, mut i) = closet_with_copies(d, COPIES);
    let per_batch = (d.loop_closure_submaps_per_node
        + d.loop_closure_nodes_per_submap
        + d.loop_closure_global_submaps_per_batch
        + 16) as u64;
    let start = slam.report().loop_searches;
    for _ in 0..80 {
        let before = slam.report().loop_searches;
        add_circle_scan(&mut slam, i);
        i += 1;
        let ran = slam.report().loop_searches - before;
        assert!(ran <= per_batch, "{ran} searches in one batch: {:?}", slam.report());
    }
    let ran = slam.report().loop_searches - start;
    assert!(ran > 0, "some node was searched: {:?}", slam.report());
    assert!(slam.grids.built <= ran + 1, "grids built only for the submaps searched: {} for {ran}", slam.grids.built);

    drop(slam);

    // Told to search every submap near a node, the batch stops at its work budget, counts
    // what it left out, and says so.
    let p = SlamParams { loop_closure_submaps_per_node: usize::MAX, loop_closure_work_per_batch: 1e7, ..d };
    let (mut slam, mut i) = closet_with_copies(p, COPIES);
    while slam.report().loop_over_budget == 0 {
        assert!(i < 4000, "no batch reached the budget: {:?}", slam.report());
        let before = slam.report().loop_searches;
        add_circle_scan(&mut slam, i);
        i += 1;
        let ran = slam.report().loop_searches - before;
        // Even in the base window (4 m, ±20°, about 120 points) a search costs over 10⁵
        // lookups, a hundredth of the budget.
        assert!(ran <= 100, "{ran} searches in one batch: {:?}", slam.report());
    }
    let rep = slam.report();
    assert!(rep.loop_over_budget as usize > COPIES - 100, "{rep:?}");
    assert!(slam.grids.built <= rep.loop_searches + 1, "{} grids for {} searches", slam.grids.built, rep.loop_searches);
    let f = rep.findings(true, p.loop_closure_global_after_m).join("\n");
    assert!(f.contains("work budget"), "{f}");
}
