//! Tree-level tests: chains in every direction against an independent SE(2) oracle,
//! interpolation, refusals and the report.

use super::*;
use crate::geometry::{normalize_angle, Point2, Pose2, Pose3};
use crate::time::Stamp;
use proptest::prelude::*;

const MS: i64 = 1_000_000;

fn planar(x: f64, y: f64, yaw: f64) -> Pose3 {
    Pose3::new([x, y, 0.0], [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()])
}

fn pose2(p: &Pose3) -> Pose2 {
    let m = p.to_mount();
    Pose2::new(m.x, m.y, m.yaw)
}

fn assert_se2_eq(got: &Pose3, want: Pose2) {
    let g = pose2(got);
    assert!((g.x - want.x).abs() < 1e-9 && (g.y - want.y).abs() < 1e-9, "{g:?} vs {want:?}");
    assert!(normalize_angle(g.theta - want.theta).abs() < 1e-9, "{g:?} vs {want:?}");
}

/// REP 105 with a second sensor: map → odom → base_link → {laser, imu}.
fn robot() -> FrameTree {
    let mut tf = FrameTree::default();
    tf.add_static("base_link", "laser", planar(0.2, 0.05, 0.1)).unwrap();
    tf.add_static("base_link", "imu", planar(-0.1, 0.0, -1.2)).unwrap();
    for (t, x, yaw) in [(0, 0.0, 0.0), (100, 1.0, 0.4), (200, 1.5, 1.0)] {
        tf.add_dynamic(Stamp(t * MS), "odom", "base_link", planar(x, 0.5 * x, yaw)).unwrap();
    }
    for (t, dx) in [(0, 0.0), (200, 0.3)] {
        tf.add_dynamic(Stamp(t * MS), "map", "odom", planar(2.0 + dx, -1.0, 0.5)).unwrap();
    }
    tf
}

#[test]
fn chains_up_down_and_across_match_se2() {
    let tf = robot();
    let t = Stamp(100 * MS);
    // At a sample stamp of odom → base_link; map → odom is interpolated half way.
    let map_from_odom = Pose2::new(2.15, -1.0, 0.5);
    let odom_from_base = Pose2::new(1.0, 0.5, 0.4);
    let base_from_laser = Pose2::new(0.2, 0.05, 0.1);
    let base_from_imu = Pose2::new(-0.1, 0.0, -1.2);
    let map_from_laser = map_from_odom * odom_from_base * base_from_laser;
    // Target above the source, and below it.
    assert_se2_eq(&tf.lookup("map", "laser", t).unwrap(), map_from_laser);
    assert_se2_eq(&tf.lookup("laser", "map", t).unwrap(), map_from_laser.inverse());
    assert_se2_eq(&tf.lookup("odom", "base_link", t).unwrap(), odom_from_base);
    assert_se2_eq(&tf.lookup("base_link", "odom", t).unwrap(), odom_from_base.inverse());
    // Siblings: the common ancestor is base_link.
    assert_se2_eq(&tf.lookup("laser", "imu", t).unwrap(), base_from_laser.inverse() * base_from_imu);
    assert_se2_eq(&tf.lookup("imu", "laser", t).unwrap(), base_from_imu.inverse() * base_from_laser);
    // A frame to itself.
    assert_eq!(tf.lookup("laser", "laser", t).unwrap(), Pose3::IDENTITY);
    // A point one metre ahead of the laser, seen from the map.
    let p = tf.lookup("map", "laser", t).unwrap().to_mount();
    let want = map_from_laser * Point2::new(1.0, 0.0);
    let got = Pose2::new(p.x, p.y, p.yaw) * Point2::new(1.0, 0.0);
    assert!(got.distance(want) < 1e-9);
}

#[test]
fn interpolates_every_dynamic_edge_at_the_stamp() {
    let tf = robot();
    let t = Stamp(150 * MS);
    let odom_from_base = Pose2::new(1.0, 0.5, 0.4).interpolate(Pose2::new(1.5, 0.75, 1.0), 0.5);
    let map_from_odom = Pose2::new(2.225, -1.0, 0.5);
    let want = map_from_odom * odom_from_base * Pose2::new(0.2, 0.05, 0.1);
    assert_se2_eq(&tf.lookup("map", "laser", t).unwrap(), want);
    // Midpoint of the first interval: translation and yaw half way.
    let mid = pose2(&tf.lookup("odom", "base_link", Stamp(50 * MS)).unwrap());
    assert!((mid.x - 0.5).abs() < 1e-12 && (mid.y - 0.25).abs() < 1e-12 && (mid.theta - 0.2).abs() < 1e-12);
}

#[test]
fn never_extrapolates() {
    let mut tf = robot();
    let e = tf.lookup("map", "laser", Stamp(-3 * MS)).unwrap_err();
    assert!(matches!(&e, LookupError::BeforeSamples { by_s, .. } if (by_s - 0.003).abs() < 1e-12), "{e}");
    let e = tf.lookup("laser", "map", Stamp(201 * MS)).unwrap_err();
    assert!(matches!(&e, LookupError::AfterSamples { by_s, .. } if (by_s - 0.001).abs() < 1e-12), "{e}");
    assert!(tf.lookup("laser", "map", Stamp(200 * MS)).is_ok());
    // Only odom → base_link goes on: map → odom still ends at 200 ms.
    tf.add_dynamic(Stamp(300 * MS), "odom", "base_link", planar(2.0, 1.0, 1.0)).unwrap();
    assert!(tf.lookup("odom", "laser", Stamp(250 * MS)).is_ok());
    let e = tf.lookup("map", "laser", Stamp(250 * MS)).unwrap_err();
    assert_eq!(e, LookupError::AfterSamples { parent: "map".into(), child: "odom".into(), by_s: 0.05 });
    // Static chains hold at any stamp.
    assert!(tf.lookup("laser", "imu", Stamp(i64::MIN)).is_ok());
}

#[test]
fn long_gaps_are_refused() {
    let limits = FrameTreeLimits { max_gap_s: 0.15, ..FrameTreeLimits::default() };
    let mut tf = FrameTree::new(limits);
    for t in [0, 100, 400] {
        tf.add_dynamic(Stamp(t * MS), "odom", "base_link", planar(t as f64, 0.0, 0.0)).unwrap();
    }
    assert!(tf.lookup("odom", "base_link", Stamp(50 * MS)).is_ok());
    let e = tf.lookup("odom", "base_link", Stamp(200 * MS)).unwrap_err();
    assert!(matches!(e, LookupError::Gap { gap_s, limit_s, .. } if (gap_s - 0.3).abs() < 1e-12 && limit_s == 0.15));
    // The samples at the gap's ends are exact, not interpolated.
    assert!(tf.lookup("odom", "base_link", Stamp(400 * MS)).is_ok());
    for exact_only in [0.0, -1.0, f64::NAN] {
        let mut tf = FrameTree::new(FrameTreeLimits { max_gap_s: exact_only, ..limits });
        tf.add_dynamic(Stamp(0), "a", "b", planar(0.0, 0.0, 0.0)).unwrap();
        tf.add_dynamic(Stamp(10), "a", "b", planar(1.0, 0.0, 0.0)).unwrap();
        assert!(tf.lookup("a", "b", Stamp(10)).is_ok());
        assert!(matches!(tf.lookup("a", "b", Stamp(5)), Err(LookupError::Gap { .. })), "{exact_only}");
    }
    // A 3 s pause while standing (1 cm, 1°) is bridged by default, not when disabled.
    let mut tf = FrameTree::default();
    tf.add_dynamic(Stamp(0), "odom", "base_link", planar(2.0, 1.0, 0.0)).unwrap();
    tf.add_dynamic(Stamp(3_000 * MS), "odom", "base_link", planar(2.01, 1.0, 1f64.to_radians())).unwrap();
    let m = pose2(&tf.lookup("odom", "base_link", Stamp(1_500 * MS)).unwrap());
    assert!((m.x - 2.005).abs() < 1e-12 && (m.theta - 0.5f64.to_radians()).abs() < 1e-12, "{m:?}");
    let mut strict = FrameTree::new(FrameTreeLimits { bridge_motion_m: -1.0, ..FrameTreeLimits::default() });
    strict.add_dynamic(Stamp(0), "odom", "base_link", planar(2.0, 1.0, 0.0)).unwrap();
    strict.add_dynamic(Stamp(3_000 * MS), "odom", "base_link", planar(2.01, 1.0, 1f64.to_radians())).unwrap();
    assert!(matches!(strict.lookup("odom", "base_link", Stamp(1_500 * MS)), Err(LookupError::Gap { .. })));
    let unlimited = FrameTreeLimits { max_gap_s: f64::INFINITY, ..limits };
    let mut tf = FrameTree::new(unlimited);
    tf.add_dynamic(Stamp(0), "a", "b", planar(0.0, 0.0, 0.0)).unwrap();
    tf.add_dynamic(Stamp(i64::MAX), "a", "b", planar(1.0, 0.0, 0.0)).unwrap();
    assert!(tf.lookup("a", "b", Stamp(1 << 62)).is_ok());
}

#[test]
fn out_of_order_samples_are_kept_in_stamp_order() {
    let mut tf = FrameTree::default();
    let outcomes: Vec<_> = [(200, 2.0), (0, 0.0), (100, 1.0), (300, 3.0), (100, 1.0)]
        .into_iter()
        .map(|(t, x)| tf.add_dynamic(Stamp(t * MS), "odom", "base_link", planar(x, 0.0, 0.0)).unwrap())
        .collect();
    use AddOutcome::*;
    assert_eq!(outcomes, [NewEdge, InsertedOutOfOrder, InsertedOutOfOrder, Appended, IdenticalDuplicate]);
    for (t, x) in [(50, 0.5), (150, 1.5), (250, 2.5)] {
        assert!((tf.lookup("odom", "base_link", Stamp(t * MS)).unwrap().translation[0] - x).abs() < 1e-12);
    }
    let r = tf.report();
    assert_eq!(r.edges[0].samples, 4);
    assert_eq!(r.edges[0].out_of_order, 2);
    assert_eq!(r.edges[0].span, Some((Stamp(0), Stamp(300 * MS))));
    assert_eq!(r.accepted.identical_dynamic_duplicates, 1);
    let e = tf.add_dynamic(Stamp(100 * MS), "odom", "base_link", planar(1.0, 0.2, 0.0)).unwrap_err();
    assert!(matches!(e, FrameError::ConflictingSample { translation_m, .. } if (translation_m - 0.2).abs() < 1e-12));
    assert_eq!(tf.rejected().conflicting_sample, 1);
}

#[test]
fn loops_are_refused_and_reported() {
    let mut tf = FrameTree::default();
    tf.add_static("a", "b", planar(1.0, 0.0, 0.0)).unwrap();
    tf.add_static("b", "c", planar(1.0, 0.0, 0.0)).unwrap();
    let e = tf.add_static("c", "a", planar(1.0, 0.0, 0.0)).unwrap_err();
    let cycle: Vec<String> = ["a", "b", "c", "a"].map(String::from).into();
    assert_eq!(e, FrameError::Loop { parent: "c".into(), child: "a".into(), cycle: cycle.clone() });
    assert_eq!(e.to_string(), "edge c → a would close the loop a → b → c → a");
    let e = tf.add_dynamic(Stamp(0), "b", "b", planar(0.0, 0.0, 0.0)).unwrap_err();
    assert!(matches!(e, FrameError::Loop { .. }));
    tf.add_static("c", "a", planar(1.0, 0.0, 0.0)).unwrap_err();
    // The tree is unchanged.
    assert_eq!(tf.parent("a"), None);
    assert!((tf.lookup_static("a", "c").unwrap().translation[0] - 2.0).abs() < 1e-12);
    let r = tf.report();
    assert_eq!(r.rejected.loops, 3);
    assert_eq!(r.loops.len(), 2);
    let ca = r.loops.iter().find(|l| l.parent == "c").unwrap();
    assert_eq!((ca.count, &ca.cycle), (2, &cycle));
    assert_eq!(r.roots, ["a"]);
}

#[test]
fn a_second_parent_is_refused() {
    let mut tf = FrameTree::default();
    tf.add_static("base_link", "laser", planar(0.2, 0.0, 0.0)).unwrap();
    let e = tf.add_static("base_footprint", "laser", planar(0.2, 0.0, 0.0)).unwrap_err();
    assert_eq!(
        e,
        FrameError::TwoParents {
            child: "laser".into(),
            parent: "base_link".into(),
            rejected_parent: "base_footprint".into()
        }
    );
    assert_eq!(tf.parent("laser"), Some("base_link"));
    assert!(!tf.contains("base_footprint"));
    let r = tf.report();
    assert_eq!((r.rejected.two_parents, r.second_parents.len(), r.second_parents[0].count), (1, 1, 1));
}

#[test]
fn static_duplicates_identical_counted_conflicting_reported() {
    let mut tf = FrameTree::default();
    let mount = planar(0.2, 0.0, 0.0);
    assert_eq!(tf.add_static("base_link", "laser", mount), Ok(AddOutcome::NewEdge));
    // A latched /tf_static seen again in each bag split; q and -q are the same rotation.
    let negated = Pose3 { rotation: mount.rotation.map(|v| -v), ..mount };
    for again in [mount, mount, negated] {
        assert_eq!(tf.add_static("/base_link", "laser", again), Ok(AddOutcome::IdenticalDuplicate));
    }
    let moved = planar(0.23, 0.04, 2f64.to_radians());
    let e = tf.add_static("base_link", "laser", moved).unwrap_err();
    let FrameError::ConflictingStatic { translation_m, rotation_deg, .. } = e else { panic!("{e}") };
    assert!(
        (translation_m - 0.05).abs() < 1e-12 && (rotation_deg - 2.0).abs() < 1e-9,
        "{translation_m} {rotation_deg}"
    );
    // The first value is kept.
    assert_eq!(tf.lookup_static("base_link", "laser").unwrap(), mount);
    let r = tf.report();
    assert_eq!(r.accepted.identical_static_duplicates, 3);
    assert_eq!(r.edges[0].identical_duplicates, 3);
    assert_eq!(r.edges[0].conflicts, 1);
    assert_eq!(r.conflicts.len(), 1);
    let c = &r.conflicts[0];
    assert_eq!((c.kind, c.count), (EdgeKind::Static, 1));
    assert!((c.max_translation_m - 0.05).abs() < 1e-12 && (c.max_rotation_deg - 2.0).abs() < 1e-9);
}

#[test]
fn static_and_dynamic_do_not_mix_on_one_edge() {
    let mut tf = FrameTree::default();
    tf.add_static("base_link", "laser", planar(0.2, 0.0, 0.0)).unwrap();
    let e = tf.add_dynamic(Stamp(0), "base_link", "laser", planar(0.2, 0.0, 0.0)).unwrap_err();
    assert!(matches!(e, FrameError::KindClash { existing: EdgeKind::Static, attempted: EdgeKind::Dynamic, .. }));
    tf.add_dynamic(Stamp(0), "odom", "base_link", planar(0.0, 0.0, 0.0)).unwrap();
    let e = tf.add_static("odom", "base_link", planar(0.0, 0.0, 0.0)).unwrap_err();
    assert!(matches!(e, FrameError::KindClash { existing: EdgeKind::Dynamic, .. }));
    assert_eq!(tf.edge_kind("odom", "base_link"), Some(EdgeKind::Dynamic));
    assert_eq!(tf.edge_kind("base_link", "odom"), None);
    assert_eq!(tf.rejected().kind_clash, 2);
    assert_eq!(tf.report().kind_clashes.len(), 2);
}

#[test]
fn non_finite_and_bad_quaternions_are_refused_without_a_trace() {
    let mut tf = FrameTree::default();
    let nan = Pose3 { translation: [f64::NAN, 0.0, 0.0], rotation: [0.0, 0.0, 0.0, 1.0] };
    assert!(matches!(tf.add_static("base_link", "laser", nan), Err(FrameError::NotFinite { .. })));
    let nan_q = Pose3 { translation: [0.0; 3], rotation: [f64::NAN, 0.0, 0.0, 1.0] };
    assert!(matches!(tf.add_dynamic(Stamp(0), "odom", "base_link", nan_q), Err(FrameError::NotFinite { .. })));
    let zero = Pose3 { translation: [0.0; 3], rotation: [0.0; 4] };
    assert!(matches!(tf.add_static("a", "b", zero), Err(FrameError::ZeroQuaternion { .. })));
    let long = Pose3 { translation: [0.0; 3], rotation: [0.0, 0.0, 0.0, 2.0] };
    assert!(matches!(tf.add_static("a", "b", long), Err(FrameError::NotUnitQuaternion { .. })));
    assert!(matches!(tf.add_static("", "b", Pose3::IDENTITY), Err(FrameError::InvalidName { .. })));
    assert_eq!(tf.frames().count(), 0);
    let r = tf.rejected();
    assert_eq!((r.not_finite, r.zero_quaternion, r.not_unit_quaternion, r.invalid_name, r.total()), (2, 1, 1, 1, 5));
    // Near-unit quaternions are normalised.
    let near = Pose3 { translation: [0.0; 3], rotation: [0.0, 0.0, 0.0, 0.999] };
    tf.add_static("a", "b", near).unwrap();
    assert_eq!(tf.lookup_static("a", "b").unwrap().rotation, [0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn one_leading_slash_is_ignored_everywhere() {
    let mut tf = FrameTree::default();
    tf.add_static("/base_link", "laser", planar(0.2, 0.0, 0.0)).unwrap();
    tf.add_static("base_link", "/laser", planar(0.2, 0.0, 0.0)).unwrap();
    tf.add_static("//odd", "base_link", planar(1.0, 0.0, 0.0)).unwrap();
    assert_eq!(tf.frames().collect::<Vec<_>>(), ["base_link", "laser", "/odd"]);
    assert_eq!(tf.parent("/base_link"), Some("/odd"));
    assert!(tf.lookup_static("//odd", "/laser").is_ok());
    assert!(!tf.contains("odd"));
    assert_eq!(tf.accepted().identical_static_duplicates, 1);
}

#[test]
fn unknown_and_disconnected_frames() {
    let mut tf = robot();
    tf.add_static("world", "dock", planar(1.0, 0.0, 0.0)).unwrap();
    let e = tf.lookup("map", "lidar", Stamp(0)).unwrap_err();
    assert_eq!(e, LookupError::UnknownFrame { frame: "lidar".into() });
    let e = tf.lookup("dock", "laser", Stamp(0)).unwrap_err();
    assert!(
        matches!(&e, LookupError::NotConnected { target_root, source_root, .. } if target_root == "world" && source_root == "map")
    );
    assert_eq!(tf.report().roots, ["map", "world"]);
}

#[test]
fn static_lookups_and_latest_common_stamp() {
    let tf = robot();
    let want = Pose2::new(0.2, 0.05, 0.1).inverse() * Pose2::new(-0.1, 0.0, -1.2);
    assert_se2_eq(&tf.lookup_static("laser", "imu").unwrap(), want);
    let e = tf.lookup_static("odom", "laser").unwrap_err();
    assert_eq!(e, LookupError::DynamicEdge { parent: "odom".into(), child: "base_link".into() });
    assert_eq!(tf.latest_common_stamp("laser", "imu"), Ok(None));
    assert_eq!(tf.latest_common_stamp("map", "laser"), Ok(Some(Stamp(200 * MS))));
    let mut tf = tf;
    tf.add_dynamic(Stamp(500 * MS), "odom", "base_link", planar(2.0, 0.0, 0.0)).unwrap();
    // map → odom ends at 200 ms: the common window ends there.
    assert_eq!(tf.latest_common_stamp("laser", "map"), Ok(Some(Stamp(200 * MS))));
    assert_eq!(tf.latest_common_stamp("odom", "laser"), Ok(Some(Stamp(500 * MS))));
    let mut apart = FrameTree::default();
    apart.add_dynamic(Stamp(0), "a", "b", Pose3::IDENTITY).unwrap();
    apart.add_dynamic(Stamp(10), "b", "c", Pose3::IDENTITY).unwrap();
    assert!(matches!(apart.latest_common_stamp("a", "c"), Err(LookupError::NoCommonTime { .. })));
}

#[test]
fn report_lists_the_tree_depth_first() {
    let mut tf = robot();
    tf.add_dynamic(Stamp(0), "odom", "base_link", planar(0.0, 0.0, 0.0)).unwrap();
    let r = tf.report();
    let frames: Vec<_> = r.frames.iter().map(|f| (f.name.as_str(), f.depth)).collect();
    assert_eq!(frames, [("map", 0), ("odom", 1), ("base_link", 2), ("imu", 3), ("laser", 3)]);
    let edges: Vec<_> = r.edges.iter().map(|e| (e.child.as_str(), e.kind, e.samples)).collect();
    use EdgeKind::*;
    assert_eq!(edges, [("odom", Dynamic, 2), ("base_link", Dynamic, 3), ("imu", Static, 1), ("laser", Static, 1)]);
    assert!((r.edges[0].longest_gap_s.unwrap() - 0.2).abs() < 1e-15);
    assert_eq!(r.accepted.new_edges, 4);
    assert_eq!(r.accepted.appended, 3);
    assert_eq!(r.accepted.identical_dynamic_duplicates, 1);
    assert_eq!(r.rejected, Rejections::default());
    fn serialisable<T: serde::Serialize>(_: &T) {}
    serialisable(&r);
}

/// A random tree: frame `i > 0` hangs below a frame `< i`, its edge either static or
/// dynamic with samples at 0 and 1 s.
type EdgeSpec = (f64, bool, [f64; 3], [f64; 4], [f64; 3], [f64; 4]);

fn random_tree(specs: &[EdgeSpec]) -> FrameTree {
    let mut tf = FrameTree::new(FrameTreeLimits { max_gap_s: 2.0, ..FrameTreeLimits::default() });
    for (k, &(pick, dynamic, t0, q0, t1, q1)) in specs.iter().enumerate() {
        let child = k + 1;
        let parent = ((pick * child as f64) as usize).min(k);
        let (p, c) = (format!("f{parent}"), format!("f{child}"));
        if dynamic {
            tf.add_dynamic(Stamp(0), &p, &c, Pose3::new(t0, q0)).unwrap();
            tf.add_dynamic(Stamp(1_000_000_000), &p, &c, Pose3::new(t1, q1)).unwrap();
        } else {
            tf.add_static(&p, &c, Pose3::new(t0, q0)).unwrap();
        }
    }
    tf
}

fn edge_spec() -> impl Strategy<Value = EdgeSpec> {
    let t = prop::array::uniform3(-3.0..3.0f64);
    let q =
        prop::array::uniform4(-1.0..1.0f64).prop_filter("rotation", |q| q.iter().map(|v| v * v).sum::<f64>() > 0.01);
    (0.0..1.0f64, any::<bool>(), t.clone(), q.clone(), t, q)
}

proptest! {
    #[test]
    fn lookups_invert_and_chain(specs in prop::collection::vec(edge_spec(), 1..8), picks in prop::array::uniform3(0usize..100),
                                at in 0i64..=1_000_000_000) {
        let tf = random_tree(&specs);
        let n = specs.len() + 1;
        let [a, b, c] = picks.map(|k| format!("f{}", k % n));
        let stamp = Stamp(at);
        let a_from_b = tf.lookup(&a, &b, stamp).unwrap();
        let b_from_a = tf.lookup(&b, &a, stamp).unwrap();
        let id = a_from_b.compose(&b_from_a);
        prop_assert!(id.distance_to(&Pose3::IDENTITY) < 1e-9 && id.angle_to(&Pose3::IDENTITY) < 1e-9, "{id:?}");
        // a_from_c = a_from_b ∘ b_from_c, whatever the frames' places in the tree.
        let direct = tf.lookup(&a, &c, stamp).unwrap();
        let via_b = a_from_b.compose(&tf.lookup(&b, &c, stamp).unwrap());
        prop_assert!(direct.distance_to(&via_b) < 1e-9 && direct.angle_to(&via_b) < 1e-9);
        // Every frame hangs below f0; nothing outside [0, 1] s when a dynamic edge is on the path.
        let late = tf.lookup(&a, &c, Stamp(1_000_000_001));
        let dynamic_on_path = tf.latest_common_stamp(&a, &c).unwrap().is_some();
        prop_assert_eq!(late.is_err(), dynamic_on_path);
        prop_assert_eq!(tf.lookup_static(&a, &c).is_ok(), !dynamic_on_path);
    }

    #[test]
    fn planar_chains_match_se2(xs in prop::collection::vec((-3.0..3.0f64, -3.0..3.0f64, -3.2..3.2f64), 2..6),
                               ys in prop::collection::vec((-3.0..3.0f64, -3.0..3.0f64, -3.2..3.2f64), 2..6),
                               f in 0.0..1.0f64) {
        // f0 → f1 → … dynamic (samples xs at 0 s and ys at 1 s), lookup f0 ← last at f.
        let n = xs.len().min(ys.len());
        let mut tf = FrameTree::new(FrameTreeLimits { max_gap_s: 1.0, ..FrameTreeLimits::default() });
        let mut want = Pose2::IDENTITY;
        for k in 0..n {
            let (a, b) = (Pose2::new(xs[k].0, xs[k].1, xs[k].2), Pose2::new(ys[k].0, ys[k].1, ys[k].2));
            let (p, c) = (format!("f{k}"), format!("f{}", k + 1));
            tf.add_dynamic(Stamp(0), &p, &c, planar(a.x, a.y, a.theta)).unwrap();
            tf.add_dynamic(Stamp(1_000_000_000), &p, &c, planar(b.x, b.y, b.theta)).unwrap();
            want = want * a.interpolate(b, f);
        }
        let got = pose2(&tf.lookup("f0", &format!("f{n}"), Stamp((f * 1e9).round() as i64)).unwrap());
        // The stamp is rounded to a nanosecond: allow for the motion over it.
        prop_assert!((got.x - want.x).abs() < 1e-6 && (got.y - want.y).abs() < 1e-6);
        prop_assert!(normalize_angle(got.theta - want.theta).abs() < 1e-6);
    }
}
