use super::*;
use proptest::prelude::*;
use std::f64::consts::PI;

fn s(secs: i64) -> Stamp {
    Stamp(secs * 1_000_000_000)
}

fn rel(t1: Stamp, t2: Stamp, motion: Pose2) -> Relation {
    Relation { line: 0, t1, t2, motion }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// The reference trajectory a chain of relations implies: the first pose at the origin,
/// each next one its predecessor composed with the relation's motion. Each relation's t1
/// must be the previous relation's t2.
fn chain_trajectory(relations: &[Relation]) -> Vec<(Stamp, Pose2)> {
    let mut out = vec![(relations[0].t1, Pose2::IDENTITY)];
    for r in relations {
        let &(t, p) = out.last().unwrap();
        assert_eq!(t, r.t1, "relations do not chain");
        out.push((r.t2, p.compose(r.motion)));
    }
    out
}

/// A chain of `n` relations one second apart with varied motions (turns of either sign,
/// some past ±π/2 so headings wrap along the chain).
fn varied_chain(n: usize) -> Vec<Relation> {
    (0..n)
        .map(|k| {
            let k = k as f64;
            let motion = Pose2::new(0.3 + 0.1 * (k * 0.7).sin(), 0.05 * (k * 1.3).cos(), 0.9 * (k * 0.45).sin());
            rel(s(k as i64), s(k as i64 + 1), motion)
        })
        .collect()
}

#[test]
fn hand_computed_case() {
    // Trajectory P1 = (0, 0, 0°), P2 = (1, 0, 90°), P3 = (1, 1, 90°).
    // a: 1→2, reference (1, 0, 80°). Estimated δ = P1⁻¹P2 = (1, 0, 90°).
    //    ε = δ*⁻¹δ: rotation 90° − 80° = 10°, translation R(−80°)·((1,0) − (1,0)) = 0.
    //    (The other order, δ∘δ*⁻¹, would give a translation of 2·sin 5° = 0.174 m.)
    // b: 2→3, reference (1, 0.1, 0°). δ = P2⁻¹P3: (0, 1) seen from a 90° heading is
    //    (1, 0), so δ = (1, 0, 0°); ε = (0, −0.1, 0°): 0.1 m, 0°.
    // c: 1→3, reference (1.3, 1.4, 90°). δ = (1, 1, 90°); ε translation
    //    R(−90°)·(−0.3, −0.4), norm 0.5 m; rotation 0°.
    // d: 3→4: no pose at t = 4, unmatched.
    // Translations (0, 0.1, 0.5): mean 0.2, population std √((0.04 + 0.01 + 0.09)/3) =
    //   √0.046667 = 0.216025, max 0.5; squares (0, 0.01, 0.25): mean 0.086667, std
    //   √((0.086667² + 0.076667² + 0.163333²)/3) = √0.013356 = 0.115566.
    // Rotations (10°, 0, 0): mean 3.333333°, std √((6.6667² + 2·3.3333²)/3) = 4.714045°,
    //   max 10°; squares (100, 0, 0): mean 33.333333 deg², std 47.140452 deg².
    let trajectory = [
        (s(1), Pose2::new(0.0, 0.0, 0.0)),
        (s(2), Pose2::new(1.0, 0.0, PI / 2.0)),
        (s(3), Pose2::new(1.0, 1.0, PI / 2.0)),
    ];
    let relations = [
        rel(s(1), s(2), Pose2::new(1.0, 0.0, 80f64.to_radians())),
        rel(s(2), s(3), Pose2::new(1.0, 0.1, 0.0)),
        rel(s(1), s(3), Pose2::new(1.3, 1.4, PI / 2.0)),
        rel(s(3), s(4), Pose2::new(1.0, 0.0, 0.0)),
    ];
    let sc = score_relations(&relations, &trajectory, 0);
    assert_eq!((sc.relations, sc.scored, sc.unmatched), (4, 3, 1));
    let tol = 1e-6;
    assert!(close(sc.translation_mean_m, 0.2, tol), "{sc:?}");
    assert!(close(sc.translation_std_m, 0.216025, tol), "{sc:?}");
    assert!(close(sc.translation_max_m, 0.5, tol), "{sc:?}");
    assert!(close(sc.translation_sq_mean_m2, 0.086667, tol), "{sc:?}");
    assert!(close(sc.translation_sq_std_m2, 0.115566, tol), "{sc:?}");
    assert!(close(sc.rotation_mean_deg, 3.333333, tol), "{sc:?}");
    assert!(close(sc.rotation_std_deg, 4.714045, tol), "{sc:?}");
    assert!(close(sc.rotation_max_deg, 10.0, tol), "{sc:?}");
    assert!(close(sc.rotation_sq_mean_deg2, 33.333333, tol), "{sc:?}");
    assert!(close(sc.rotation_sq_std_deg2, 47.140452, tol), "{sc:?}");

    let errors = relation_errors(&relations, &trajectory, 0);
    assert!(errors[3].is_none());
    let b = errors[1].unwrap();
    assert!(close(b.x, 0.0, 1e-12) && close(b.y, -0.1, 1e-12) && close(b.theta, 0.0, 1e-12), "{b:?}");
}

#[test]
fn rotational_error_wraps_across_pi() {
    // Reference turn +179°, estimated −179°: 2° apart, not 358°.
    let trajectory = [(s(0), Pose2::IDENTITY), (s(1), Pose2::new(0.0, 0.0, (-179f64).to_radians()))];
    let relations = [rel(s(0), s(1), Pose2::new(0.0, 0.0, 179f64.to_radians()))];
    let sc = score_relations(&relations, &trajectory, 0);
    assert!(close(sc.rotation_mean_deg, 2.0, 1e-9), "{sc:?}");
    assert!(close(sc.translation_mean_m, 0.0, 1e-12), "{sc:?}");
}

#[test]
fn the_chain_reference_trajectory_scores_zero() {
    let relations = varied_chain(200);
    let trajectory = chain_trajectory(&relations);
    let sc = score_relations(&relations, &trajectory, 0);
    assert_eq!((sc.scored, sc.unmatched), (200, 0));
    assert!(sc.translation_max_m < 1e-9 && sc.rotation_max_deg < 1e-9, "{sc:?}");
}

#[test]
fn a_constant_per_step_error_scores_that_error() {
    // est_{k+1} = est_k ∘ δ*_k ∘ e, so δ_k = δ*_k ∘ e and ε_k = δ*_k⁻¹ ∘ δ*_k ∘ e = e.
    let e = Pose2::new(0.03, -0.04, 2f64.to_radians());
    let relations = varied_chain(100);
    let mut trajectory = vec![(relations[0].t1, Pose2::new(5.0, -3.0, 1.0))];
    for r in &relations {
        let p = trajectory.last().unwrap().1;
        trajectory.push((r.t2, p.compose(r.motion).compose(e)));
    }
    let sc = score_relations(&relations, &trajectory, 0);
    assert_eq!(sc.scored, 100);
    assert!(close(sc.translation_mean_m, 0.05, 1e-9), "{sc:?}");
    assert!(close(sc.rotation_mean_deg, 2.0, 1e-9), "{sc:?}");
    assert!(sc.translation_std_m < 1e-9 && sc.rotation_std_deg < 1e-9, "{sc:?}");
    assert!(close(sc.translation_sq_mean_m2, 0.0025, 1e-12), "{sc:?}");
    assert!(close(sc.rotation_sq_mean_deg2, 4.0, 1e-8), "{sc:?}");
}

#[test]
fn unmatched_stamps_are_counted_and_the_tolerance_applies() {
    let relations = varied_chain(4);
    let mut trajectory = chain_trajectory(&relations);
    // Pose at t = 2 s recorded 0.5 ms late; the pose at t = 4 s missing.
    trajectory[2].0 = Stamp(trajectory[2].0 .0 + 500_000);
    trajectory.pop();
    let exact = score_relations(&relations, &trajectory, 0);
    assert_eq!((exact.relations, exact.scored, exact.unmatched), (4, 1, 3));
    let ms = score_relations(&relations, &trajectory, 1_000_000);
    assert_eq!((ms.scored, ms.unmatched), (3, 1));
    assert!(ms.translation_max_m < 1e-9, "{ms:?}");
    let none = score_relations(&relations, &[], 1_000_000);
    assert_eq!((none.scored, none.unmatched), (0, 4));
    assert!(none.translation_mean_m.is_nan() && none.rotation_std_deg.is_nan());
}

#[test]
fn the_nearest_sample_is_taken() {
    // Samples at 0.9 s and 1.3 s for a relation stamp of 1 s: 0.9 s is nearer.
    let far = Pose2::new(9.0, 9.0, 0.0);
    let trajectory =
        [(s(0), Pose2::IDENTITY), (Stamp(900_000_000), Pose2::new(1.0, 0.0, 0.0)), (Stamp(1_300_000_000), far)];
    let relations = [rel(s(0), s(1), Pose2::new(1.0, 0.0, 0.0))];
    let sc = score_relations(&relations, &trajectory, 400_000_000);
    assert_eq!(sc.scored, 1);
    assert!(sc.translation_max_m < 1e-12, "{sc:?}");
}

#[test]
fn an_unsorted_trajectory_scores_like_the_sorted_one() {
    let relations = varied_chain(30);
    let mut trajectory = chain_trajectory(&relations);
    for p in trajectory.iter_mut() {
        p.1 = p.1.compose(Pose2::new(0.01 * (p.0 .0 % 7) as f64, 0.0, 0.002));
    }
    let sorted = score_relations(&relations, &trajectory, 0);
    trajectory.reverse();
    trajectory.swap(3, 17);
    assert_eq!(score_relations(&relations, &trajectory, 0), sorted);
    assert!(sorted.translation_mean_m > 0.0);
}

#[test]
fn parses_the_benchmark_format() {
    let text =
        "# comment\n\n976052905.167303 976052911.885496 -0.056990 -0.128430 0.000000 0.000000 0.000000 -1.682210\r\n\
                1134864645.90321 1134864646.32420 0.31293 0.02935 0.00000  0.00000 0.00000 4.0\n";
    let r = parse_relations(text).unwrap();
    assert_eq!(r.len(), 2);
    assert_eq!(r[0].line, 3);
    assert_eq!(r[0].t1, Stamp(976_052_905_167_303_000));
    assert_eq!(r[0].t2, Stamp(976_052_911_885_496_000));
    assert_eq!(r[0].motion, Pose2::new(-0.056990, -0.128430, -1.682210));
    assert_eq!(r[1].line, 4);
    assert_eq!(r[1].t2, Stamp(1_134_864_646_324_200_000));
    assert!(close(r[1].motion.theta, 4.0 - 2.0 * PI, 1e-12), "yaw wrapped to (-π, π]");
}

#[test]
fn parse_errors_name_the_line_and_the_fault() {
    let good = "1.0 2.0 0.1 0.2 0 0 0 0.3";
    let cases = [
        ("1.0 2.0 0.1 0.2 0 0 0", "expected 8 fields", "got 7"),
        ("1.0 2.0 0.1 0.2 0 0 0 0.3 9", "expected 8 fields", "got 9"),
        ("1e3 2.0 0.1 0.2 0 0 0 0.3", "field 1 (t1)", "`1e3`"),
        ("1.0 two 0.1 0.2 0 0 0 0.3", "field 2 (t2)", "decimal number of seconds"),
        ("1.0 2.0 x 0.2 0 0 0 0.3", "field 3 (x) is not a number", "`x`"),
        ("1.0 2.0 0.1 NaN 0 0 0 0.3", "field 4 (y) is not finite", "NaN"),
        ("1.0 2.0 0.1 0.2 0 0 0 inf", "field 8 (yaw) is not finite", "inf"),
        ("1.0 2.0 0.1 0.2 0 0.1 0 0.3", "roll is 0.1 rad", "not planar"),
        ("1.0 2.0 0.1 0.2 0 0 -0.05 0.3", "pitch is -0.05 rad", "not planar"),
        ("1.0 2.0 0.1 0.2 0.5 0 0 0.3", "z is 0.5 m", "not planar"),
    ];
    for (bad, what, detail) in cases {
        let text = format!("# header\n{good}\n\n{bad}\n{good}\n");
        let e = parse_relations(&text).unwrap_err();
        assert_eq!(e.line, 4, "{bad}: {e}");
        let msg = e.to_string();
        assert!(msg.starts_with("line 4: ") && msg.contains(what) && msg.contains(detail), "{bad}: {msg}");
    }
    assert_eq!(parse_relations("1.0 2.0 0.1 0.2 0.0005 0.0005 -0.0005 0.3").unwrap().len(), 1, "within tolerance");
    assert!(parse_relations("").unwrap().is_empty());
}

fn pose() -> impl Strategy<Value = Pose2> {
    (-50.0..50.0f64, -50.0..50.0f64, -PI..PI).prop_map(|(x, y, t)| Pose2::new(x, y, t))
}

proptest! {
    /// Relations drawn from any trajectory (any pairs of its poses, not only neighbours)
    /// score zero against it.
    #[test]
    fn relations_of_a_trajectory_score_zero_on_it(
        poses in prop::collection::vec(pose(), 2..30),
        pairs in prop::collection::vec((0usize..30, 0usize..30), 1..40),
    ) {
        let trajectory: Vec<(Stamp, Pose2)> = poses.iter().enumerate().map(|(k, p)| (s(k as i64), *p)).collect();
        let n = poses.len();
        let relations: Vec<Relation> = pairs
            .iter()
            .map(|&(i, j)| (i % n, j % n))
            .map(|(i, j)| rel(s(i as i64), s(j as i64), poses[i].inverse().compose(poses[j])))
            .collect();
        let sc = score_relations(&relations, &trajectory, 0);
        prop_assert_eq!(sc.scored, relations.len());
        prop_assert!(sc.translation_max_m < 1e-9 && sc.rotation_max_deg < 1e-9, "{:?}", sc);
    }

    /// The metric compares relative motions only: moving the whole trajectory by a rigid
    /// transform (a different map frame) leaves the score unchanged.
    #[test]
    fn the_score_ignores_the_map_frame(
        poses in prop::collection::vec(pose(), 2..20),
        motions in prop::collection::vec(pose(), 19),
        g in pose(),
    ) {
        let trajectory: Vec<(Stamp, Pose2)> = poses.iter().enumerate().map(|(k, p)| (s(k as i64), *p)).collect();
        let moved: Vec<(Stamp, Pose2)> = trajectory.iter().map(|&(t, p)| (t, g.compose(p))).collect();
        let relations: Vec<Relation> =
            (1..poses.len()).map(|k| rel(s(k as i64 - 1), s(k as i64), motions[k - 1])).collect();
        let a = score_relations(&relations, &trajectory, 0);
        let b = score_relations(&relations, &moved, 0);
        prop_assert!(close(a.translation_mean_m, b.translation_mean_m, 1e-9), "{:?} {:?}", a, b);
        prop_assert!(close(a.rotation_mean_deg, b.rotation_mean_deg, 1e-7), "{:?} {:?}", a, b);
        prop_assert!(close(a.translation_std_m, b.translation_std_m, 1e-9), "{:?} {:?}", a, b);
    }
}

#[test]
fn a_trajectory_between_the_relation_stamps_is_interpolated_within_the_gap() {
    // Straight at 1 m/s turning 0.1 rad/s, sampled every 100 ms; the relations name stamps
    // 30 ms after samples.
    let truth = |ns: i64| {
        let t = ns as f64 * 1e-9;
        Pose2::new(t, 0.0, 0.1 * t)
    };
    let trajectory: Vec<(Stamp, Pose2)> = (0..100).map(|k| (Stamp(k * 100_000_000), truth(k * 100_000_000))).collect();
    let (t1, t2) = (Stamp(1_030_000_000), Stamp(5_030_000_000));
    let motion = truth(t1.0).inverse().compose(truth(t2.0));
    let relations = [rel(t1, t2, motion), rel(t2, Stamp(20_000_000_000), Pose2::IDENTITY)];
    // Nearest-pose matching finds nothing within 1 ms …
    assert_eq!(score_relations(&relations, &trajectory, 1_000_000).scored, 0);
    // … the resampled trajectory scores the first relation, its translation exact and its
    // heading within the interpolation's linearisation.
    let resampled = at_relation_stamps(&relations, &trajectory, 1_000_000, 200_000_000);
    let score = score_relations(&relations, &resampled, 1_000_000);
    assert_eq!((score.scored, score.unmatched), (1, 1), "20 s lies past the trajectory");
    assert!(score.translation_max_m < 1e-9 && score.rotation_max_deg < 1e-9, "{score:?}");
    // A gap wider than allowed is not bridged.
    assert!(at_relation_stamps(&relations, &trajectory, 1_000_000, 50_000_000).is_empty());
}

#[test]
fn score_trajectory_moves_to_the_sensor_and_bridges_short_gaps_only() {
    // The laser 0.3 m ahead of the base; the relations are the laser's true motions.
    let relations = varied_chain(6);
    let laser = Pose2::new(0.3, 0.0, 0.0);
    let base: Vec<(Stamp, Pose2)> =
        chain_trajectory(&relations).into_iter().map(|(t, p)| (t, p.compose(laser.inverse()))).collect();
    let at_laser = RelationMatching { sensor_in_base: laser, ..RelationMatching::default() };
    let exact = score_trajectory(&relations, &base, &at_laser);
    assert_eq!((exact.scored, exact.unmatched), (6, 0));
    assert!(exact.translation_max_m < 1e-12 && exact.rotation_max_deg < 1e-9, "{exact:?}");
    // Scored at the base instead, the turns move it: an error, so the mount matters.
    assert!(score_trajectory(&relations, &base, &RelationMatching::default()).translation_max_m > 0.01);
    // Stamp 3 s missing: its neighbours are 2 s apart, beyond the 500 ms gap, so the two
    // relations naming it are unmatched; with a 2 s gap allowed they are interpolated.
    let holed: Vec<_> = base.iter().copied().filter(|(t, _)| *t != s(3)).collect();
    let r = score_trajectory(&relations, &holed, &at_laser);
    assert_eq!((r.scored, r.unmatched), (4, 2));
    let wide = RelationMatching { max_gap_ns: 2_000_000_000, ..at_laser };
    assert_eq!(score_trajectory(&relations, &holed, &wide).unmatched, 0);
}
