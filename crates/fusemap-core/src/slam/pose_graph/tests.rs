use super::*;
use proptest::prelude::*;
use std::f64::consts::PI;

/// A small deterministic generator (SplitMix64) so noisy scenarios are reproducible.
pub(super) struct Rng(u64);

impl Rng {
    pub(super) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal sample (Box–Muller).
    pub(super) fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-300);
        let v = self.uniform();
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
}

pub(super) const EYE: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Information for σ = `sigma_xy` metres and `sigma_theta` radians.
pub(super) fn info(sigma_xy: f64, sigma_theta: f64) -> [[f64; 3]; 3] {
    let a = 1.0 / (sigma_xy * sigma_xy);
    let b = 1.0 / (sigma_theta * sigma_theta);
    [[a, 0.0, 0.0], [0.0, a, 0.0], [0.0, 0.0, b]]
}

pub(super) fn edge(from: usize, to: usize, measurement: Pose2, information: [[f64; 3]; 3], loss: Loss) -> Edge {
    Edge { from, to, measurement, information, loss, kind: EdgeKind::Match }
}

/// The exact measurement between two true poses.
fn between(a: Pose2, b: Pose2) -> Pose2 {
    a.inverse().compose(b)
}

fn max_pose_error(a: &[Pose2], b: &[Pose2]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.translation().distance(q.translation()).max(normalize_angle(p.theta - q.theta).abs()))
        .fold(0.0, f64::max)
}

/// Poses on a circle of radius `r`, heading along the tangent.
fn ring(n: usize, r: f64) -> Vec<Pose2> {
    (0..n)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / n as f64;
            Pose2::new(r * a.cos(), r * a.sin(), normalize_angle(a + PI / 2.0))
        })
        .collect()
}

/// A graph whose every measurement is exact, with chords between `i` and `i + 3`.
fn consistent_graph(truth: &[Pose2], init: &[Pose2]) -> PoseGraph {
    let mut g = PoseGraph::new();
    for p in init {
        g.add_node(*p);
    }
    for i in 0..truth.len() {
        for k in [1, 3] {
            if i + k < truth.len() {
                g.add_edge(edge(i, i + k, between(truth[i], truth[i + k]), info(0.1, 0.05), Loss::Trivial)).unwrap();
            }
        }
    }
    g
}

#[test]
fn consistent_graph_started_at_truth_stays_put() {
    let truth = ring(30, 5.0);
    let mut g = consistent_graph(&truth, &truth);
    let report = g.optimize(&OptimizeOptions::default()).unwrap();
    assert!(report.converged);
    assert!(report.initial_cost < 1e-20, "{report:?}");
    assert!(max_pose_error(g.nodes(), &truth) < 1e-12);
}

#[test]
fn consistent_graph_converges_to_truth_from_perturbed_start() {
    let truth = ring(40, 6.0);
    let mut rng = Rng(7);
    let mut init = truth.clone();
    for p in init.iter_mut().skip(1) {
        *p = Pose2::new(p.x + 0.3 * rng.normal(), p.y + 0.3 * rng.normal(), p.theta + 0.1 * rng.normal());
    }
    let mut g = consistent_graph(&truth, &init);
    let before = max_pose_error(g.nodes(), &truth);
    let report = g.optimize(&OptimizeOptions::default()).unwrap();
    assert!(report.converged, "{report:?}");
    assert!(report.final_cost < 1e-12 * report.initial_cost, "{report:?}");
    assert!(before > 0.1);
    assert!(max_pose_error(g.nodes(), &truth) < 1e-6, "{:?}", max_pose_error(g.nodes(), &truth));
}

/// Odometry with noise along a ring; returns the graph (odometry edges only, nodes at the
/// integrated odometry) and the truth.
fn noisy_ring(n: usize, seed: u64, loss: Loss) -> (PoseGraph, Vec<Pose2>) {
    let truth = ring(n, 10.0);
    let mut rng = Rng(seed);
    let mut g = PoseGraph::new();
    g.add_node(truth[0]);
    for i in 1..n {
        let z = between(truth[i - 1], truth[i]);
        let noisy = Pose2::new(z.x + 0.05 * rng.normal(), z.y + 0.05 * rng.normal(), z.theta + 0.02 * rng.normal());
        let prev = g.nodes()[i - 1];
        g.add_node(prev.compose(noisy));
        let e = Edge { kind: EdgeKind::Odometry, ..edge(i - 1, i, noisy, info(0.05, 0.02), loss) };
        g.add_edge(e).unwrap();
    }
    (g, truth)
}

#[test]
fn one_loop_closure_shrinks_the_drift_at_the_end_of_a_ring() {
    let n = 60;
    let (mut g, truth) = noisy_ring(n, 11, Loss::Trivial);
    let drift_before = g.nodes()[n - 1].translation().distance(truth[n - 1].translation());
    let closure = Edge {
        kind: EdgeKind::LoopClosure,
        ..edge(n - 1, 0, between(truth[n - 1], truth[0]), info(0.01, 0.005), Loss::Trivial)
    };
    g.add_edge(closure).unwrap();
    let report = g.optimize(&OptimizeOptions::default()).unwrap();
    assert!(report.converged, "{report:?}");
    let drift_after = g.nodes()[n - 1].translation().distance(truth[n - 1].translation());
    assert!(drift_before > 0.3, "scenario too easy: {drift_before}");
    assert!(drift_after < 0.2 * drift_before, "{drift_before} → {drift_after}");
}

/// A ring with noisy odometry, good loop closures between every 10th node and the node
/// half a turn later, and one wrong closure claiming two far-apart nodes coincide.
fn ring_with_wrong_closure(loss: Loss) -> (PoseGraph, Vec<Pose2>, usize) {
    let n = 80;
    // Odometry stays least squares (its errors are small and honest); the closures, which
    // come from a place-recognition search that can be fooled, get the robust loss.
    let (mut g, truth) = noisy_ring(n, 23, Loss::Trivial);
    let mut rng = Rng(99);
    for i in (0..n / 2).step_by(5) {
        let j = i + n / 2;
        let z = between(truth[i], truth[j]);
        let z = Pose2::new(z.x + 0.02 * rng.normal(), z.y + 0.02 * rng.normal(), z.theta + 0.01 * rng.normal());
        g.add_edge(Edge { kind: EdgeKind::LoopClosure, ..edge(i, j, z, info(0.02, 0.01), loss) }).unwrap();
    }
    let wrong = g
        .add_edge(Edge {
            kind: EdgeKind::LoopClosure,
            ..edge(15, 35, Pose2::new(0.5, 0.0, 0.0), info(0.02, 0.01), loss)
        })
        .unwrap();
    (g, truth, wrong)
}

fn mean_translation_error(a: &[Pose2], b: &[Pose2]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.translation().distance(q.translation())).sum::<f64>() / a.len() as f64
}

#[test]
fn robust_losses_down_weight_a_wrong_loop_closure() {
    let opts = OptimizeOptions { max_iterations: 200, ..OptimizeOptions::default() };
    let mut errors = Vec::new();
    for loss in [Loss::Trivial, Loss::Huber(1.0), Loss::Cauchy(1.0), Loss::Dcs(1.0)] {
        let dcs = matches!(loss, Loss::Dcs(_));
        // DCS is not convex: from a poor start it settles where it starts. Huber first
        // brings the right closures in, then DCS lets the wrong one go.
        let (mut g, truth, wrong) = ring_with_wrong_closure(if dcs { Loss::Huber(1.0) } else { loss });
        assert!(g.optimize(&opts).unwrap().converged);
        if dcs {
            g.set_loss_of(EdgeKind::LoopClosure, loss).unwrap();
            assert!(g.optimize(&opts).unwrap().converged);
        }
        let err = mean_translation_error(g.nodes(), &truth);
        let wrong_residual = g.edge_error(wrong);
        errors.push((err, wrong_residual[0].hypot(wrong_residual[1])));
    }
    let (trivial, huber, cauchy, dcs) = (errors[0], errors[1], errors[2], errors[3]);
    assert!(dcs.0 < 0.7 * huber.0 && dcs.0 <= 1.05 * cauchy.0 && dcs.1 > 10.0, "{errors:?}");
    // Least squares spreads the 14 m lie over the ring; robust losses leave it unexplained.
    assert!(trivial.0 > 1.0, "{errors:?}");
    assert!(huber.0 < 0.2 * trivial.0, "{errors:?}");
    assert!(cauchy.0 < 0.1 * trivial.0, "{errors:?}");
    assert!(trivial.1 < 1.0 && huber.1 > 10.0 && cauchy.1 > 10.0, "{errors:?}");
}

#[test]
fn position_priors_carry_the_graph_into_their_frame_with_the_lever_arm() {
    // Truth in a world frame rotated and shifted away from the odometry frame.
    let world_from_odom = Pose2::new(100.0, -40.0, 2.0);
    let local = ring(24, 4.0);
    let truth: Vec<Pose2> = local.iter().map(|p| world_from_odom.compose(*p)).collect();
    let mut g = consistent_graph(&truth, &local);
    let lever_arm = Point2::new(0.4, -0.25);
    for k in [0, 8, 16] {
        let position = truth[k].transform_point(lever_arm);
        let p = PositionPrior {
            node: k,
            position,
            lever_arm,
            information: [[100.0, 0.0], [0.0, 100.0]],
            loss: Loss::Trivial,
        };
        g.add_position_prior(p).unwrap();
    }
    let opts = OptimizeOptions { max_iterations: 100, ..OptimizeOptions::default() };
    let report = g.optimize(&opts).unwrap();
    assert!(report.converged, "{report:?}");
    assert!(max_pose_error(g.nodes(), &truth) < 1e-6, "{}", max_pose_error(g.nodes(), &truth));
    // Node 0 is not held when priors fix the gauge.
    assert!(g.nodes()[0].translation().distance(local[0].translation()) > 50.0);
}

#[test]
fn fixed_nodes_do_not_move() {
    let truth = ring(20, 3.0);
    let mut init = truth.clone();
    init[5].x += 0.5;
    init[12].theta += 0.3;
    let mut g = consistent_graph(&truth, &init);
    g.set_fixed(12, true);
    assert!(g.is_fixed(12));
    g.optimize(&OptimizeOptions::default()).unwrap();
    assert_eq!(g.nodes()[12], init[12]);
    // Node 0 is free now that node 12 holds the gauge.
    assert_ne!(g.nodes()[0], init[0]);
}

#[test]
fn a_node_without_constraints_is_left_alone() {
    let truth = ring(12, 2.0);
    let mut init = truth.clone();
    init[4].y += 0.4;
    let mut g = consistent_graph(&truth, &init);
    let lonely = g.add_node(Pose2::new(7.0, -3.0, 1.0));
    // Many iterations drive the damping to its floor, where the lonely node's block is tiny.
    let opts = OptimizeOptions {
        max_iterations: 100,
        function_tolerance: 0.0,
        parameter_tolerance: 0.0,
        ..Default::default()
    };
    g.optimize(&opts).unwrap();
    assert_eq!(g.nodes()[lonely], Pose2::new(7.0, -3.0, 1.0));
    assert!(max_pose_error(&g.nodes()[..12], &truth) < 1e-6);
}

#[test]
fn angles_wrap_across_plus_minus_pi() {
    let truth =
        vec![Pose2::new(0.0, 0.0, PI - 0.01), Pose2::new(-1.0, 0.0, -PI + 0.01), Pose2::new(-2.0, 0.02, PI - 0.02)];
    let mut g = PoseGraph::new();
    g.add_node(truth[0]);
    g.add_node(Pose2::new(-0.9, 0.1, PI - 0.05));
    g.add_node(Pose2::new(-2.1, -0.1, -PI + 0.04));
    for (a, b) in [(0, 1), (1, 2), (0, 2)] {
        let z = between(truth[a], truth[b]);
        assert!(z.theta.abs() < 0.1);
        g.add_edge(edge(a, b, z, EYE, Loss::Trivial)).unwrap();
    }
    // The residual of an edge straddling ±π is small, not ±2π.
    assert!(g.edge_error(1)[2].abs() < 0.2, "{:?}", g.edge_error(1));
    let report = g.optimize(&OptimizeOptions::default()).unwrap();
    assert!(report.converged && report.final_cost < 1e-16, "{report:?}");
    assert!(max_pose_error(g.nodes(), &truth) < 1e-7);
    assert!(g.nodes().iter().all(|p| p.theta.abs() <= PI));
}

#[test]
fn bad_inputs_are_rejected() {
    let mut g = PoseGraph::new();
    g.add_node(Pose2::IDENTITY);
    g.add_node(Pose2::new(1.0, 0.0, 0.0));
    let good = edge(0, 1, Pose2::new(1.0, 0.0, 0.0), EYE, Loss::Trivial);
    assert_eq!(g.add_edge(Edge { to: 2, ..good }), Err(PoseGraphError::UnknownNode { node: 2, len: 2 }));
    assert_eq!(g.add_edge(Edge { to: 0, ..good }), Err(PoseGraphError::SelfEdge(0)));
    assert!(matches!(
        g.add_edge(Edge { measurement: Pose2::new(f64::NAN, 0.0, 0.0), ..good }),
        Err(PoseGraphError::NonFinite(_))
    ));
    let mut nan_info = EYE;
    nan_info[1][1] = f64::INFINITY;
    assert!(matches!(g.add_edge(Edge { information: nan_info, ..good }), Err(PoseGraphError::NonFinite(_))));
    let asymmetric = [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert_eq!(g.add_edge(Edge { information: asymmetric, ..good }), Err(PoseGraphError::BadInformation));
    let indefinite = [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert_eq!(g.add_edge(Edge { information: indefinite, ..good }), Err(PoseGraphError::BadInformation));
    let negative = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1e-3]];
    assert_eq!(g.add_edge(Edge { information: negative, ..good }), Err(PoseGraphError::BadInformation));
    assert_eq!(g.add_edge(Edge { loss: Loss::Huber(0.0), ..good }), Err(PoseGraphError::BadLoss));
    assert_eq!(g.add_edge(Edge { loss: Loss::Cauchy(f64::NAN), ..good }), Err(PoseGraphError::BadLoss));
    let prior = PositionPrior {
        node: 3,
        position: Point2::new(0.0, 0.0),
        lever_arm: Point2::default(),
        information: [[1.0, 0.0], [0.0, 1.0]],
        loss: Loss::Trivial,
    };
    assert!(matches!(g.add_position_prior(prior), Err(PoseGraphError::UnknownNode { node: 3, .. })));
    let nan_prior = PositionPrior { node: 0, position: Point2::new(f64::NAN, 0.0), ..prior };
    assert!(matches!(g.add_position_prior(nan_prior), Err(PoseGraphError::NonFinite(_))));
    assert!(g.edges().is_empty() && g.position_priors().is_empty());

    // A semi-definite information (no heading constraint) is accepted.
    g.add_edge(Edge { information: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]], ..good }).unwrap();
    g.set_node(1, Pose2::new(f64::NAN, 0.0, 0.0));
    assert_eq!(g.optimize(&OptimizeOptions::default()), Err(PoseGraphError::NonFinitePose(1)));
    assert!(g.nodes()[1].x.is_nan());
}

#[test]
fn symbolic_factorisation_is_reused_until_the_structure_changes() {
    let truth = ring(20, 3.0);
    let mut g = consistent_graph(&truth, &truth);
    let opts = OptimizeOptions::default();
    assert!(!g.optimize(&opts).unwrap().reused_symbolic);
    g.set_node(4, Pose2::new(truth[4].x + 0.2, truth[4].y, truth[4].theta));
    let warm = g.optimize(&opts).unwrap();
    assert!(warm.reused_symbolic);
    assert!(max_pose_error(g.nodes(), &truth) < 1e-6);
    g.add_edge(edge(2, 9, between(truth[2], truth[9]), EYE, Loss::Trivial)).unwrap();
    assert!(!g.optimize(&opts).unwrap().reused_symbolic);
    g.set_fixed(3, true);
    assert!(!g.optimize(&opts).unwrap().reused_symbolic);
}

#[test]
fn gradient_matches_finite_differences_of_the_cost() {
    let truth = ring(8, 2.0);
    let mut rng = Rng(5);
    let init: Vec<Pose2> = truth
        .iter()
        .map(|p| Pose2::new(p.x + 0.2 * rng.normal(), p.y + 0.2 * rng.normal(), p.theta + 0.2 * rng.normal()))
        .collect();
    let mut g = PoseGraph::new();
    for p in &init {
        g.add_node(*p);
    }
    let full = [[2.0, 0.3, 0.1], [0.3, 1.5, -0.2], [0.1, -0.2, 4.0]];
    for (i, loss) in [Loss::Trivial, Loss::Huber(0.3), Loss::Cauchy(0.5)].into_iter().enumerate() {
        for a in 0..8 {
            g.add_edge(edge(a, (a + 1 + i) % 8, between(truth[a], truth[(a + 1 + i) % 8]), full, loss)).unwrap();
        }
    }
    let lever_arm = Point2::new(0.3, -0.1);
    let info2 = [[3.0, 0.5], [0.5, 2.0]];
    let prior = PositionPrior {
        node: 3,
        position: Point2::new(1.0, 2.0),
        lever_arm,
        information: info2,
        loss: Loss::Huber(0.5),
    };
    g.add_position_prior(prior).unwrap();
    let gradient = solver::gradient(&g);
    let h = 1e-6;
    for (i, p) in init.iter().enumerate() {
        for c in 0..3 {
            let shift = |d: f64| {
                let mut q = *p;
                match c {
                    0 => q.x += d,
                    1 => q.y += d,
                    _ => q.theta += d,
                }
                let mut nodes = init.clone();
                nodes[i] = q;
                solver::total_cost(&g, &nodes)
            };
            let numeric = (shift(h) - shift(-h)) / (2.0 * h);
            let analytic = gradient[3 * i + c];
            assert!(
                (numeric - analytic).abs() < 1e-5 * (1.0 + numeric.abs()),
                "node {i} comp {c}: {numeric} vs {analytic}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Measurements taken from any true poses are all satisfied at the optimum.
    #[test]
    fn random_consistent_graphs_reach_zero_cost(
        truth in prop::collection::vec((-20.0..20.0f64, -20.0..20.0f64, -PI..PI), 2..25),
        extra in prop::collection::vec((0usize..1000, 0usize..1000), 0..30),
        seed in any::<u64>(),
    ) {
        let truth: Vec<Pose2> = truth.into_iter().map(|(x, y, t)| Pose2::new(x, y, t)).collect();
        let n = truth.len();
        let mut rng = Rng(seed);
        let mut g = PoseGraph::new();
        for (i, p) in truth.iter().enumerate() {
            let noise = if i == 0 { 0.0 } else { 1.0 };
            g.add_node(Pose2::new(p.x + 0.2 * noise * rng.normal(), p.y + 0.2 * noise * rng.normal(), p.theta + 0.1 * noise * rng.normal()));
        }
        for i in 1..n {
            g.add_edge(edge(i - 1, i, between(truth[i - 1], truth[i]), info(0.1, 0.05), Loss::Huber(2.0))).unwrap();
        }
        for (a, b) in extra {
            let (a, b) = (a % n, b % n);
            if a != b {
                g.add_edge(edge(a, b, between(truth[a], truth[b]), info(0.1, 0.05), Loss::Cauchy(1.0))).unwrap();
            }
        }
        let opts = OptimizeOptions { max_iterations: 100, parameter_tolerance: 1e-14, function_tolerance: 1e-14, ..OptimizeOptions::default() };
        let report = g.optimize(&opts).unwrap();
        prop_assert!(report.final_cost < 1e-14, "{:?}", report);
        prop_assert!(max_pose_error(g.nodes(), &truth) < 1e-6);
    }

    /// `ρ'` is the derivative of `ρ`, and both agree with least squares near zero.
    #[test]
    fn loss_derivative_matches_finite_differences(s in 1e-3..100.0f64, k in 0.1..5.0f64) {
        for loss in [Loss::Trivial, Loss::Huber(k), Loss::Cauchy(k), Loss::Dcs(k)] {
            let h = 1e-6 * s;
            let numeric = (loss.evaluate(s + h).0 - loss.evaluate(s - h).0) / (2.0 * h);
            prop_assert!((numeric - loss.evaluate(s).1).abs() < 1e-5, "{:?} at {}", loss, s);
            let (rho0, w0) = loss.evaluate(0.0);
            prop_assert!(rho0 == 0.0 && w0 == 1.0);
        }
    }
}

/// A measurement, not a check: the time of `optimize` on a graph the size of a long indoor
/// log (15,000 nodes, 60,000 edges).  Run by hand:
/// `cargo test --release -p fusemap-core --lib slam::pose_graph::tests::timing -- --ignored --nocapture`
#[test]
#[ignore = "measurement, not a check; run by hand with --release"]
fn timing_15000_nodes_60000_edges() {
    use std::collections::HashMap;
    use std::time::Instant;
    let n = 15_000;
    let mut rng = Rng(2024);
    // A smooth random walk in a 60 m square, 0.4 m a step, turning back at the walls.
    let mut truth = vec![Pose2::new(30.0, 30.0, 0.0)];
    for _ in 1..n {
        let p = *truth.last().unwrap();
        let ahead = p.compose(Pose2::new(2.0, 0.0, 0.0));
        let turn =
            if (0.0..60.0).contains(&ahead.x) && (0.0..60.0).contains(&ahead.y) { 0.15 * rng.normal() } else { 0.5 };
        truth.push(p.compose(Pose2::new(0.4, 0.0, turn)));
    }
    let mut g = PoseGraph::new();
    g.add_node(truth[0]);
    let noisy = |rng: &mut Rng, z: Pose2, s: f64| {
        Pose2::new(z.x + s * rng.normal(), z.y + s * rng.normal(), z.theta + 0.25 * s * rng.normal())
    };
    for i in 1..n {
        let z = noisy(&mut rng, between(truth[i - 1], truth[i]), 0.02);
        let prev = g.nodes()[i - 1];
        g.add_node(prev.compose(z));
        g.add_edge(Edge { kind: EdgeKind::Odometry, ..edge(i - 1, i, z, info(0.02, 0.005), Loss::Trivial) }).unwrap();
    }
    for i in 0..n {
        for k in [2, 3] {
            if i + k < n {
                let z = noisy(&mut rng, between(truth[i], truth[i + k]), 0.02);
                g.add_edge(edge(i, i + k, z, info(0.02, 0.005), Loss::Huber(2.0))).unwrap();
            }
        }
    }
    // Loop closures: earlier nodes within the same 2 m cell, until 60,000 edges.
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, p) in truth.iter().enumerate() {
        let key = ((p.x / 2.0).floor() as i64, (p.y / 2.0).floor() as i64);
        let cell = cells.entry(key).or_default();
        let old: Vec<usize> = cell.iter().copied().filter(|&j| j + 50 < i).collect();
        for _ in 0..2 {
            if !old.is_empty() && g.edges().len() < 60_000 {
                let j = old[(rng.uniform() * old.len() as f64) as usize % old.len()];
                let z = noisy(&mut rng, between(truth[j], truth[i]), 0.05);
                g.add_edge(Edge { kind: EdgeKind::LoopClosure, ..edge(j, i, z, info(0.05, 0.0125), Loss::Huber(2.0)) })
                    .unwrap();
            }
        }
        cell.push(i);
    }
    let opts = OptimizeOptions::default();
    let t = Instant::now();
    let cold = g.optimize(&opts).unwrap();
    let cold_time = t.elapsed();
    eprintln!("nodes {} edges {}", g.nodes().len(), g.edges().len());
    eprintln!("from odometry (with symbolic analysis): {cold_time:?} {cold:?}");
    eprintln!("mean error {:.3} m", mean_translation_error(g.nodes(), &truth));
    let one = OptimizeOptions { max_iterations: 1, ..opts };
    let t = Instant::now();
    let single = g.optimize(&one).unwrap();
    eprintln!("one iteration at the optimum (symbolic reused): {:?} {single:?}", t.elapsed());
    for i in (0..n).step_by(7) {
        let p = g.nodes()[i];
        g.set_node(i, Pose2::new(p.x + 0.05 * rng.normal(), p.y + 0.05 * rng.normal(), p.theta + 0.01 * rng.normal()));
    }
    let t = Instant::now();
    let warm = g.optimize(&opts).unwrap();
    eprintln!("warm start, perturbed (symbolic reused): {:?} {warm:?}", t.elapsed());
}

/// A copy optimised elsewhere gives back the poses of the nodes it had, and the nodes
/// added to the graph meanwhile keep theirs, edges included.
#[test]
fn an_adopted_copy_sets_the_nodes_it_had_and_keeps_the_later_ones() {
    let mut g = PoseGraph::new();
    let a = g.add_node(Pose2::new(0.0, 0.0, 0.0));
    let b = g.add_node(Pose2::new(1.3, 0.2, 0.1));
    g.set_fixed(a, true);
    let info = [[100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [0.0, 0.0, 100.0]];
    let edge = |from, to| Edge {
        from,
        to,
        measurement: Pose2::new(1.0, 0.0, 0.0),
        information: info,
        loss: Loss::Trivial,
        kind: EdgeKind::Odometry,
    };
    g.add_edge(edge(a, b)).unwrap();
    let mut copy = g.take_copy();
    let later = g.add_node(Pose2::new(5.0, 5.0, 0.5));
    g.add_edge(edge(b, later)).unwrap();
    copy.optimize(&OptimizeOptions::default()).unwrap();
    let optimised = copy.nodes()[b];
    assert!(optimised.translation().distance(Point2::new(1.0, 0.0)) < 1e-6);
    g.adopt(copy);
    assert_eq!(g.nodes()[b], optimised);
    assert_eq!(g.nodes()[later], Pose2::new(5.0, 5.0, 0.5));
    assert_eq!(g.edges().len(), 2);
    g.optimize(&OptimizeOptions::default()).unwrap();
    assert!(g.nodes()[later].translation().distance(Point2::new(2.0, 0.0)) < 1e-6);
}
