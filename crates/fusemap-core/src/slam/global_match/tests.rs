use super::*;
use crate::sim::{Segment, SplitMix64, World};
use crate::slam::grid::UpdateTable;
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

const R: f64 = 0.05;

/// A 10 × 8 m room with a pillar, a wall stub and a cut corner: no symmetry maps it onto
/// itself, so a scan of it has one best pose.
fn room() -> World {
    World {
        segments: vec![
            Segment::new(0.0, 0.0, 10.0, 0.0),
            Segment::new(10.0, 0.0, 10.0, 6.5),
            Segment::new(10.0, 6.5, 8.5, 8.0),
            Segment::new(8.5, 8.0, 0.0, 8.0),
            Segment::new(0.0, 8.0, 0.0, 0.0),
            // pillar
            Segment::new(2.5, 5.0, 3.5, 5.0),
            Segment::new(3.5, 5.0, 3.5, 6.0),
            Segment::new(3.5, 6.0, 2.5, 6.0),
            Segment::new(2.5, 6.0, 2.5, 5.0),
            // wall stub from the south wall
            Segment::new(7.0, 0.0, 7.0, 2.5),
        ],
    }
}

/// A long corridor, 2 m wide, unlike the room.
fn corridor_world() -> World {
    World { segments: vec![Segment::new(-30.0, -1.0, 30.0, -1.0), Segment::new(-30.0, 1.0, 30.0, 1.0)] }
}

/// A full-circle scan of `beams` returns from `pose`, in the scan's own frame.
fn scan(world: &World, pose: Pose2, beams: usize, range_max: f64) -> Vec<Point2> {
    (0..beams)
        .filter_map(|i| {
            let a = -PI + TAU * i as f64 / beams as f64;
            let d = world.cast(pose.translation(), pose.theta + a)?;
            (d < range_max).then(|| Point2::new(d * a.cos(), d * a.sin()))
        })
        .collect()
}

/// A submap of `world` built from scans at `origins`, each inserted `reps` times.
fn map_of(world: &World, origins: &[Point2], reps: usize) -> ProbabilityGrid {
    let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
    let mut g = ProbabilityGrid::new(R);
    for _ in 0..reps {
        for &o in origins {
            let pose = Pose2::new(o.x, o.y, 0.0);
            let hits: Vec<Point2> = scan(world, pose, 720, 30.0).into_iter().map(|p| pose.transform_point(p)).collect();
            g.insert(o, &hits, &[], &hit, &miss);
        }
    }
    g
}

fn room_map() -> ProbabilityGrid {
    let origins = [Point2::new(2.0, 2.0), Point2::new(5.0, 4.0), Point2::new(8.0, 5.0), Point2::new(5.0, 7.0)];
    map_of(&room(), &origins, 14)
}

fn step_for(points: &[Point2]) -> f64 {
    angular_step(R, points.iter().map(|p| p.x.hypot(p.y)).fold(0.0, f64::max))
}

#[test]
fn the_angular_step_moves_the_farthest_point_by_one_cell() {
    for d in [0.5, 3.0, 30.0] {
        let s = angular_step(0.05, d);
        assert!((2.0 * d * (s / 2.0).sin() - 0.05).abs() < 1e-9, "d={d} step={s}");
    }
    assert!(angular_step(0.05, 0.0).is_finite());
}

#[test]
fn recovers_a_pose_far_from_the_guess() {
    let g = room_map();
    let grids = PrecomputedGrids::new(&g, 7);
    let truth = Pose2::new(4.2, 3.1, 0.4);
    let points = scan(&room(), truth, 180, 30.0);
    let initial = Pose2::new(truth.x - 2.3, truth.y + 1.7, truth.theta - 17f64.to_radians());
    let m = match_branch_and_bound(&grids, &points, initial, &GlobalSearch::default()).expect("a match");
    let step = step_for(&points);
    assert!((m.pose.x - truth.x).abs() <= R + 1e-9, "{m:?}");
    assert!((m.pose.y - truth.y).abs() <= R + 1e-9, "{m:?}");
    assert!(normalize_angle(m.pose.theta - truth.theta).abs() <= step + 1e-12, "{m:?}, step {step}");
    let exact = score_at(&g, &points, m.pose);
    assert!(m.score >= 0.55 && (m.score - exact).abs() < 0.01, "{m:?} exact {exact}");
    // The guess itself scores far lower: the search did the work.
    assert!(score_at(&g, &points, initial) < 0.3);
}

#[test]
fn recovers_a_pose_across_the_angle_wrap() {
    let g = room_map();
    let grids = PrecomputedGrids::new(&g, 7);
    for truth in [Pose2::new(5.5, 3.5, 3.05), Pose2::new(5.5, 3.5, -3.1)] {
        let points = scan(&room(), truth, 180, 30.0);
        // The guess sits on the other side of ±π.
        let initial =
            Pose2::new(truth.x + 1.1, truth.y - 0.6, normalize_angle(truth.theta + 0.25 * truth.theta.signum()));
        assert!(initial.theta.signum() != truth.theta.signum());
        let m = match_branch_and_bound(&grids, &points, initial, &GlobalSearch::default()).expect("a match");
        assert!((m.pose.x - truth.x).abs() <= R + 1e-9 && (m.pose.y - truth.y).abs() <= R + 1e-9, "{m:?}");
        assert!(normalize_angle(m.pose.theta - truth.theta).abs() <= step_for(&points) + 1e-12, "{m:?}");
        assert!(m.pose.theta > -PI && m.pose.theta <= PI);
    }
}

#[test]
fn a_scan_of_another_place_finds_no_match() {
    let g = room_map();
    let grids = PrecomputedGrids::new(&g, 7);
    let initial = Pose2::new(5.0, 4.0, 0.0);
    let search = GlobalSearch::default();
    let corridor = scan(&corridor_world(), Pose2::new(0.0, 0.0, 0.3), 180, 30.0);
    assert_eq!(match_branch_and_bound(&grids, &corridor, initial, &search), None);
    let mut rng = SplitMix64::new(7);
    let random: Vec<Point2> = (0..180).map(|_| Point2::new(rng.uniform(-6.0, 6.0), rng.uniform(-6.0, 6.0))).collect();
    assert_eq!(match_branch_and_bound(&grids, &random, initial, &search), None);
    // The same searches with no threshold do find a best pose, and it is below 0.55.
    let lenient = GlobalSearch { min_score: 0.0, ..search };
    for pts in [&corridor, &random] {
        let m = match_branch_and_bound(&grids, pts, initial, &lenient).expect("some pose");
        assert!(m.score < 0.55 && m.score >= P_MIN, "{m:?}");
    }
}

#[test]
fn no_points_no_match() {
    let grids = PrecomputedGrids::new(&room_map(), 7);
    let search = GlobalSearch { min_score: 0.0, ..GlobalSearch::default() };
    assert_eq!(match_branch_and_bound(&grids, &[], Pose2::IDENTITY, &search), None);
    let nan = [Point2::new(f64::NAN, 1.0), Point2::new(1.0, f64::INFINITY)];
    assert_eq!(match_branch_and_bound(&grids, &nan, Pose2::IDENTITY, &search), None);
    assert_eq!(score_at(&room_map(), &[], Pose2::IDENTITY), P_MIN);
}

#[test]
fn a_threshold_above_p_max_finds_nothing() {
    let g = room_map();
    let grids = PrecomputedGrids::new(&g, 7);
    let truth = Pose2::new(4.2, 3.1, 0.4);
    let points = scan(&room(), truth, 90, 30.0);
    let search = GlobalSearch { min_score: 0.95, ..GlobalSearch::default() };
    assert_eq!(match_branch_and_bound(&grids, &points, truth, &search), None);
}

/// The exhaustive search over the same discretised window: every angle, every offset,
/// scored on level 0.
fn brute_force(grids: &PrecomputedGrids, problem: &Problem) -> Option<Candidate> {
    let w = problem.window;
    let mut best: Option<Candidate> = None;
    for (scan, s) in problem.scans.iter().enumerate() {
        for dx in -w..=w {
            for dy in -w..=w {
                let bound = grids.level(0).sum(&s.cells, dx, dy, -1);
                if best.is_none_or(|b| bound > b.bound) {
                    best = Some(Candidate { scan: scan as u32, dx, dy, bound });
                }
            }
        }
    }
    best
}

fn random_grid(seed: u64, n: usize) -> ProbabilityGrid {
    let mut rng = SplitMix64::new(seed);
    let (hit, miss) = (UpdateTable::new(0.7), UpdateTable::new(0.4));
    let mut g = ProbabilityGrid::new(0.1);
    for _ in 0..n {
        let o = Point2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
        let hits: Vec<_> = (0..6).map(|_| Point2::new(rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5))).collect();
        g.insert(o, &hits, &[], &hit, &miss);
    }
    g
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The bound is admissible: branch and bound finds exactly the exhaustive optimum
    /// (same score), at a pose inside the window whose level-0 score is that optimum.
    #[test]
    fn branch_and_bound_equals_exhaustive_search(
        seed in any::<u64>(),
        inserts in 1usize..30,
        n_points in 1usize..25,
        depth in 1usize..6,
        window_m in 0.0f64..0.9,
        angular in 0.0f64..0.6,
        min_score in 0.1f32..0.6,
        init in (-1.5f64..1.5, -1.5f64..1.5, -PI..PI),
    ) {
        let g = random_grid(seed, inserts);
        let grids = PrecomputedGrids::new(&g, depth);
        let mut rng = SplitMix64::new(seed ^ 0x9e37);
        let points: Vec<Point2> =
            (0..n_points).map(|_| Point2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0))).collect();
        let initial = Pose2::new(init.0, init.1, init.2);
        let search = GlobalSearch { linear_window_m: window_m, angular_window_rad: angular, min_score, depth };
        let problem = Problem::new(&grids, &points, initial, &search, depth);
        let need = problem.threshold(min_score).expect("reachable threshold");
        let exhaustive = brute_force(&grids, &problem).expect("a non-empty window");
        let (found, root) = branch_and_bound(&grids, &problem, depth, need);
        // The best root bounds every leaf of the window from above.
        prop_assert!(root.expect("a non-empty window").bound >= exhaustive.bound);
        let outcome = search_branch_and_bound(&grids, &points, initial, &search);
        prop_assert!(outcome.best_score >= problem.score(u64::from(exhaustive.bound)));
        if exhaustive.bound >= need {
            let found = found.expect("branch and bound misses a pose the exhaustive search accepts");
            prop_assert_eq!(found.bound, exhaustive.bound);
            let w = problem.window;
            prop_assert!(found.dx.abs() <= w && found.dy.abs() <= w);
            prop_assert_eq!(grids.level(0).sum(&problem.scans[found.scan as usize].cells, found.dx, found.dy, -1), found.bound);
            let m = match_branch_and_bound(&grids, &points, initial, &search).expect("the same match");
            prop_assert!(m.score >= min_score);
            prop_assert_eq!(m.score, problem.score(u64::from(exhaustive.bound)));
        } else {
            prop_assert_eq!(found, None);
            prop_assert_eq!(match_branch_and_bound(&grids, &points, initial, &search), None);
            prop_assert!(outcome.found.is_none());
        }
    }

    /// The byte score of a leaf never falls below the exact score, and exceeds it by at
    /// most one byte step (up to points on a cell boundary).
    #[test]
    fn byte_scores_bound_the_exact_score(seed in any::<u64>(), inserts in 1usize..30, theta in -PI..PI) {
        let g = random_grid(seed, inserts);
        let grids = PrecomputedGrids::new(&g, 1);
        let mut rng = SplitMix64::new(seed.wrapping_add(1));
        let points: Vec<Point2> =
            (0..20).map(|_| Point2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0))).collect();
        let pose = Pose2::new(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), theta);
        let search = GlobalSearch { linear_window_m: 0.0, angular_window_rad: 0.0, min_score: 0.0, depth: 1 };
        let m = match_branch_and_bound(&grids, &points, pose, &search).expect("threshold zero");
        prop_assert_eq!(m.pose, pose.normalized());
        let exact = score_at(&g, &points, pose);
        prop_assert!(m.score >= exact - 1e-5 && m.score <= exact + (P_MAX - P_MIN) / 255.0 + 1e-5, "{} vs {}", m.score, exact);
    }
}

/// A measurement, not a test: one match of a 180-point scan against a ≈400 × 400 grid with
/// the default window. Run with
/// `cargo test -p fusemap-core --release --lib slam::global_match::tests::timing -- --ignored --nocapture`.
#[test]
#[ignore]
fn timing_of_one_match_against_a_400_cell_submap() {
    use std::time::Instant;
    let s = 13.6;
    let world = World {
        segments: vec![
            Segment::new(0.0, 0.0, s, 0.0),
            Segment::new(s, 0.0, s, s),
            Segment::new(s, s, 0.0, s),
            Segment::new(0.0, s, 0.0, 0.0),
            Segment::new(3.0, 8.0, 5.0, 8.0),
            Segment::new(5.0, 8.0, 5.0, 9.5),
            Segment::new(9.0, 0.0, 9.0, 4.0),
            Segment::new(10.0, 10.0, 12.0, 12.0),
        ],
    };
    let origins: Vec<Point2> = [(2.0, 2.0), (6.8, 6.8), (11.0, 3.0), (3.0, 11.5), (11.5, 8.0)]
        .iter()
        .map(|&(x, y)| Point2::new(x, y))
        .collect();
    let g = map_of(&world, &origins, 12);
    let l = g.limits();
    let t = Instant::now();
    let grids = PrecomputedGrids::new(&g, 7);
    let pre = t.elapsed();
    println!("grid {}x{} cells; precompute depth 7: {:?}, {} bytes", l.width, l.height, pre, grids.memory_bytes());
    let search = GlobalSearch::default();
    let truth = Pose2::new(6.0, 5.0, 1.0);
    let points = scan(&world, truth, 180, 30.0);
    let initial = Pose2::new(truth.x - 2.3, truth.y + 1.7, truth.theta - 17f64.to_radians());
    let other = scan(&corridor_world(), Pose2::new(0.0, 0.0, 0.3), 180, 30.0);
    for (name, pts) in [("matching scan", &points), ("corridor scan (no match)", &other)] {
        let mut times = Vec::new();
        let mut result = None;
        for _ in 0..7 {
            let t = Instant::now();
            result = match_branch_and_bound(&grids, pts, initial, &search);
            times.push(t.elapsed());
        }
        times.sort();
        println!("{name}: {} points, median {:?} (min {:?}), result {result:?}", pts.len(), times[3], times[0]);
    }
}
