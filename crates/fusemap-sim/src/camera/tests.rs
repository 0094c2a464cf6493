//! Camera tests: analytic depths of a wall and of the floor, glass, the backlight, the
//! person, determinism and stamps.

use super::*;
use crate::world::{Material, Shape};
use crate::{simulate, Scenario};

/// A camera without noise or backlight, `w × h`, pitched down `pitch_deg`.
fn exact(w: u32, h: u32, pitch_deg: f64) -> CameraConfig {
    let mut c =
        CameraConfig { width: w, height: h, depth_sigma_k: 0.0, label_noise_probability: 0.0, ..Default::default() };
    c.mount.pitch = pitch_deg.to_radians();
    c.backlight.enabled = false;
    c
}

fn segment(name: &str, class: &str, material: Material, height_m: f64, a: [f64; 2], b: [f64; 2]) -> WorldObject {
    WorldObject {
        name: name.into(),
        class: class.into(),
        material,
        height_m,
        shape: Shape::Segment { a, b, thickness_m: 0.0 },
    }
}

fn render(cfg: &CameraConfig, objects: &[WorldObject], pose: Pose2, person: Option<(Point2, f64, f64)>) -> NoisyFrame {
    let caster = Caster::new(objects);
    let mut sim = CameraSim::new(cfg, objects, &caster, 1);
    let mut f = NoisyFrame::default();
    sim.frame(0.0, pose, person, &mut f);
    f
}

#[test]
fn centre_pixel_looks_forward_and_down_along_the_mount() {
    let cfg = CameraConfig { width: 321, height: 241, ..CameraConfig::default() };
    let caster = Caster::new(&[]);
    let r = render::Renderer::new(&cfg, &[], &caster);
    let centre = 120 * 321 + 160;
    let d = r.ray_in_map(Pose2::IDENTITY, centre);
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let p = cfg.mount.pitch;
    assert!(
        (d[0] / n - p.cos()).abs() < 1e-12 && (d[1] / n).abs() < 1e-12 && (d[2] / n + p.sin()).abs() < 1e-12,
        "{d:?}"
    );
    // The rightmost column looks right (−y), the top row up relative to the centre.
    let right = r.ray_in_map(Pose2::IDENTITY, 120 * 321 + 320);
    assert!(right[1] < -0.5);
    let top = r.ray_in_map(Pose2::IDENTITY, 160);
    assert!(top[2] / top[0] > d[2] / d[0]);
    // The robot's heading turns the ray, not its height.
    let turned = r.ray_in_map(Pose2::new(0.0, 0.0, std::f64::consts::FRAC_PI_2), centre);
    assert!((turned[1] - d[0]).abs() < 1e-12 && turned[0].abs() < 1e-12 && turned[2] == d[2]);
    let c = r.centre_in_map(Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2));
    assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 2.25).abs() < 1e-12 && (c[2] - 1.0).abs() < 1e-12);
}

#[test]
fn a_wall_ahead_has_its_class_and_the_plane_depth() {
    let (w, h) = (160, 120);
    let cfg = exact(w, h, 0.0);
    let objects = [segment("wall", "wall", Material::Wall, 4.0, [5.0, -20.0], [5.0, 20.0])];
    let f = render(&cfg, &objects, Pose2::IDENTITY, None);
    let k = cfg.k_matrix();
    let (fy, cy) = (k[4], k[5]);
    // A level camera 0.25 m ahead of the base, 1 m up: every wall pixel has depth
    // 5 − 0.25 along the optical axis (a fronto-parallel plane); the wall meets the floor
    // where the ray drops 1 m over 4.75 m.
    let boundary = cy + fy / 4.75;
    let (mut walls, mut floors) = (0, 0);
    for v in 0..h as usize {
        for u in 0..w as usize {
            let i = v * w as usize + u;
            if (v as f64) < boundary - 1.0 {
                assert_eq!(f.labels[i], CLASS_WALL, "pixel ({u}, {v})");
                assert!((f.depth[i] - 4.75).abs() < 1e-4, "pixel ({u}, {v}): {}", f.depth[i]);
                walls += 1;
            } else if (v as f64) > boundary + 1.0 {
                assert_eq!(f.labels[i], CLASS_FLOOR, "pixel ({u}, {v})");
                let expected = fy / (v as f64 - cy);
                assert!((f64::from(f.depth[i]) - expected).abs() < 1e-4, "pixel ({u}, {v})");
                floors += 1;
            }
        }
    }
    assert!(walls > 0 && floors > 0);
    // Facing away, the same wall is not seen: floor below, ceiling above the horizon.
    let f = render(&cfg, &objects, Pose2::new(0.0, 0.0, std::f64::consts::PI), None);
    assert!(!f.labels.contains(&CLASS_WALL));
    assert_eq!(f.labels[0], CLASS_CEILING);
    assert!(f.depth[0].is_nan());
}

#[test]
fn the_floor_of_a_pitched_camera_is_at_the_analytic_depth() {
    let (w, h) = (81, 61);
    let cfg = CameraConfig { max_depth_m: 100.0, ..exact(w, h, 25.0) };
    let f = render(&cfg, &[], Pose2::new(3.0, -2.0, 0.7), None);
    let k = cfg.k_matrix();
    let (fy, cy) = (k[4], k[5]);
    let p = 25f64.to_radians();
    for v in 0..h as usize {
        // Optical ray (a, b, 1) drops sin p + b cos p per unit depth: the floor 1 m below
        // is at depth 1 / (sin p + b cos p), the same along a row.
        let b = (v as f64 - cy) / fy;
        let drop = p.sin() + b * p.cos();
        for u in 0..w as usize {
            let i = v * w as usize + u;
            if drop > 1e-9 {
                assert_eq!(f.labels[i], CLASS_FLOOR);
                assert!((f64::from(f.depth[i]) - 1.0 / drop).abs() < 1e-4 / drop, "({u}, {v})");
            } else {
                assert_eq!(f.labels[i], CLASS_CEILING);
            }
        }
    }
    // Beyond max_depth the floor keeps its label and loses its depth.
    let near = CameraConfig { max_depth_m: 2.0, ..cfg.clone() };
    let g = render(&near, &[], Pose2::IDENTITY, None);
    let far = (0..g.labels.len()).filter(|&i| f64::from(f.depth[i]) > 2.0).collect::<Vec<_>>();
    assert!(!far.is_empty());
    assert!(far.iter().all(|&i| g.labels[i] == CLASS_FLOOR && g.depth[i].is_nan()));
}

#[test]
fn glass_is_labelled_glass_and_returns_its_depth_or_what_lies_behind() {
    let cfg = exact(80, 60, 0.0);
    let objects = [
        segment("fence", "glass", Material::Glass, 2.0, [3.0, -20.0], [3.0, 20.0]),
        segment("wall", "wall", Material::Wall, 4.0, [6.0, -20.0], [6.0, 20.0]),
    ];
    let f = render(&cfg, &objects, Pose2::IDENTITY, None);
    let (mut own, mut behind, mut glass) = (0, 0, 0);
    for (i, &l) in f.labels.iter().enumerate() {
        if l == CLASS_GLASS {
            glass += 1;
            let d = f.depth[i];
            if (d - 2.75).abs() < 1e-4 {
                own += 1;
            } else {
                assert!(d > 2.75 + 1e-3, "transmitted depth {d} lies behind the glass");
                behind += 1;
            }
        }
    }
    // The fence's top at 2 m is 1 m above the camera, 2.75 m ahead: rows above see the wall.
    let (fy, cy) = (cfg.k_matrix()[4], cfg.k_matrix()[5]);
    let top_row = (cy - fy / 2.75).floor() as usize;
    assert_eq!(f.labels[(top_row - 1) * 80 + 40], CLASS_WALL);
    assert_eq!(f.labels[(top_row + 2) * 80 + 40], CLASS_GLASS);
    let share = f64::from(own) / f64::from(glass);
    assert!(glass > 1000 && (share - 0.5).abs() < 0.05, "{own} own of {glass} ({behind} behind)");
}

#[test]
fn backlight_mislabels_only_floor_pixels_and_only_facing_the_window() {
    let mut cfg = exact(160, 120, 25.0);
    cfg.backlight.enabled = true;
    let objects = crate::production_hall_objects();
    let caster = Caster::new(&objects);
    let mut sim = CameraSim::new(&cfg, &objects, &caster, 3);
    let mut f = NoisyFrame::default();
    let mut previous: Option<Vec<usize>> = None;
    for k in 0..5 {
        sim.frame(10.0 + 0.1 * f64::from(k), Pose2::new(5.0, 3.0, 0.1), None, &mut f);
        assert!(f.facing_window);
        let floor = f.truth.floor.iter().filter(|&&x| x).count();
        assert_eq!(f.backlit.len(), (0.25 * floor as f64).round() as usize);
        for &i in &f.backlit {
            assert!(f.truth.floor[i] && f.truth.labels[i] == CLASS_FLOOR && f.labels[i] == CLASS_WALL);
            let same = f.depth[i] == f.truth.depth[i] || (f.truth.depth[i] > 8.0 && f.depth[i].is_nan());
            assert!(same, "the depth stays the floor's: {} vs {}", f.depth[i], f.truth.depth[i]);
        }
        // Blobs, not salt: most backlit pixels have a backlit right-hand neighbour.
        let set: std::collections::HashSet<usize> = f.backlit.iter().copied().collect();
        let joined = f.backlit.iter().filter(|&&i| set.contains(&(i + 1))).count();
        assert!(joined as f64 > 0.9 * f.backlit.len() as f64, "{joined} of {}", f.backlit.len());
        // Smooth in time: 0.1 s later most of the blobs are where they were.
        if let Some(prev) = &previous {
            let kept = prev.iter().filter(|i| set.contains(i)).count();
            assert!(kept as f64 > 0.8 * prev.len() as f64, "{kept} of {}", prev.len());
        }
        previous = Some(f.backlit.clone());
    }
    for yaw in [70f64, 180.0, -90.0] {
        sim.frame(10.0, Pose2::new(15.0, 7.0, yaw.to_radians()), None, &mut f);
        assert!(!f.facing_window && f.backlit.is_empty(), "yaw {yaw}");
        assert_eq!(f.labels, f.truth.labels, "yaw {yaw}");
    }
}

#[test]
fn a_person_in_view_is_labelled_at_its_depth() {
    let cfg = exact(80, 60, 0.0);
    let person = Some((Point2::new(4.0, 0.0), 0.25, 1.7));
    let f = render(&cfg, &[], Pose2::IDENTITY, person);
    let centre = 30 * 80 + 40;
    assert_eq!(f.labels[centre], CLASS_PERSON);
    // The cylinder's front is 4 − 0.25 − 0.25 m ahead of the optical centre.
    assert!((f.depth[centre] - 3.5).abs() < 0.01, "{}", f.depth[centre]);
    // Its top is 0.7 m above the camera: the top row (0.3 m higher at 3.5 m) sees over it.
    assert_ne!(f.labels[40], CLASS_PERSON);
    let behind = render(&cfg, &[], Pose2::new(0.0, 0.0, std::f64::consts::PI), person);
    assert!(!behind.labels.contains(&CLASS_PERSON));
}

#[test]
fn noise_and_encodings() {
    let mut cfg = exact(80, 60, 25.0);
    cfg.label_noise_probability = 0.05;
    cfg.depth_sigma_k = 0.01;
    let f = render(&cfg, &[], Pose2::IDENTITY, None);
    let wrong = f.labels.iter().zip(&f.truth.labels).filter(|(a, b)| a != b).count();
    // 5 % salted, of which 5/6 land on another class: 200 expected of 4800.
    assert!((100..=300).contains(&wrong), "{wrong}");
    assert!(f.labels.iter().all(|&l| l <= 7));
    // Normalised depth errors have unit variance (σ = k d²).
    let z: Vec<f64> = f
        .depth
        .iter()
        .zip(&f.truth.depth)
        .filter(|(_, t)| t.is_finite() && **t <= 8.0)
        .map(|(d, t)| (f64::from(*d) - f64::from(*t)) / (0.01 * f64::from(*t).powi(2)))
        .collect();
    let var = z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64;
    assert!((var - 1.0).abs() < 0.1, "{var} over {}", z.len());
    assert_eq!(encode_labels(&[1, 7, 300], LabelEncoding::Mono8), vec![1, 7, 255]);
    assert_eq!(encode_labels(&[1, 300], LabelEncoding::Mono16), vec![1, 0, 44, 1]);
    assert_eq!(
        encode_depth(&[1.5, f32::NAN, 70.0, -1.0], DepthEncoding::U16Millimetres),
        vec![220, 5, 0, 0, 255, 255, 0, 0]
    );
    assert_eq!(encode_depth(&[1.5], DepthEncoding::Float32Metres), 1.5f32.to_le_bytes().to_vec());
}

/// A short run with a small camera (debug builds render slowly).
fn small(duration_s: f64) -> Scenario {
    let mut s = Scenario::default();
    s.robot.duration_s = duration_s;
    s.camera.width = 96;
    s.camera.height = 72;
    s
}

fn images<'a>(run: &'a crate::SimRecording, topic: &'a str) -> impl Iterator<Item = &'a SimImage> + 'a {
    run.messages.iter().filter_map(move |m| match m {
        SimMessage::Image(i) if i.topic == topic => Some(i),
        _ => None,
    })
}

#[test]
fn same_seed_same_images_and_stamps_carry_the_offset() {
    let mut s = small(3.0);
    s.camera.time_offset_s = 0.03;
    let a = simulate(&s).unwrap();
    let b = simulate(&s).unwrap();
    let la: Vec<_> = images(&a, "/camera/labels").collect();
    assert_eq!(la.len(), 31);
    assert_eq!(la, images(&b, "/camera/labels").collect::<Vec<_>>());
    assert_eq!(
        format!("{:?}", images(&a, "/camera/depth").collect::<Vec<_>>()),
        format!("{:?}", images(&b, "/camera/depth").collect::<Vec<_>>())
    );
    for (img, (truth, stamp)) in la.iter().zip(&a.camera_truth.stamps) {
        assert_eq!(img.header.stamp, *stamp);
        assert_eq!(stamp.0 - truth.0, 30_000_000);
        assert_eq!((img.encoding.as_str(), img.step, img.data.len()), ("mono8", 96, 96 * 72));
    }
    let info = a.messages.iter().find_map(|m| if let SimMessage::CameraInfo(c) = m { Some(c) } else { None }).unwrap();
    assert_eq!(
        (info.header.stamp, info.distortion_model.as_str(), info.d.as_slice()),
        (la[0].header.stamp, "plumb_bob", &[0.0; 5][..])
    );
    let tf = a.messages.iter().find_map(|m| match m {
        SimMessage::StaticTransform(t) if t.child_frame_id == "camera_optical" => Some(t),
        _ => None,
    });
    assert_eq!(tf.unwrap().header.frame_id, "base_link");
    s.world.seed += 1;
    let c = simulate(&s).unwrap();
    assert_ne!(la, images(&c, "/camera/labels").collect::<Vec<_>>());
    // Depth as 16UC1 millimetres, labels as mono16.
    s.camera.depth_encoding = DepthEncoding::U16Millimetres;
    s.camera.label_encoding = LabelEncoding::Mono16;
    let d = simulate(&s).unwrap();
    let depth = images(&d, "/camera/depth").next().unwrap();
    assert_eq!((depth.encoding.as_str(), depth.step), ("16UC1", 192));
    assert_eq!(images(&d, "/camera/labels").next().unwrap().encoding, "mono16");
}

#[test]
fn the_fast_blob_field_is_the_value_noise() {
    let mut f = render::BlobField::new(50, 40, 12.5);
    for t in [0.0, 0.3, 7.9] {
        f.field_at(99, t);
        for (u, v) in [(0, 0), (13, 7), (49, 39), (25, 20)] {
            let slow = render::value_noise(99, u as f64 / 12.5, v as f64 / 12.5, t);
            assert!((f64::from(f.value(u, v)) - slow).abs() < 1e-5, "({u}, {v}, {t})");
            assert!((0.0..1.0).contains(&slow));
        }
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Any pitch, height and pose: a pixel whose ray drops reaches the floor at depth
        /// `z / (sin p + b cos p)` (`b` its normalised image row), and its map point lies on
        /// the ray from the optical centre.
        #[test]
        fn floor_depth_for_any_pitch_and_height(
            pitch in 5.0..60.0f64, z in 0.3..2.0f64, x in -5.0..5.0f64, y in -5.0..5.0f64, yaw in -3.1..3.1f64,
        ) {
            let mut cfg = exact(21, 15, pitch);
            cfg.mount.z = z;
            cfg.max_depth_m = 1e6;
            let f = render(&cfg, &[], Pose2::new(x, y, yaw), None);
            let k = cfg.k_matrix();
            let p = pitch.to_radians();
            for v in 0..15usize {
                let drop = p.sin() + (v as f64 - k[5]) / k[4] * p.cos();
                for u in 0..21usize {
                    let i = v * 21 + u;
                    if drop > 1e-3 {
                        prop_assert_eq!(f.labels[i], CLASS_FLOOR);
                        let want = z / drop;
                        prop_assert!((f64::from(f.depth[i]) - want).abs() < 1e-5 * want.max(1.0));
                    } else if drop < -1e-9 {
                        prop_assert_eq!(f.labels[i], CLASS_CEILING);
                    }
                }
            }
        }
    }
}

#[test]
fn bottom_k_keeps_the_smallest_keys() {
    let mut rng = SplitMix64::new(5);
    let all: Vec<(u64, Point2)> = (0..1000).map(|i| (rng.next_u64(), Point2::new(f64::from(i), 0.0))).collect();
    let mut keys: Vec<u64> = all.iter().map(|a| a.0).collect();
    keys.sort_unstable();
    // Fed in pieces, as the threads and the per-frame pruning do.
    let mut kept = Vec::new();
    for piece in all.chunks(37) {
        kept.extend_from_slice(piece);
        bottom_k(&mut kept, 100);
    }
    let threshold = bottom_k(&mut kept, 100);
    let mut got: Vec<u64> = kept.iter().map(|k| k.0).collect();
    got.sort_unstable();
    assert_eq!(got, keys[..100]);
    assert_eq!(threshold, keys[99]);
    assert_eq!(bottom_k(&mut vec![(3, Point2::default())], 100), u64::MAX);
}

/// The simulator's pixels and fusemap's camera model share one convention (`CameraInfo`'s:
/// pixel centres at integer coordinates, `cx = (w − 1) / 2` for a centred camera): a
/// pitched camera's points of an oblique wall, projected by the core model from the
/// recorded `K` and mount, lie on the wall to the micrometre. Centres at `u + 0.5`, as the
/// model once took them, put them 4 mm off on average here.
#[test]
fn the_core_camera_model_puts_the_rendered_wall_on_the_wall() {
    use fusemap_core::sensor::camera::{
        CameraModel, CameraObservation, CameraParams, ClassTable, DepthImage, LabelImage, Pinhole, PixelCounts,
    };
    let cfg = exact(320, 240, 25.0);
    let (a, b) = ([4.0, -3.0], [2.0, 3.0]);
    let objects = [segment("wall", "wall", Material::Wall, 4.0, a, b)];
    let pose = Pose2::new(0.3, -0.2, 0.1);
    let f = render(&cfg, &objects, pose, None);
    let k = cfg.k_matrix();
    let pinhole = Pinhole::new(cfg.width, cfg.height, k[0], k[4], k[2], k[5]).unwrap();
    let params = CameraParams { stride: 1, max_depth_m: 20.0, depth_sigma_k: 0.0, ..Default::default() };
    let model =
        CameraModel::new(pinhole, cfg.base_from_optical(), params, 0.05, ClassTable::production_default()).unwrap();
    let labels = LabelImage::new(cfg.width, cfg.height, f.labels.clone()).unwrap();
    let depth = DepthImage::new(cfg.width, cfg.height, f.depth.clone()).unwrap();
    let (mut out, mut counts) =
        (CameraObservation::empty(fusemap_core::measurement::SensorId(0)), PixelCounts::default());
    model.project(&labels, &depth, pose, &mut out, &mut counts).unwrap();
    let wall = model.classes().iter().position(|c| c.id == CLASS_WALL).unwrap();
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let n = (ex * ex + ey * ey).sqrt();
    let on_wall: Vec<f64> = (out.points.iter().filter(|p| usize::from(p.class) == wall))
        .map(|p| ((p.end.x - a[0]) * ey - (p.end.y - a[1]) * ex) / n)
        .collect();
    assert!(on_wall.len() > 10_000, "{} wall points", on_wall.len());
    let worst = on_wall.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    assert!(worst < 1e-5, "a wall point {worst} m off the wall");
}
