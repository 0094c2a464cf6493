//! Tests of the camera model against scenes whose answer is known analytically.

use super::model::erf;
use super::*;
use crate::geometry::{Mount3, Point2, Pose2, Pose3};
use crate::measurement::SensorId;
use proptest::prelude::*;
use std::f64::consts::FRAC_PI_2;

const WALL: u16 = 2;
const FLOOR: u16 = 1;

fn pinhole(w: u32, h: u32, f: f64) -> Pinhole {
    Pinhole::new(w, h, f, f, w as f64 / 2.0, h as f64 / 2.0).unwrap()
}

fn model(p: Pinhole, mount: Pose3, params: CameraParams) -> CameraModel {
    CameraModel::new(p, mount, params, 0.05, ClassTable::production_default()).unwrap()
}

fn run(m: &CameraModel, labels: &LabelImage, depth: &DepthImage, pose: Pose2) -> (CameraObservation, PixelCounts) {
    let mut out = CameraObservation::empty(SensorId(3));
    let mut counts = PixelCounts::default();
    m.project(labels, depth, pose, &mut out, &mut counts).unwrap();
    (out, counts)
}

fn class_of(m: &CameraModel, p: &CameraPoint) -> u16 {
    m.classes().get(p.class).id
}

/// A level forward camera at (0.2, 0, 1.0) in base; a wall at base x = 3 (2 m high), the
/// floor below. Depths are written from the analytic hit points, and each used pixel's
/// point must land where that hit point is (within 1 cm), in the band its height says.
#[test]
fn level_camera_sees_wall_and_floor_where_they_are() {
    let ph = pinhole(64, 48, 40.0);
    let params = CameraParams { stride: 1, max_depth_m: 10.0, depth_sigma_k: 0.0, ..Default::default() };
    let m = model(ph, optical_mount([0.2, 0.0, 1.0], 0.0, 0.0), params);
    let (mut labels, mut depth) = (vec![0u16; 64 * 48], vec![f32::NAN; 64 * 48]);
    let mut expected = Vec::new();
    for v in 0..48 {
        for u in 0..64 {
            let xn = (u as f64 - 32.0) / 40.0;
            let yn = (v as f64 - 24.0) / 40.0;
            // The ray with optical z = 1 points along base (1, -xn, -yn) from the camera.
            let z_at_wall = 1.0 - 2.8 * yn;
            let (class, t) = if (0.0..=2.0).contains(&z_at_wall) {
                (WALL, 2.8)
            } else if yn > 0.0 {
                (FLOOR, 1.0 / yn)
            } else {
                continue;
            };
            let i = v * 64 + u;
            (labels[i], depth[i]) = (class, t as f32);
            if t <= 10.0 {
                expected.push((class, [0.2 + t, -t * xn, 1.0 - t * yn]));
            }
        }
    }
    let labels = LabelImage::new(64, 48, labels).unwrap();
    let depth = DepthImage::new(64, 48, depth).unwrap();
    let pose = Pose2::new(2.0, 1.0, FRAC_PI_2);
    let (out, counts) = run(&m, &labels, &depth, pose);
    assert_eq!(out.sensor, SensorId(3), "the caller's fields are kept");
    assert!(out.origin.distance(Point2::new(2.0, 1.2)) < 1e-9, "{:?}", out.origin);
    assert_eq!(counts.seen, 64 * 48);
    assert_eq!(counts.used, expected.len() as u64);
    assert_eq!(counts.out_of_depth_range + counts.ignored_class + counts.used, counts.seen);
    assert_eq!(out.points.len(), expected.len());
    let mut bands = [0usize; 2];
    for (p, (class, b)) in out.points.iter().zip(&expected) {
        assert_eq!(class_of(&m, p), *class);
        // Map = pose · base: base (bx, by) goes to (2 - by, 1 + bx).
        let want = Point2::new(2.0 - b[1], 1.0 + b[0]);
        assert!(p.end.distance(want) < 0.01, "{:?} vs {want:?}", p.end);
        let band = if b[2] < 0.08 { Band::Floor } else { Band::Obstacle };
        assert_eq!(p.band, band, "point at height {}", b[2]);
        bands[(band == Band::Obstacle) as usize] += 1;
        assert_eq!(p.weight, 1.0, "k = 0: exact depth");
    }
    // Both bands and both classes occur, and a wall row low enough to be floor-band.
    assert!(bands[0] > 100 && bands[1] > 100, "{bands:?}");
    assert!(out.points.iter().any(|p| class_of(&m, p) == WALL && p.band == Band::Floor));
}

/// The pixel convention of `CameraInfo` (centres at integer coordinates): an ideal camera,
/// `cx = (w − 1) / 2`, facing a wall square on sees it symmetrically, the first column's
/// points the mirror images of the last's. Centres at `u + 0.5` turn every ray by half a
/// pixel and break the symmetry by about a centimetre here.
#[test]
fn an_ideal_camera_sees_a_square_wall_symmetrically() {
    let (w, h, f) = (32u32, 8u32, 20.0);
    let ph = Pinhole::new(w, h, f, f, (f64::from(w) - 1.0) / 2.0, (f64::from(h) - 1.0) / 2.0).unwrap();
    let params = CameraParams { stride: 1, max_depth_m: 10.0, depth_sigma_k: 0.0, ..Default::default() };
    let m = model(ph, optical_mount([0.0, 0.0, 1.0], 0.0, 0.0), params);
    let n = (w * h) as usize;
    let labels = LabelImage::new(w, h, vec![WALL; n]).unwrap();
    let depth = DepthImage::new(w, h, vec![3.0; n]).unwrap();
    let (out, counts) = run(&m, &labels, &depth, Pose2::default());
    assert_eq!(counts.used, n as u64);
    // Points come row by row, left to right; the base frame's y is left.
    for row in out.points.chunks(w as usize) {
        for (a, b) in row.iter().zip(row.iter().rev()) {
            assert!((a.end.x - 3.0).abs() < 1e-9 && (b.end.x - 3.0).abs() < 1e-9, "{:?} {:?}", a.end, b.end);
            assert!((a.end.y + b.end.y).abs() < 1e-9, "{:?} and {:?} are not mirror images", a.end, b.end);
        }
        assert!((row[0].end.y - 3.0 * 15.5 / f).abs() < 1e-9, "{:?}", row[0].end);
    }
}

/// The optical axes of `optical_mount` in the base frame, against REP 103.
#[test]
fn optical_mount_axes() {
    let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12);
    let level = optical_mount([0.0; 3], 0.0, 0.0);
    assert!(close(level.rotate([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]), "z forward");
    assert!(close(level.rotate([1.0, 0.0, 0.0]), [0.0, -1.0, 0.0]), "x right");
    assert!(close(level.rotate([0.0, 1.0, 0.0]), [0.0, 0.0, -1.0]), "y down");
    let (p, y) = (0.4f64, 0.7f64);
    let m = optical_mount([1.0, 2.0, 3.0], y, p);
    assert_eq!(m.translation, [1.0, 2.0, 3.0]);
    let fwd = [p.cos() * y.cos(), p.cos() * y.sin(), -p.sin()];
    assert!(close(m.rotate([0.0, 0.0, 1.0]), fwd), "{:?}", m.rotate([0.0, 0.0, 1.0]));
    assert!(close(m.rotate([1.0, 0.0, 0.0]), [y.sin(), -y.cos(), 0.0]), "x stays level");
    // As RPY: roll = -(π/2 + pitch), yaw = -π/2 + yaw for a camera pitched then turned.
    let rpy = Mount3 { roll: -(FRAC_PI_2 + p), pitch: 0.0, yaw: -FRAC_PI_2, ..Default::default() };
    let same = Pose3::new([0.0; 3], rpy.quaternion());
    assert!(optical_mount([0.0; 3], 0.0, p).angle_to(&same) < 1e-12);
}

/// A camera pitched down 0.5 rad and turned 0.3 rad, 1.2 m up, over a flat floor: the
/// depth of each pixel from an independent ray cast (the mount's rotation matrix), each
/// point on the floor where the cast says, the principal ray at 1.2 / tan 0.5 ahead.
#[test]
fn pitched_camera_over_the_floor() {
    let (pitch, yaw, h) = (0.5f64, 0.3f64, 1.2);
    let ph = Pinhole::new(40, 30, 30.0, 32.0, 19.0, 14.0).unwrap();
    let params = CameraParams { stride: 1, max_depth_m: 20.0, ..Default::default() };
    let m = model(ph, optical_mount([0.1, -0.2, h], yaw, pitch), params);
    let r = Mount3 { roll: -(FRAC_PI_2 + pitch), yaw: yaw - FRAC_PI_2, ..Default::default() }.rotation();
    let (mut depth, mut expected) = (vec![f32::NAN; 40 * 30], Vec::new());
    for v in 0..30 {
        for u in 0..40 {
            let ray = [(u as f64 - 19.0) / 30.0, (v as f64 - 14.0) / 32.0, 1.0];
            let dir: Vec<f64> = (0..3).map(|i| (0..3).map(|j| r[i][j] * ray[j]).sum()).collect();
            if dir[2] < -1e-3 {
                let t = h / -dir[2];
                depth[v * 40 + u] = t as f32;
                if (0.3..=20.0).contains(&t) {
                    expected.push((0.1 + t * dir[0], -0.2 + t * dir[1], (u, v)));
                }
            }
        }
    }
    let labels = LabelImage::new(40, 30, vec![FLOOR; 1200]).unwrap();
    let depth = DepthImage::new(40, 30, depth).unwrap();
    let pose = Pose2::new(-1.0, 0.5, -0.4);
    let (out, counts) = run(&m, &labels, &depth, pose);
    assert_eq!(out.points.len(), expected.len());
    assert!(counts.used > 600, "{counts:?}");
    for (p, (bx, by, _)) in out.points.iter().zip(&expected) {
        assert_eq!(p.band, Band::Floor);
        assert!(p.end.distance(pose * Point2::new(*bx, *by)) < 0.01);
    }
    // Pixel (19, 14), whose centre is the principal point, looks along the optical axis.
    let i = expected.iter().position(|e| e.2 == (19, 14)).unwrap();
    let ahead = h / pitch.tan();
    let want = pose * Point2::new(0.1 + ahead * yaw.cos(), -0.2 + ahead * yaw.sin());
    assert!(out.points[i].end.distance(want) < 0.01, "{:?} vs {want:?}", out.points[i].end);
}

#[test]
fn stride_takes_every_nth_pixel_of_every_nth_row() {
    let ph = pinhole(10, 7, 8.0);
    let (w, h) = (10usize, 7usize);
    let labels = LabelImage::new(10, 7, vec![WALL; w * h]).unwrap();
    // Distinct depths so each point says which pixel it came from.
    let depth = DepthImage::new(10, 7, (0..w * h).map(|i| 1.0 + i as f32 * 0.01).collect()).unwrap();
    let mount = optical_mount([0.0, 0.0, 1.0], 0.0, 0.0);
    let params = |stride| CameraParams { stride, ..Default::default() };
    let (all, c1) = run(&model(ph, mount, params(1)), &labels, &depth, Pose2::default());
    let (some, c4) = run(&model(ph, mount, params(4)), &labels, &depth, Pose2::default());
    assert_eq!(c1.seen, 70);
    assert_eq!(c4.seen, 3 * 2, "columns 0, 4, 8 of rows 0, 4");
    let picked: Vec<CameraPoint> =
        all.points.iter().enumerate().filter(|(i, _)| i % w % 4 == 0 && i / w % 4 == 0).map(|(_, p)| *p).collect();
    assert_eq!(c1.used, 70, "{c1:?}");
    assert_eq!(some.points, picked);
}

/// Every counter, from a 3×3 camera (rays at ±0.5 and 0 in x and y), level at 1 m.
#[test]
fn every_pixel_counter() {
    let ph = Pinhole::new(3, 3, 2.0, 2.0, 1.0, 1.0).unwrap();
    let params = CameraParams { stride: 1, ..Default::default() };
    let m = model(ph, optical_mount([0.0, 0.0, 1.0], 0.0, 0.0), params);
    let labels = LabelImage::new(3, 3, vec![99, 0, WALL, WALL, WALL, WALL, FLOOR, FLOOR, WALL]).unwrap();
    // Row 0 looks up (z = 1 + d/2), row 1 level, row 2 down (z = 1 - d/2).
    let depth = DepthImage::new(3, 3, vec![1.0, 1.0, 5.0, f32::NAN, 0.0, 10.0, 5.0, 2.0, 0.1]).unwrap();
    let (out, c) = run(&m, &labels, &depth, Pose2::default());
    let want = PixelCounts {
        seen: 9,
        used: 1,
        unknown_class: 1,
        ignored_class: 1,
        no_depth: 2,
        out_of_depth_range: 2,
        above_band: 1,
        below_floor: 1,
    };
    assert_eq!(c, want);
    assert_eq!(c.used + c.skipped(), c.seen);
    assert_eq!(out.points.len(), 1);
    assert_eq!(out.points[0].band, Band::Floor);
    assert!(out.points[0].end.distance(Point2::new(2.0, 0.0)) < 1e-9);
    // -1 and ±inf are no depth too; a reused buffer and summed counts.
    let depth =
        DepthImage::new(3, 3, vec![1.0, 1.0, f32::INFINITY, -1.0, f32::NEG_INFINITY, 1.0, 1.0, 2.0, 1.0]).unwrap();
    let mut out = out;
    let mut sum = c;
    m.project(&labels, &depth, Pose2::default(), &mut out, &mut sum).unwrap();
    assert_eq!(sum.seen, 18);
    assert_eq!(sum.no_depth, 2 + 3);
    assert_eq!(sum.used + sum.skipped(), sum.seen);
    assert_eq!(out.points.len() as u64, sum.used - c.used, "the buffer is cleared, not appended to");
    let mut twice = want;
    twice.add(&want);
    assert_eq!(twice.seen, 18);
    assert_eq!(twice.below_floor, 2);
}

#[test]
fn sizes_must_agree() {
    let ph = pinhole(4, 3, 4.0);
    let m = model(ph, optical_mount([0.0, 0.0, 1.0], 0.0, 0.0), CameraParams::default());
    let mut out = CameraObservation::empty(SensorId(0));
    let mut c = PixelCounts::default();
    let l43 = LabelImage::new(4, 3, vec![WALL; 12]).unwrap();
    let d44 = DepthImage::new(4, 4, vec![1.0; 16]).unwrap();
    let e = m.project(&l43, &d44, Pose2::default(), &mut out, &mut c).unwrap_err();
    assert_eq!(e, CameraError::ImageSize { labels: (4, 3), depth: (4, 4), camera: (4, 3) });
    let msg = e.to_string();
    assert!(
        msg.contains("labels 4×3") && msg.contains("depth 4×4") && msg.contains("camera (CameraInfo) 4×3"),
        "{msg}"
    );
    // Both images agree with each other but not with the camera.
    let l = LabelImage::new(3, 4, vec![WALL; 12]).unwrap();
    let d = DepthImage::new(3, 4, vec![1.0; 12]).unwrap();
    assert!(m.project(&l, &d, Pose2::default(), &mut out, &mut c).is_err());
    // Public fields let a buffer disagree with its size: an error, not a panic.
    let short = LabelImage { width: 4, height: 3, labels: vec![WALL; 5] };
    let d43 = DepthImage::new(4, 3, vec![1.0; 12]).unwrap();
    assert!(m.project(&short, &d43, Pose2::default(), &mut out, &mut c).is_err());
    let e = m.project(&l43, &d43, Pose2::new(f64::NAN, 0.0, 0.0), &mut out, &mut c).unwrap_err();
    assert!(matches!(e, CameraError::Pose { .. }), "{e}");
    assert_eq!(c, PixelCounts::default(), "nothing counted from a refused frame");
    assert!(m.project(&l43, &d43, Pose2::default(), &mut out, &mut c).is_ok());
}

#[test]
fn camera_info_refusals() {
    let k = [500.0, 0.0, 320.0, 0.0, 510.0, 240.0, 0.0, 0.0, 1.0];
    let p = Pinhole::from_camera_info(640, 480, k, "plumb_bob", &[0.0; 5]).unwrap();
    assert_eq!((p.fx, p.fy, p.cx, p.cy, p.width, p.height), (500.0, 510.0, 320.0, 240.0, 640, 480));
    for model in ["", "none", "plumb_bob", "rational_polynomial", "equidistant"] {
        assert!(Pinhole::from_camera_info(640, 480, k, model, &[0.0; 8]).is_ok(), "{model}");
        assert!(Pinhole::from_camera_info(640, 480, k, model, &[]).is_ok(), "{model}");
    }
    let e = Pinhole::from_camera_info(640, 480, k, "plumb_bob", &[0.1, 0.0, 0.0, 0.0, 0.0]).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("plumb_bob") && msg.contains("0.1") && msg.contains("rectified"), "{msg}");
    assert!(msg.contains("does not undistort"), "{msg}");
    let e = Pinhole::from_camera_info(640, 480, k, "equidistant", &[0.0, f64::NAN]).unwrap_err();
    assert!(matches!(e, CameraError::Distorted { .. }), "{e}");
    let e = Pinhole::from_camera_info(640, 480, k, "kannala_brandt", &[]).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("`kannala_brandt`") && msg.contains("rectified"), "{msg}");
    let skewed = [500.0, 1.5, 320.0, 0.0, 510.0, 240.0, 0.0, 0.0, 1.0];
    assert_eq!(Pinhole::from_camera_info(640, 480, skewed, "", &[]), Err(CameraError::Skew { skew: 1.5 }));
    let e = Pinhole::from_camera_info(640, 480, [0.0; 9], "", &[]).unwrap_err();
    assert!(e.to_string().contains("K[8]") || e.to_string().contains("entries"), "{e}");
    let uncalibrated = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    let e = Pinhole::from_camera_info(640, 480, uncalibrated, "", &[]).unwrap_err();
    assert!(e.to_string().contains("fx") && e.to_string().contains("uncalibrated"), "{e}");
    let nan_fy = [500.0, 0.0, 320.0, 0.0, f64::NAN, 240.0, 0.0, 0.0, 1.0];
    assert!(Pinhole::from_camera_info(640, 480, nan_fy, "", &[]).unwrap_err().to_string().contains("fy"));
    let nan_cx = [500.0, 0.0, f64::INFINITY, 0.0, 510.0, 240.0, 0.0, 0.0, 1.0];
    assert!(Pinhole::from_camera_info(640, 480, nan_cx, "", &[]).unwrap_err().to_string().contains("cx"));
    assert_eq!(Pinhole::from_camera_info(0, 480, k, "", &[]), Err(CameraError::EmptyImage { width: 0, height: 480 }));
    let e = Pinhole::from_camera_info(10_000, 10_000, k, "", &[]).unwrap_err();
    assert!(e.to_string().contains("MAX_CAMERA_PIXELS"), "{e}");
    assert!(Pinhole::from_camera_info(10_000, 5_000, k, "", &[]).is_ok(), "exactly MAX_CAMERA_PIXELS");
    // A rectified stream's intrinsics from P.
    let proj = [480.0, 0.0, 321.0, 0.0, 0.0, 490.0, 239.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let p = Pinhole::from_projection(640, 480, proj).unwrap();
    assert_eq!((p.fx, p.fy, p.cx, p.cy), (480.0, 490.0, 321.0, 239.0));
    let mut right = proj;
    right[3] = -48.0;
    assert!(Pinhole::from_projection(640, 480, right).unwrap_err().to_string().contains("Tx"));
}

#[test]
fn erf_matches_tabulated_values() {
    // Abramowitz & Stegun Table 7.1.
    for (x, want) in [
        (0.0, 0.0),
        (0.1, 0.112_462_916_0),
        (0.3, 0.328_626_759_5),
        (0.5, 0.520_499_877_8),
        (0.7, 0.677_801_193_8),
        (1.0, 0.842_700_792_9),
        (1.5, 0.966_105_146_5),
        (2.0, 0.995_322_265_0),
        (3.0, 0.999_977_909_5),
    ] {
        assert!((erf(x) - want).abs() < 2e-7, "erf({x}) = {} not {want}", erf(x));
        assert!((erf(-x) + want).abs() < 2e-7);
    }
    assert_eq!(erf(10.0), 1.0);
    // The cell spans ±1σ: the one-sigma mass.
    assert!((depth_weight(0.1, 0.05) - 0.682_689_492).abs() < 2e-7);
    assert_eq!(depth_weight(0.05, 0.0), 1.0);
    assert!(depth_weight(0.05, 1e300) > 0.0);
}

#[test]
fn weight_falls_with_depth() {
    let m = model(pinhole(4, 4, 4.0), optical_mount([0.0; 3], 0.0, 0.0), CameraParams::default());
    let weights: Vec<f32> = (1..=60).map(|i| m.point_weight(i as f64 * 0.1)).collect();
    assert!(weights[0] > 0.999, "10 cm away: σ = 50 µm");
    assert!(weights.windows(2).all(|w| w[1] <= w[0]), "{weights:?}");
    assert!(weights.windows(2).skip(20).all(|w| w[1] < w[0]), "strictly beyond 2 m");
    // 6 m, k = 0.005: σ = 0.18 m; a 5 cm cell holds erf(0.05 / (2√2 · 0.18)) of it.
    let w6 = weights[59] as f64;
    assert!((w6 - erf(0.05 / (2.0 * 2f64.sqrt() * 0.18))).abs() < 1e-6 && w6 < 0.15 && w6 > 0.05, "{w6}");
    assert!(weights.iter().all(|w| *w > 0.0 && *w <= 1.0));
    // Exact depth: every point weighs 1.
    let exact = CameraParams { depth_sigma_k: 0.0, ..Default::default() };
    let m = model(pinhole(4, 4, 4.0), optical_mount([0.0; 3], 0.0, 0.0), exact);
    assert_eq!(m.point_weight(6.0), 1.0);
}

#[test]
fn evidence_rule_geometry_signs_class_strengths() {
    let m = model(pinhole(4, 4, 4.0), optical_mount([0.0; 3], 0.0, 0.0), CameraParams::default());
    let t = ClassTable::production_default();
    let at = |name: &str, band| CameraPoint {
        end: Point2::new(0.0, 0.0),
        class: t.index_by_name(name).unwrap(),
        weight: 0.8,
        band,
        height: 0.5,
    };
    let close = |a: Option<(f64, f32)>, b: (f64, f32)| a.is_some_and(|a| a.0 == b.0 && (a.1 - b.1).abs() < 1e-6);
    // Floor band: free whatever the label; a floor label at its own strength.
    assert!(close(m.occupancy_evidence(&at("floor", Band::Floor), &t), (0.2, 0.8 * 0.5)));
    assert!(close(m.occupancy_evidence(&at("wall", Band::Floor), &t), (0.45, 0.8 * 0.5)), "backlit shadow");
    // Obstacle band: occupied at the class's strength.
    assert!(close(m.occupancy_evidence(&at("glass", Band::Obstacle), &t), (0.7, 0.8 * 0.5)));
    assert_eq!(m.occupancy_evidence(&at("floor", Band::Obstacle), &t), None, "no free evidence at obstacle height");
    // Dynamic and ignored classes never write static occupancy.
    assert_eq!(m.occupancy_evidence(&at("person", Band::Obstacle), &t), None);
    assert_eq!(m.occupancy_evidence(&at("person", Band::Floor), &t), None);
    assert_eq!(m.occupancy_evidence(&at("ceiling", Band::Obstacle), &t), None);
    let stray = CameraPoint { class: 200, ..at("wall", Band::Obstacle) };
    assert_eq!(m.occupancy_evidence(&stray, &t), None);
    assert_eq!(m.semantic_weight(&stray, &t), 0.0);
    // Semantic weight: full when label and band agree, reduced when they contradict.
    assert!((m.semantic_weight(&at("wall", Band::Obstacle), &t) - 0.8).abs() < 1e-6);
    assert!((m.semantic_weight(&at("floor", Band::Floor), &t) - 0.8).abs() < 1e-6);
    assert!((m.semantic_weight(&at("wall", Band::Floor), &t) - 0.8 * 0.2).abs() < 1e-6);
    assert!((m.semantic_weight(&at("floor", Band::Obstacle), &t) - 0.8 * 0.2).abs() < 1e-6);
    assert!((m.semantic_weight(&at("person", Band::Obstacle), &t) - 0.8 * 0.5).abs() < 1e-6, "p = 0.5 is neutral");
    assert_eq!(m.semantic_weight(&at("unlabeled", Band::Floor), &t), 0.0);
    // A class of weight 0.5 scales occupancy too, and occupancy_weight scales everything.
    let mut spec = t.as_slice().to_vec();
    spec[2].weight = 0.5;
    let t2 = ClassTable::new(spec).unwrap();
    let half = CameraParams { occupancy_weight: 0.25, ..Default::default() };
    let m2 = model(pinhole(4, 4, 4.0), optical_mount([0.0; 3], 0.0, 0.0), half);
    assert!(close(m2.occupancy_evidence(&at("wall", Band::Obstacle), &t2), (0.7, 0.5 * 0.8 * 0.25)));
    assert!(close(m2.occupancy_evidence(&at("wall", Band::Floor), &t2), (0.45, 0.8 * 0.25)));
}

#[test]
fn bad_parameters_are_named() {
    let ph = pinhole(4, 4, 4.0);
    let mount = optical_mount([0.0; 3], 0.0, 0.0);
    let name = |p: CameraParams| match CameraModel::new(ph, mount, p, 0.05, ClassTable::production_default()) {
        Err(CameraError::Parameter { name, .. }) => name,
        other => panic!("{other:?}"),
    };
    let d = CameraParams::default();
    assert_eq!(name(CameraParams { stride: 0, ..d }), "stride");
    assert_eq!(name(CameraParams { stride: 65, ..d }), "stride");
    assert_eq!(name(CameraParams { min_depth_m: -1.0, ..d }), "min_depth_m");
    assert_eq!(name(CameraParams { max_depth_m: 0.2, ..d }), "max_depth_m");
    assert_eq!(name(CameraParams { max_depth_m: f64::INFINITY, ..d }), "max_depth_m");
    assert_eq!(name(CameraParams { depth_sigma_k: -0.1, ..d }), "depth_sigma_k");
    assert_eq!(name(CameraParams { floor_band_m: 0.0, ..d }), "floor_band_m");
    assert_eq!(name(CameraParams { obstacle_max_z_m: 0.05, ..d }), "obstacle_max_z_m");
    assert_eq!(name(CameraParams { p_free: 0.5, ..d }), "p_free");
    assert_eq!(name(CameraParams { occupancy_weight: 1.5, ..d }), "occupancy_weight");
    assert_eq!(name(CameraParams { inconsistent_label_weight: f64::NAN, ..d }), "inconsistent_label_weight");
    let e = CameraModel::new(ph, mount, d, 0.0, ClassTable::production_default()).unwrap_err();
    assert!(e.to_string().contains("cell_size_m"), "{e}");
    let broken = Pose3 { translation: [f64::NAN, 0.0, 0.0], ..mount };
    assert!(matches!(
        CameraModel::new(ph, broken, d, 0.05, ClassTable::production_default()),
        Err(CameraError::Mount { .. })
    ));
    // A non-unit quaternion is normalised, not a scaled rotation.
    let scaled = Pose3 { rotation: mount.rotation.map(|q| 3.0 * q), ..mount };
    let m = CameraModel::new(ph, scaled, d, 0.05, ClassTable::production_default()).unwrap();
    assert!(m.base_from_optical().angle_to(&mount) < 1e-12);
}

proptest! {
    /// A point in front of the camera, projected to a pixel, back-projected through that
    /// pixel's centre (at its integer coordinates) at its own depth and projected again, lands in the same pixel.
    #[test]
    fn reprojection_hits_the_same_pixel(
        f in (50.0..1500.0f64, 0.8..1.25f64),
        c in (0.0..1.0f64, 0.0..1.0f64),
        p in (-3.0..3.0f64, -3.0..3.0f64, 0.2..20.0f64),
    ) {
        let (w, h) = (640u32, 480u32);
        let ph = Pinhole::new(w, h, f.0, f.0 * f.1, c.0 * w as f64, c.1 * h as f64).unwrap();
        let Some((u, v)) = ph.project([p.0, p.1, p.2]) else { unreachable!("z > 0") };
        prop_assume!(u >= -0.5 && v >= -0.5 && u < w as f64 - 0.5 && v < h as f64 - 0.5);
        // Pixel centres at integer coordinates: the pixel is the nearest integer.
        let (pu, pv) = (u.round(), v.round());
        let r = ph.ray(pu, pv);
        let back = r.map(|x| x * p.2);
        let (u2, v2) = ph.project(back).unwrap();
        prop_assert_eq!((u2.round(), v2.round()), (pu, pv));
        prop_assert!((u2 - pu).abs() < 1e-9 && (v2 - pv).abs() < 1e-9);
        prop_assert!(ph.project([p.0, p.1, -p.2]).is_none());
    }
}
