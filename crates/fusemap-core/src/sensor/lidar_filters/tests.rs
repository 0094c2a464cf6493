use super::*;
use crate::geometry::{Mount3, Pose2};
use crate::measurement::{RangeData, SensorId};
use crate::sensor::{LaserScan, LidarModel, LidarParams, MaxRangePolicy, ReturnCounts};
use crate::time::Stamp;
use proptest::prelude::*;

/// One degree per beam, beam 0 at `angle_min_deg`.
fn run_with(filters: ScanFilters, mount: PlanarMount, angle_min_deg: f64, ranges: &[f32]) -> (RangeData, ReturnCounts) {
    let params =
        LidarParams { filters, max_range: 20.0, max_range_policy: MaxRangePolicy::Clear, ..Default::default() };
    let model = LidarModel::new(params, mount);
    let scan = LaserScan {
        stamp: Stamp(0),
        angle_min: angle_min_deg.to_radians(),
        angle_increment: 1f64.to_radians(),
        ranges: ranges.to_vec(),
    };
    let mut out = RangeData::empty(SensorId(0), model.evidence());
    let mut counts = ReturnCounts::default();
    model.scan_to_range_data(SensorId(0), &scan, Pose2::IDENTITY, &mut out, &mut counts);
    (out, counts)
}

fn run(filters: ScanFilters, ranges: &[f32]) -> (RangeData, ReturnCounts) {
    run_with(filters, PlanarMount::default(), 0.0, ranges)
}

fn only(f: impl FnOnce(&mut ScanFilters)) -> ScanFilters {
    let mut s = ScanFilters::NONE;
    f(&mut s);
    s
}

fn shadow() -> ScanFilters {
    only(|s| s.shadow.enabled = true)
}

/// The ranges of the rays a run produced, hits only.
fn hit_ranges(rd: &RangeData) -> Vec<f64> {
    rd.rays.iter().filter(|r| r.hit).map(|r| r.end.distance(r.origin)).collect()
}

#[test]
fn a_mixed_pixel_at_a_depth_edge_is_dropped_whole() {
    // A box edge at 2 m, the wall behind at 6 m, and one mixed pixel between them.
    let ranges = [2.0, 2.0, 2.0, 4.1, 6.0, 6.0, 6.0];
    let (rd, c) = run(shadow(), &ranges);
    assert_eq!(c.shadow, 2, "{c:?}");
    // The farther point of each veil went: the mixed pixel (beside 2.0) and the first
    // background return (beside the mixed pixel); the foreground stays.
    let kept = hit_ranges(&rd);
    assert_eq!(kept.len(), 5);
    assert!(!kept.iter().any(|r| (r - 4.1).abs() < 1e-6), "{kept:?}");
    assert_eq!(kept.iter().filter(|r| (*r - 2.0).abs() < 1e-6).count(), 3);
    // No ray at all along the dropped beams: neither hit nor free space.
    assert_eq!(rd.rays.len(), 5);
    assert_eq!(c.total(), ranges.len() as u64);
    // Without the filter everything is used.
    let (rd, c) = run(ScanFilters::NONE, &ranges);
    assert_eq!((rd.rays.len(), c.shadow), (7, 0));
}

#[test]
fn an_oblique_wall_is_not_a_veil() {
    // A wall 2 m ahead seen from beams 0°..30°: r = 2 / cos(a). Its incidence reaches 30°,
    // far from grazing, so nothing is dropped.
    let ranges: Vec<f32> = (0..=30).map(|a| (2.0 / (a as f64).to_radians().cos()) as f32).collect();
    let (_, c) = run(shadow(), &ranges);
    assert_eq!(c.shadow, 0);
    // At 81°..86° (9° to 4° from grazing) a wall 1 m ahead is a veil for a 10° filter, not for a 3° one.
    let grazing: Vec<f32> = (80..=86).map(|a| (1.0 / (a as f64).to_radians().cos()) as f32).collect();
    let (_, c) = run_with(shadow(), PlanarMount::default(), 80.0, &grazing);
    assert!(c.shadow >= 5, "{c:?}");
    let narrow = only(|s| {
        s.shadow.enabled = true;
        s.shadow.min_angle_deg = 3.0;
    });
    let (_, c) = run_with(narrow, PlanarMount::default(), 80.0, &grazing);
    assert_eq!(c.shadow, 0);
}

#[test]
fn shadow_neighbors_widen_the_cut_behind_the_edge() {
    let ranges = [2.0, 2.0, 2.0, 6.0, 6.0, 6.0, 6.0, 6.0];
    let (_, c) = run(shadow(), &ranges);
    assert_eq!(c.shadow, 1);
    let wide = only(|s| {
        s.shadow.enabled = true;
        s.shadow.neighbors = 3;
    });
    let (rd, c) = run(wide, &ranges);
    // Beams 3, 4, 5 are within 3 of beam 2 (the nearer point) and farther than it.
    assert_eq!(c.shadow, 3);
    assert_eq!(rd.rays.len(), 5);
}

#[test]
fn speckles_are_dropped_runs_kept() {
    let speckle = only(|s| s.speckle.enabled = true);
    // An isolated return among no-returns, and a pair of consistent ones.
    let ranges = [f32::INFINITY, 3.0, f32::INFINITY, 5.0, 5.05, f32::NAN, 8.0, 9.0];
    let (rd, c) = run(speckle, &ranges);
    assert_eq!(c.speckle, 3, "{c:?}");
    assert_eq!(hit_ranges(&rd).len(), 2);
    // A window of 3 also drops the pair.
    let three = only(|s| {
        s.speckle.enabled = true;
        s.speckle.window = 3;
    });
    assert_eq!(run(three, &ranges).1.speckle, 5);
    // Window 1 keeps everything.
    let one = only(|s| {
        s.speckle.enabled = true;
        s.speckle.window = 1;
    });
    assert_eq!(run(one, &ranges).1.speckle, 0);
}

#[test]
fn angular_bounds_drop_returns_and_no_returns_outside() {
    let bounds = only(|s| {
        s.angular_bounds = AngularBounds { enabled: true, lower_deg: -1.0, upper_deg: 1.0 };
    });
    // Beams at -3..=3 degrees; two of those outside are no-returns (cleared under Clear).
    let ranges = [4.0, 25.0, 4.0, 4.0, 4.0, 25.0, 4.0];
    let (rd, c) = run_with(bounds, PlanarMount::default(), -3.0, &ranges);
    assert_eq!(c.out_of_angle, 4);
    assert_eq!((c.valid, c.no_return), (3, 0));
    assert_eq!(rd.rays.len(), 3);
    assert!(rd.rays.iter().all(|r| r.end.y.abs() < 4.0 * 1.5f64.to_radians().sin()));
}

#[test]
fn the_self_box_is_in_the_base_frame() {
    // Lidar 0.3 m ahead of the base, looking backwards: a return at 0.4 m lies at
    // x = -0.1 in the base frame, inside a box around the base; one at 2 m does not.
    let mount = Mount3 { x: 0.3, yaw: std::f64::consts::PI, ..Default::default() }.to_planar(0.01).unwrap();
    let boxed = only(|s| s.self_box = SelfBox { enabled: true, min: [-0.5, -0.4], max: [0.5, 0.4] });
    let (rd, c) = run_with(boxed, mount, 0.0, &[0.4, 2.0, 0.45]);
    assert_eq!(c.in_box, 2);
    assert_eq!(rd.rays.len(), 1);
    assert!((rd.rays[0].end.x - (0.3 - 2.0)).abs() < 1e-3, "{:?}", rd.rays[0]);
}

#[test]
fn bad_parameters_name_their_key() {
    type Edit = fn(&mut ScanFilters);
    let cases: [(Edit, &str); 6] = [
        (|s| s.shadow.min_angle_deg = 0.0, "shadow.min_angle_deg"),
        (|s| s.shadow.window = 0, "shadow.window"),
        (|s| s.shadow.neighbors = 1000, "shadow.neighbors"),
        (|s| s.speckle.max_range_difference = f64::NAN, "speckle.max_range_difference"),
        (|s| s.angular_bounds.lower_deg = 200.0, "angular_bounds"),
        (|s| s.self_box.min = [1.0, 0.0], "box"),
    ];
    for (f, key) in cases {
        let mut s = ScanFilters::default();
        f(&mut s);
        assert_eq!(s.validate().unwrap_err().field, key);
    }
    assert!(ScanFilters::default().validate().is_ok());
    assert!(ScanFilters::NONE.validate().is_ok());
}

fn range_strategy() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => 0.05f32..25.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(0.0f32),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Every beam lands in exactly one counter, every counted return or cleared no-return
    /// is one ray, and a filter only ever removes rays.
    #[test]
    fn every_beam_is_counted_once(
        ranges in prop::collection::vec(range_strategy(), 1..60),
        shadow_on: bool, speckle_on: bool, bounds_on: bool, box_on: bool,
        window in 1u32..4, neighbors in 0u32..4, min_angle in 1.0f64..30.0,
    ) {
        let filters = ScanFilters {
            shadow: ShadowFilter { enabled: shadow_on, min_angle_deg: min_angle, window, neighbors },
            speckle: SpeckleFilter { enabled: speckle_on, max_range_difference: 0.2, window: window + 1 },
            angular_bounds: AngularBounds { enabled: bounds_on, lower_deg: 5.0, upper_deg: 40.0 },
            self_box: SelfBox { enabled: box_on, min: [-1.0, -1.0], max: [1.0, 1.0] },
        };
        let (rd, c) = run(filters, &ranges);
        prop_assert_eq!(c.total(), ranges.len() as u64);
        prop_assert_eq!(rd.rays.len() as u64, c.valid + c.no_return);
        let (plain, pc) = run(ScanFilters::NONE, &ranges);
        prop_assert_eq!(c.valid + c.no_return + c.filtered(), pc.valid + pc.no_return);
        prop_assert_eq!(c.invalid(), pc.invalid());
        prop_assert!(rd.rays.iter().all(|r| plain.rays.contains(r)));
    }
}
