use super::*;
use crate::slam::grid::UpdateTable;
use crate::slam::test_world::World;

fn grid_of(world: &World, poses: &[Pose2]) -> ProbabilityGrid {
    let (hit, miss) = (UpdateTable::new(0.55), UpdateTable::new(0.49));
    let mut g = ProbabilityGrid::new(0.05);
    for _ in 0..4 {
        for &pose in poses {
            let pts: Vec<Point2> = world.scan(pose, 360, 30.0).into_iter().map(|q| pose.transform_point(q)).collect();
            g.insert(pose.translation(), &pts, &[], &hit, &miss);
        }
    }
    g
}

#[test]
fn a_perturbed_prediction_is_corrected_to_the_true_pose() {
    let world = World::room();
    let g = grid_of(&world, &[Pose2::new(6.0, 4.0, 0.0), Pose2::new(7.0, 3.0, 1.0)]);
    let truth = Pose2::new(6.4, 3.7, 0.4);
    let pts = world.scan(truth, 180, 30.0);
    let params = LocalMatchParams::default();
    for (dx, dy, dth) in [(0.08, -0.06, 3f64.to_radians()), (-0.11, 0.04, -5f64.to_radians()), (0.0, 0.0, 0.0)] {
        let predicted = Pose2::new(truth.x + dx, truth.y + dy, truth.theta + dth);
        let m = match_scan(&g, &pts, predicted, &params);
        let e = (m.pose.x - truth.x).hypot(m.pose.y - truth.y);
        let eth = normalize_angle(m.pose.theta - truth.theta).abs();
        // Within 0.4 cell: the optimum of a 5 cm grid sits about a centimetre off the
        // truth, and the translation's pull to the prediction (the motion prior) adds a
        // few millimetres from 10 cm off.
        assert!(e < 0.02 && eth < 0.3f64.to_radians(), "from ({dx},{dy},{dth}): error {e} m, {eth} rad");
        assert!(!m.degenerate);
        assert!(m.score > 0.6, "score {}", m.score);
    }
}

#[test]
fn the_correlative_search_pulls_a_slip_out_of_the_refinements_basin() {
    let world = World::room();
    let g = grid_of(&world, &[Pose2::new(6.0, 4.0, 0.0)]);
    let truth = Pose2::new(6.0, 4.0, 0.0);
    let pts = world.scan(truth, 180, 30.0);
    let params = LocalMatchParams::default();
    // 14 cm off: far outside the bicubic kernel's reach from the start.
    let predicted = Pose2::new(6.14, 4.0, 0.0);
    let refined_only = refine(&g, &pts, predicted, predicted, &LocalMatchParams { translation_weight: 0.0, ..params });
    let m = match_scan(&g, &pts, predicted, &params);
    assert!((m.pose.x - truth.x).abs() < 0.015, "matched {:?}", m.pose);
    assert!((refined_only.x - truth.x).abs() > (m.pose.x - truth.x).abs());
}

#[test]
fn a_corridor_match_is_degenerate_along_the_corridor() {
    let world = World::corridor();
    let along: Vec<Pose2> = (-10..=10).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
    let g = grid_of(&world, &along);
    let pts = world.scan(Pose2::new(0.5, 0.1, 0.0), 180, 8.0);
    let m = match_scan(&g, &pts, Pose2::new(0.5, 0.1, 0.0), &LocalMatchParams::default());
    assert!(m.degenerate, "{:?}", m.information);
    // Across the corridor the match is confident, along it almost not.
    assert!(m.information[1][1] > 20.0 * m.information[0][0], "{:?}", m.information);
    // Along the corridor the translation stays where the prediction put it (the pull to
    // the prediction), wherever the search's best cell fell; from 5 cm across it, the
    // match pulls it back onto the walls.
    let predicted = Pose2::new(0.5, 0.15, 0.0);
    let m = match_scan(&g, &pts, predicted, &LocalMatchParams::default());
    assert!((m.pose.x - 0.5).abs() < 0.01, "along: {:?}", m.pose);
    assert!((m.pose.y - 0.1).abs() < 0.02, "across: {:?}", m.pose);
    let room = World::room();
    let g = grid_of(&room, &[Pose2::new(6.0, 4.0, 0.0)]);
    let m = match_scan(
        &g,
        &room.scan(Pose2::new(6.0, 4.0, 0.0), 180, 30.0),
        Pose2::new(6.0, 4.0, 0.0),
        &LocalMatchParams::default(),
    );
    assert!(!m.degenerate);
}

#[test]
fn no_points_no_panic() {
    let g = ProbabilityGrid::new(0.05);
    let m = match_scan(&g, &[], Pose2::new(1.0, 2.0, 0.5), &LocalMatchParams::default());
    assert!(m.pose.is_finite());
    assert!(m.degenerate);
}

/// The textbook correlative search (translations outer, points inner, one bounds-checked
/// lookup per point): the fast search must find the same pose and score to the bit.
fn reference_search(grid: &ProbabilityGrid, points: &[Point2], predicted: Pose2, p: &LocalMatchParams) -> (Pose2, f32) {
    let r = grid.resolution();
    let max_range = points.iter().map(|q| q.x.hypot(q.y)).fold(r, f64::max).min(10.0);
    let step = (1.0 - r * r / (2.0 * max_range * max_range)).clamp(-1.0, 1.0).acos().max(1e-4);
    let n_ang = (p.angular_window_rad / step).ceil() as i64;
    let n_lin = (p.linear_window_m / r).ceil() as i64;
    let (mut best, mut best_score) = (predicted, f32::MIN);
    let inv_n = 1.0 / points.len().max(1) as f32;
    for a in -n_ang..=n_ang {
        let dtheta = a as f64 * step;
        let rotated = Pose2::new(predicted.x, predicted.y, predicted.theta + dtheta);
        let cells: Vec<(i64, i64)> = points
            .iter()
            .map(|q| {
                let w = rotated.transform_point(*q);
                ((w.x / r).floor() as i64, (w.y / r).floor() as i64)
            })
            .collect();
        for dy in -n_lin..=n_lin {
            for dx in -n_lin..=n_lin {
                let sum: f32 = cells.iter().map(|&(cx, cy)| grid.probability(cx + dx, cy + dy)).sum();
                let dist = ((dx * dx + dy * dy) as f64).sqrt() * r;
                let penalty = (-(dist * p.translation_delta_cost + dtheta.abs() * p.rotation_delta_cost).powi(2)).exp();
                let score = sum * inv_n * penalty as f32;
                if score > best_score {
                    best_score = score;
                    best =
                        Pose2::new(predicted.x + dx as f64 * r, predicted.y + dy as f64 * r, predicted.theta + dtheta);
                }
            }
        }
    }
    (best.normalized(), best_score)
}

#[test]
fn the_fast_correlative_search_is_the_textbook_one_to_the_bit() {
    let world = World::room();
    let mut g = grid_of(&world, &[Pose2::new(6.0, 4.0, 0.0), Pose2::new(7.0, 3.0, 1.0)]);
    let truth = Pose2::new(6.4, 3.7, 0.4);
    let pts = world.scan(truth, 180, 30.0);
    // Points past the grid's edge take the bounds-checked path; a window of 4 cells (9
    // columns) spans two lanes of eight.
    let mut far = pts.clone();
    far.extend([Point2::new(60.0, 1.0), Point2::new(-3.0, 45.0)]);
    let wide = LocalMatchParams { linear_window_m: 0.2, ..LocalMatchParams::default() };
    for frozen in [false, true] {
        if frozen {
            g.freeze();
        }
        for (points, params) in [(&pts, LocalMatchParams::default()), (&far, LocalMatchParams::default()), (&pts, wide)]
        {
            for (dx, dy, dth) in [(0.08, -0.06, 3f64.to_radians()), (-0.11, 0.04, -5f64.to_radians()), (0.0, 0.0, 0.0)]
            {
                let predicted = Pose2::new(truth.x + dx, truth.y + dy, truth.theta + dth);
                let (pose, score) = correlative_search(&g, points, predicted, &params);
                let (ref_pose, ref_score) = reference_search(&g, points, predicted, &params);
                assert_eq!(score.to_bits(), ref_score.to_bits(), "frozen {frozen}, from ({dx},{dy},{dth})");
                assert_eq!(
                    [pose.x, pose.y, pose.theta].map(f64::to_bits),
                    [ref_pose.x, ref_pose.y, ref_pose.theta].map(f64::to_bits)
                );
            }
        }
    }
}
