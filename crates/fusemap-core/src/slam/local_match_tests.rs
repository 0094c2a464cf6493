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
