//! Whole-run tests: counts and rates, order, determinism, clearance, each failure mode
//! measured from the output, and the baselines an estimator must beat.
//! `cargo test -p fusemap-core production -- --nocapture` prints the figures.

use super::*;
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellIndex, GridGeometry};
use fusemap_io::log::ros2::msgs::sensor_msgs::{NavSatFix, NavSatStatus};
use std::sync::OnceLock;

fn default_run() -> &'static SimRecording {
    static RUN: OnceLock<SimRecording> = OnceLock::new();
    RUN.get_or_init(|| simulate(&Scenario::default()).expect("the default scenario is valid"))
}

/// A scenario without random errors, to compare outputs with exact truth.
fn clean(duration_s: f64) -> Scenario {
    let mut s = Scenario::default();
    s.robot.duration_s = duration_s;
    s.lidar.range_noise_std_m = 0.0;
    s.lidar.dropout_probability = 0.0;
    s.lidar.edge_mixed_probability = 0.0;
    s.lidar.steel_flying_probability = 0.0;
    s.odometry.scale_error = 1.0;
    s.odometry.slip_factor_left = 1.0;
    s.odometry.slip_factor_right = 1.0;
    s.odometry.wheel_noise_std_mps = 0.0;
    s.gnss.good_sigma_m = 0.0;
    // Exact lidar comparisons need the static world only; the camera has its own tests.
    s.person.enabled = false;
    s.camera.enabled = false;
    s
}

fn secs(a: Stamp, b: Stamp) -> f64 {
    a.secs_since(b)
}

#[test]
fn counts_rates_order_and_frames() {
    let run = default_run();
    let s = Scenario::default();
    let d = s.robot.duration_s;
    assert!(d >= 120.0);
    let mut by_topic: std::collections::BTreeMap<&str, Vec<Stamp>> = Default::default();
    for m in &run.messages {
        by_topic.entry(m.topic()).or_default().push(m.stamp());
        let expected = match m {
            SimMessage::Scan(_) => "laser",
            SimMessage::Odometry(_) => "odom",
            SimMessage::Imu(_) => "imu_link",
            SimMessage::Fix(_) => "gps",
            SimMessage::StaticTransform(_) => "base_link",
            SimMessage::Image(_) | SimMessage::CameraInfo(_) => "camera_optical",
        };
        assert_eq!(m.frame_id(), expected);
    }
    assert!(run.messages.windows(2).all(|w| w[0].stamp() <= w[1].stamp()), "messages out of time order");
    let count = |t: &str| by_topic.get(t).map_or(0, |v| v.len());
    eprintln!("{d} s run:");
    for (topic, stamps) in &by_topic {
        let span = secs(*stamps.last().unwrap(), stamps[0]);
        let rate = if span > 0.0 { (stamps.len() - 1) as f64 / span } else { 0.0 };
        eprintln!("  {topic:12} {:6} messages, {rate:6.2} Hz", stamps.len());
    }
    assert_eq!(count("/scan"), ((d - s.lidar.sweep_time_s) * s.lidar.rate_hz).floor() as usize + 1);
    assert_eq!(count("/odom"), (d * s.odometry.rate_hz) as usize + 1);
    assert_eq!(count("/imu/data"), (d * s.imu.rate_hz) as usize + 1);
    assert_eq!(count("/tf_static"), 4);
    let frames = (d * s.camera.rate_hz) as usize + 1;
    for topic in ["/camera/labels", "/camera/depth", "/camera/camera_info"] {
        assert_eq!(count(topic), frames, "{topic}");
    }
    // Silent dropouts: fewer fixes than 5 Hz over the whole run, exactly the missing ones.
    let fixes = count("/gnss/fix");
    let dropped: f64 = run.dropouts.iter().map(|(a, b)| secs(*b, *a)).sum();
    let expected = d * s.gnss.rate_hz + 1.0 - dropped * s.gnss.rate_hz;
    assert!((fixes as f64 - expected).abs() <= 1.0 + run.dropouts.len() as f64, "{fixes} vs {expected}");
    for (topic, rate) in [("/scan", 10.0), ("/odom", 50.0), ("/imu/data", 100.0), ("/camera/labels", 10.0)] {
        let st = &by_topic[topic];
        assert!(st.windows(2).all(|w| (secs(w[1], w[0]) - 1.0 / rate).abs() < 1e-6), "{topic} not periodic");
    }
}

#[test]
fn same_seed_same_recording_other_seed_differs() {
    let mut s = Scenario::default();
    s.robot.duration_s = 15.0;
    let a = simulate(&s).unwrap();
    let b = simulate(&s).unwrap();
    // Debug text compares NaN ranges as equal, which `==` would not.
    assert_eq!(format!("{:?}", a.messages), format!("{:?}", b.messages));
    assert_eq!(a.injected_outliers, b.injected_outliers);
    s.world.seed += 1;
    let c = simulate(&s).unwrap();
    assert_ne!(format!("{:?}", a.messages), format!("{:?}", c.messages));
    // The truth does not depend on the seed.
    assert_eq!(a.truth_trajectory, c.truth_trajectory);
}

#[test]
fn the_path_keeps_clearance_from_every_object() {
    let s = Scenario::default();
    let traj = Trajectory::generate(&s.robot);
    let worst = traj.closest_approach(&s.world.objects).unwrap();
    let name = &s.world.objects[worst.object].name;
    eprintln!("closest approach: {:.2} m to {name} at t = {:.1} s", worst.distance_m, worst.t);
    assert!(worst.distance_m >= 0.5, "{worst:?}");
    // The check finds a path that does not keep clear.
    let mut tight = s.clone();
    tight.robot.waypoints[1] = [20.0, 7.0];
    let close = Trajectory::generate(&tight.robot).closest_approach(&tight.world.objects).unwrap();
    assert!(close.distance_m < 0.5, "{close:?}");
    // The loop is closed: the robot passes its start again.
    let start = traj.samples()[0].pose.translation();
    let back = traj.samples().iter().filter(|x| x.t > 30.0).map(|x| x.pose.translation().distance(start));
    assert!(back.fold(f64::INFINITY, f64::min) < 0.2);
}

/// Casts every beam of the clean run again from the true pose of its own time and
/// compares with what the scan reports.
#[test]
fn glass_passes_at_the_configured_rate_and_beams_are_deskewed() {
    let s = clean(100.0);
    let run = simulate(&s).unwrap();
    let traj = Trajectory::generate(&s.robot);
    let caster = Caster::new(&s.world.objects);
    let mount = s.lidar.mount.to_planar(1e-6).unwrap();
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let (mut glass, mut passed, mut exact, mut other, mut skew_visible) = (0u64, 0u64, 0u64, 0u64, 0u64);
    for scan in run.messages.iter().filter_map(|m| if let SimMessage::Scan(x) = m { Some(x) } else { None }) {
        let t0 = secs(scan.header.stamp, start) - s.lidar.time_offset_s;
        for (i, &r) in scan.ranges.iter().enumerate() {
            let t = t0 + i as f64 * scan.time_increment as f64;
            let pose = traj.pose_at(t);
            let origin = pose * mount.origin_in_base();
            let (sn, cs) = (pose.theta
                + mount.beam_angle_in_base(scan.angle_min as f64 + i as f64 * scan.angle_increment as f64))
            .sin_cos();
            let Some(hit) = caster.cast(origin, (cs, sn), &[]) else { continue };
            if hit.material == Material::Glass {
                glass += 1;
                if !(r as f64).is_finite() || r as f64 > hit.range + 0.05 {
                    passed += 1;
                }
            } else if hit.range < s.lidar.range_max_m {
                if (r as f64 - hit.range).abs() < 1e-4 {
                    exact += 1;
                } else {
                    other += 1;
                }
                // The same beam cast from the pose at the scan's stamp (no de-skew).
                let p0 = traj.pose_at(t0);
                let (s0, c0) = (p0.theta
                    + mount.beam_angle_in_base(scan.angle_min as f64 + i as f64 * scan.angle_increment as f64))
                .sin_cos();
                if let Some(h0) = caster.cast(p0 * mount.origin_in_base(), (c0, s0), &[]) {
                    if (h0.range - r as f64).abs() > 1e-3 {
                        skew_visible += 1;
                    }
                }
            }
        }
    }
    let share = passed as f64 / glass as f64;
    eprintln!(
        "glass: {glass} beams met the fence, {:.3} passed (configured {}); other beams: {exact} exact, {other} not; \
         {skew_visible} would differ if cast from the scan stamp's pose",
        share, s.lidar.glass_pass_probability
    );
    assert!(glass > 5_000, "{glass}");
    assert!((share - s.lidar.glass_pass_probability).abs() < 0.02, "{share}");
    // Without noise and failures every non-glass beam is exact at its own time...
    assert_eq!(other, 0);
    // ...and the sweep matters: many beams would differ by > 1 mm without de-skew.
    assert!(skew_visible as f64 > 0.2 * exact as f64, "{skew_visible} of {exact}");
}

#[test]
fn steel_flying_points_edges_and_dropouts_happen_at_their_rates() {
    let run = default_run();
    let st = run.lidar_stats;
    let lc = LidarConfig::default();
    eprintln!("lidar: {st:?}");
    let flying = st.flying_points as f64 / st.steel_hits as f64;
    assert!(st.steel_hits > 1_000 && (flying - lc.steel_flying_probability).abs() < 0.03, "{flying}");
    let drop = st.dropouts as f64 / st.beams as f64;
    assert!((drop - lc.dropout_probability).abs() < 0.002, "{drop}");
    assert!(st.mixed_pixels > 1_000);
    // The dropouts are really in the data: NaN, inf and 0 all occur.
    let (mut nan, mut zero) = (0u64, 0u64);
    for m in &run.messages {
        if let SimMessage::Scan(s) = m {
            nan += s.ranges.iter().filter(|r| r.is_nan()).count() as u64;
            zero += s.ranges.iter().filter(|&&r| r == 0.0).count() as u64;
        }
    }
    assert!(nan > 0 && zero > 0 && nan + zero < st.dropouts);
}

#[test]
fn fixes_in_dropouts_are_absent_or_no_fix() {
    let check = |mode: DropoutMode| {
        let mut s = Scenario::default();
        s.gnss.dropout_mode = mode;
        let run = simulate(&s).unwrap();
        assert!(!run.dropouts.is_empty());
        for (a, b) in &run.dropouts {
            let span = secs(*b, *a);
            eprintln!("{mode:?}: dropout of {span:.1} s");
            assert!(span >= 10.0, "{span}");
        }
        let mut no_fix = 0;
        for m in &run.messages {
            if let SimMessage::Fix(f) = m {
                let inside = run.dropouts.iter().any(|(a, b)| f.header.stamp >= *a && f.header.stamp <= *b);
                if inside {
                    assert_eq!(mode, DropoutMode::NoFix);
                    assert_eq!(f.status.status, NavSatStatus::STATUS_NO_FIX);
                    assert!(f.latitude.is_nan() && f.position_covariance_type == NavSatFix::COVARIANCE_TYPE_UNKNOWN);
                    no_fix += 1;
                } else {
                    assert!(f.status.status >= NavSatStatus::STATUS_FIX && f.latitude.is_finite());
                    assert_eq!(f.position_covariance_type, NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN);
                }
            }
        }
        no_fix
    };
    assert_eq!(check(DropoutMode::Silent), 0);
    assert!(check(DropoutMode::NoFix) >= 50);
}

#[test]
fn good_fixes_round_trip_to_the_antenna_within_a_millimetre() {
    let s = clean(120.0);
    let run = simulate(&s).unwrap();
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let traj = Trajectory::generate(&s.robot);
    let (mut good, mut worst) = (0, 0.0f64);
    for m in &run.messages {
        if let SimMessage::Fix(f) = m {
            if f.status.status != NavSatStatus::STATUS_GBAS_FIX {
                continue;
            }
            good += 1;
            let enu = run.datum.to_enu(f.latitude, f.longitude, f.altitude);
            let antenna = traj.pose_at(secs(f.header.stamp, start)) * Point2::new(s.gnss.mount.x, s.gnss.mount.y);
            let err = (enu[0] - antenna.x).hypot(enu[1] - antenna.y).hypot(enu[2] - s.gnss.mount.z);
            worst = worst.max(err);
        }
    }
    eprintln!("{good} RTK-fixed fixes, worst round-trip error {:.2e} m", worst);
    assert!(good > 300 && worst < 1e-3, "{good} {worst}");
}

#[test]
fn degraded_fixes_have_correlated_error_and_unreported_outliers() {
    let run = default_run();
    let s = Scenario::default();
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let traj = Trajectory::generate(&s.robot);
    let (mut errs, mut outlier_errs) = (Vec::new(), Vec::new());
    for m in &run.messages {
        if let SimMessage::Fix(f) = m {
            let enu = run.datum.to_enu(f.latitude, f.longitude, f.altitude);
            let antenna = traj.pose_at(secs(f.header.stamp, start)) * Point2::new(s.gnss.mount.x, s.gnss.mount.y);
            let e = (enu[0] - antenna.x).hypot(enu[1] - antenna.y);
            let sigma = f.position_covariance[0].sqrt();
            if run.injected_outliers.contains(&f.header.stamp) {
                assert_eq!(f.status.status, NavSatStatus::STATUS_FIX, "outliers only in degraded zones");
                outlier_errs.push(e / sigma);
            } else if f.status.status == NavSatStatus::STATUS_FIX {
                errs.push(e);
            } else {
                assert!(e < 5.0 * sigma.max(1e-9) * 2.0, "good fix {e} m off");
            }
        }
    }
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    eprintln!(
        "degraded: {} fixes, rms horizontal error {rms:.2} m; {} outliers at {:.1}–{:.1} σ (reported σ {} m)",
        errs.len(),
        outlier_errs.len(),
        outlier_errs.iter().cloned().fold(f64::INFINITY, f64::min),
        outlier_errs.iter().cloned().fold(0.0, f64::max),
        s.gnss.degraded_sigma_m
    );
    assert!(errs.len() > 100 && rms > 0.1 && rms < 3.0 * s.gnss.degraded_sigma_m, "{rms}");
    assert!(!outlier_errs.is_empty());
    // An outlier sits beyond what its covariance admits (≥ 2 m against σ = 0.5 m, minus
    // at most the correlated error pulling back).
    assert!(outlier_errs.iter().filter(|&&z| z > 2.0).count() * 2 > outlier_errs.len());
}

/// Absolute trajectory error of dead-reckoned odometry, anchored at the start pose.
fn odometry_ate(run: &SimRecording) -> (f64, f64) {
    let map_from_odom = run.truth_trajectory[0].1;
    let (mut sum, mut n, mut last) = (0.0, 0usize, 0.0);
    for m in &run.messages {
        if let SimMessage::Odometry(o) = m {
            let Some(truth) = run.truth_at(o.header.stamp) else { continue };
            let est = map_from_odom * o.pose2();
            let e = est.translation().distance(truth.translation());
            sum += e * e;
            n += 1;
            last = e;
        }
    }
    ((sum / n as f64).sqrt(), last)
}

#[test]
fn raw_odometry_drifts_far_and_exact_odometry_does_not() {
    let run = default_run();
    let (ate, final_err) = odometry_ate(run);
    eprintln!(
        "raw odometry: ATE RMSE {ate:.2} m, final error {final_err:.2} m over {} grooved 5 ms steps \
         (the estimator's target: ATE below {:.2} m)",
        run.slipping_steps,
        ate / 5.0
    );
    assert!(run.slipping_steps > 100);
    assert!(ate > 1.0, "{ate}");
    let exact = simulate(&clean(60.0)).unwrap();
    let (ate0, _) = odometry_ate(&exact);
    eprintln!("odometry without scale, slip or noise: ATE RMSE {ate0:.2e} m");
    assert!(ate0 < 1e-3, "{ate0}");
}

#[test]
fn imu_reports_rate_plus_bias_and_gravity_without_orientation() {
    let run = default_run();
    let s = Scenario::default();
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let traj = Trajectory::generate(&s.robot);
    let (mut bias_sum, mut az_sum, mut n) = (0.0, 0.0, 0usize);
    for m in &run.messages {
        if let SimMessage::Imu(i) = m {
            assert_eq!(i.orientation_covariance[0], -1.0);
            let truth = traj.sample_at(secs(i.header.stamp, start));
            bias_sum += i.angular_velocity.z - truth.omega;
            az_sum += i.linear_acceleration.z;
            n += 1;
        }
    }
    let bias = bias_sum / n as f64;
    eprintln!(
        "imu: mean gyro z minus true rate {bias:.5} rad/s (true bias {}), mean accel z {:.3}",
        run.gyro_bias_radps,
        az_sum / n as f64
    );
    assert!((bias - run.gyro_bias_radps).abs() < 2e-4);
    assert!((az_sum / n as f64 - STANDARD_GRAVITY).abs() < 0.01);
}

#[test]
fn truth_occupancy_contains_every_wall_and_leaves_the_path_free() {
    let run = default_run();
    let g = GridGeometry::centered(0.05).unwrap();
    let raster = run.truth_occupancy(g).unwrap();
    let mut checked = 0;
    for o in &run.objects {
        let edges = o.outline();
        for (a, b) in edges {
            for k in 0..=20 {
                let u = k as f64 / 20.0;
                let p = Point2::new(a.x + (b.x - a.x) * u, a.y + (b.y - a.y) * u);
                assert!(raster.is_occupied(g.cell_of(p).unwrap()), "{} at {p:?}", o.name);
                checked += 1;
            }
        }
    }
    for (_, pose) in run.truth_trajectory.iter().step_by(25) {
        assert!(!raster.is_occupied(g.cell_of(pose.translation()).unwrap()));
    }
    let n = raster.occupied_count();
    eprintln!("truth raster {}×{} cells, {n} occupied, {checked} outline points checked", raster.width, raster.height);
    assert_eq!(raster.occupied_cells().count(), n);
    // Walls are 0.2 m thick and 30 + 15 m long per side pair: at least that area.
    assert!(n as f64 * 0.0025 > 0.2 * 90.0);
}

#[test]
fn invalid_scenarios_are_refused_and_generation_is_quick() {
    let mut s = Scenario::default();
    s.lidar.beams = 0;
    assert!(matches!(simulate(&s), Err(SimError::Invalid(m)) if m.field == "lidar.beams"));
    let t = std::time::Instant::now();
    let mut s = Scenario::default();
    s.robot.duration_s = 120.0;
    let run = simulate(&s).unwrap();
    eprintln!(
        "120 s scenario: {} messages generated in {:.2} s (this build's profile)",
        run.messages.len(),
        t.elapsed().as_secs_f64()
    );
}

#[test]
fn time_offsets_move_stamps_not_measurements() {
    let mut s = clean(10.0);
    let base = simulate(&s).unwrap();
    s.lidar.time_offset_s = 0.03;
    s.imu.time_offset_s = -0.01;
    let shifted = simulate(&s).unwrap();
    let scans = |r: &SimRecording| -> Vec<SimScan> {
        r.messages.iter().filter_map(|m| if let SimMessage::Scan(x) = m { Some(x.clone()) } else { None }).collect()
    };
    let imus = |r: &SimRecording| -> Vec<Stamp> {
        r.messages.iter().filter_map(|m| if let SimMessage::Imu(x) = m { Some(x.header.stamp) } else { None }).collect()
    };
    let (a, b) = (scans(&base), scans(&shifted));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(y.header.stamp.0 - x.header.stamp.0, 30_000_000);
        assert_eq!(format!("{:?}", x.ranges), format!("{:?}", y.ranges));
    }
    assert!(imus(&base).iter().zip(imus(&shifted)).all(|(x, y)| y.0 - x.0 == -10_000_000));
    assert_eq!(base.truth_trajectory, shifted.truth_trajectory);
}

#[test]
fn imu_lateral_acceleration_is_centripetal() {
    let mut s = clean(120.0);
    s.imu.accel_noise_std_mps2 = 0.0;
    s.imu.accel_bias_mps2 = [0.0; 3];
    let run = simulate(&s).unwrap();
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let traj = Trajectory::generate(&s.robot);
    let (mut worst, mut turning) = (0.0f64, 0);
    for m in &run.messages {
        if let SimMessage::Imu(i) = m {
            let t = traj.sample_at(secs(i.header.stamp, start));
            // The IMU sits on the base's z axis: no lever-arm terms in the plane.
            worst = worst.max((i.linear_acceleration.y - t.v * t.omega).abs());
            worst = worst.max((i.linear_acceleration.x - t.accel).abs());
            turning += usize::from(t.omega.abs() > 0.2);
        }
    }
    eprintln!("imu: {turning} samples turning faster than 0.2 rad/s, worst accel mismatch {worst:.2e} m/s²");
    assert!(turning > 1_000 && worst < 1e-9);
}

/// Maps a run through the core's own engine with true, de-skewed poses and measures the
/// map against the truth raster: the precision of its occupied cells (within one cell of
/// truth) and the share of glass-fence cells it marks occupied.
fn map_with_true_poses(s: &Scenario) -> (f64, f64, usize) {
    use fusemap_core::fusion::Engine;
    use fusemap_core::grid::{FusionGrid, OccupancyParams, Ternary};
    use fusemap_core::sensor::{LaserScan, LidarModel, LidarParams};
    let run = simulate(s).unwrap();
    let traj = Trajectory::generate(&s.robot);
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let g = GridGeometry::centered(0.05).unwrap();
    let mut engine = Engine::new(FusionGrid::new(g, OccupancyParams::default()));
    let params = LidarParams { max_range: s.lidar.range_max_m, ..LidarParams::default() };
    let laser = engine.add_lidar("laser", LidarModel::new(params, s.lidar.mount.to_planar(1e-6).unwrap()));
    for m in &run.messages {
        if let SimMessage::Scan(x) = m {
            let scan = LaserScan {
                stamp: x.header.stamp,
                angle_min: x.angle_min as f64,
                angle_increment: x.angle_increment as f64,
                ranges: x.ranges.clone(),
            };
            let t0 = secs(x.header.stamp, start) - s.lidar.time_offset_s;
            let ti = x.time_increment as f64;
            engine.insert_scan_with(laser, &scan, |i| traj.pose_at(t0 + i as f64 * ti)).unwrap();
        }
    }
    let truth = run.truth_occupancy(g).unwrap();
    let near_truth =
        |c: CellIndex| (-1..=1).any(|dy| (-1..=1).any(|dx| truth.is_occupied(CellIndex::new(c.x + dx, c.y + dy))));
    let grid = engine.grid();
    let known = grid.known_box().unwrap();
    let (mut tp, mut fp) = (0usize, 0usize);
    for y in known.min.y..=known.max.y {
        for x in known.min.x..=known.max.x {
            let c = CellIndex::new(x, y);
            if grid.ternary(c) == Ternary::Occupied {
                if near_truth(c) {
                    tp += 1
                } else {
                    fp += 1
                }
            }
        }
    }
    // Glass-fence cells on the fence line, x ∈ [6, 24] (away from its ends).
    let fence: Vec<CellIndex> =
        (0..=360).map(|i| g.cell_of(Point2::new(6.0 + 0.05 * i as f64, 10.5)).unwrap()).collect();
    let fence_seen =
        fence.iter().filter(|&&c| grid.ternary(c) == Ternary::Occupied).count() as f64 / fence.len() as f64;
    (tp as f64 / (tp + fp) as f64, fence_seen, fp)
}

#[test]
fn the_failures_reach_a_map_built_from_true_poses() {
    let mut clean_run = clean(90.0);
    clean_run.lidar.glass_pass_probability = 0.0;
    let (p_clean, fence_clean, fp_clean) = map_with_true_poses(&clean_run);
    let mut faulty = Scenario::default();
    faulty.robot.duration_s = 90.0;
    let (p_faulty, fence_faulty, fp_faulty) = map_with_true_poses(&faulty);
    eprintln!(
        "map from true poses, 90 s: without failures precision {p_clean:.3} ({fp_clean} stray cells), glass fence \
         {:.0} % occupied; with the production line's failures precision {p_faulty:.3} ({fp_faulty} stray cells), \
         glass fence {:.0} % occupied",
        100.0 * fence_clean,
        100.0 * fence_faulty
    );
    assert!(p_clean > 0.98, "{p_clean}");
    assert!(fence_clean > 0.9, "{fence_clean}");
    // Flying points and mixed pixels put obstacles where there are none...
    assert!(fp_faulty > 5 * fp_clean.max(10), "{fp_faulty} vs {fp_clean}");
    // ...and glass that passes 60 % of the beams fades from the map.
    assert!(fence_faulty < fence_clean - 0.2, "{fence_faulty} vs {fence_clean}");
}

/// The walking person: in the scans and the label images on more than one meeting, and
/// never in the truth.
#[test]
fn the_person_is_seen_by_lidar_and_camera_and_absent_from_the_truth() {
    let run = default_run();
    let s = Scenario::default();
    assert!(run.lidar_stats.person_hits > 100, "{:?}", run.lidar_stats);
    assert!(!run.person_track.is_empty() && run.person_radius_m == s.person.radius_m);
    // Person pixels in the label images per presence window (plus salt noise, which
    // gives every class about 1/600 of the pixels).
    let start = Stamp(s.world.start_time_s * 1_000_000_000);
    let mut per_window = vec![0usize; s.person.windows.len()];
    let mut absent = 0usize;
    let mut absent_frames = 0usize;
    for m in &run.messages {
        let SimMessage::Image(img) = m else { continue };
        if img.topic != s.camera.label_topic {
            continue;
        }
        let t = secs(img.header.stamp, start) - s.camera.time_offset_s;
        let n = img.data.iter().filter(|&&l| u16::from(l) == CLASS_PERSON).count();
        match s.person.windows.iter().position(|w| t >= w[0] && t <= w[1]) {
            Some(k) => per_window[k] += n,
            None => {
                absent += n;
                absent_frames += 1;
            }
        }
    }
    let pixels = (s.camera.width * s.camera.height) as f64;
    let salt_per_frame = pixels * s.camera.label_noise_probability / 6.0;
    eprintln!(
        "person: {} lidar returns; label pixels per window {per_window:?}, {absent} in {absent_frames} frames without it",
        run.lidar_stats.person_hits
    );
    assert!((absent as f64) < 1.5 * salt_per_frame * absent_frames as f64, "{absent}");
    for (k, n) in per_window.iter().enumerate() {
        let w = s.person.windows[k];
        let salt = salt_per_frame * (w[1] - w[0]) * s.camera.rate_hz;
        assert!(*n as f64 > salt + 2_000.0, "window {k}: {n} person pixels, salt alone gives {salt:.0}");
    }
    // The truth is that of the objects alone.
    let g = GridGeometry::centered(0.05).unwrap();
    let truth = run.truth_occupancy(g).unwrap();
    for (stamp, p) in &run.person_track {
        assert!(!truth.is_occupied(g.cell_of(*p).unwrap()), "the person at {p:?} ({stamp:?}) is in the truth");
    }
    let mut without = run.clone();
    without.person_track.clear();
    assert_eq!(without.truth_occupancy(g).unwrap(), truth);
    // It leaves: the track stops before the end of the run.
    let last = run.person_track.last().unwrap().0;
    assert!(secs(*run.truth_trajectory.last().map(|(s, _)| s).unwrap(), last) > 30.0);
}
