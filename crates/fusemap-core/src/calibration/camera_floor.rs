//! A depth camera's tilt and height above the floor, from the floor it sees.
//!
//! The floor is the one surface every frame of a ground robot's camera shares, and its
//! plane fixes exactly the three mount parameters the lidar's map cannot: the camera's
//! height above the floor and its tilt (pitch down, and roll about the optical axis). The
//! heading about the vertical and the position in the floor's plane leave the floor as it
//! is; [`camera_against_map`](super::camera_against_map) finds the yaw against the lidar.
//!
//! **Fit.** The depth pixels near the configured floor, rotated into `base_link` with the
//! configured mount but kept relative to the camera's origin, are fitted with a plane
//! `z = a·x + b·y + c` by least squares, with the usual iteratively narrowed inlier band
//! (0.3 m around the configured floor, then 0.15, 0.08 and 0.04 m around the fit) so that
//! pallets, legs and walls near the floor drop out. The plane's upward normal `n` and its
//! distance `h` from the camera give the correction: the roll and pitch that put `n` on the
//! vertical (the tilt, which does not depend on the yaw; the yaw is kept as configured),
//! and `h` as the mount's `z` (the floor is `base_link`'s `z = 0`, as the camera model's
//! floor band assumes).
//!
//! **Intervals.** A frame's pixels are not independent (one floor, one depth bias per
//! frame), and neighbouring frames see the same floor: the interval is the delete-a-group
//! jackknife over [`GROUPS`] runs of consecutive frames, each left out in turn with the
//! inliers of the whole fit (Efron & Tibshirani 1993, §11; as the other estimates here).

use super::{jackknife_sigma, Interval};
use crate::geometry::{normalize_angle, Mount3, Pose3};

/// Runs of consecutive frames the jackknife leaves out in turn.
pub const GROUPS: usize = 10;
/// Fewer frames with floor points than this leave the floor undetermined: the jackknife
/// needs frames in every group.
pub const MIN_FRAMES: usize = 2 * GROUPS;
/// Fewer floor points than this in all leave it undetermined.
pub const MIN_POINTS: usize = 200;
/// The inlier bands of the fit's rounds, metres: the first around the configured floor,
/// the others around the previous round's plane.
const BANDS_M: [f64; 4] = [0.3, 0.15, 0.08, 0.04];

/// One frame's depth points in the optical frame (metres): what the floor fit takes.
pub type FloorPoints = Vec<[f32; 3]>;

/// What the floor says of the camera's mount.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorFit {
    /// Frames that gave floor points.
    pub frames: usize,
    /// Floor points (inliers of the last round).
    pub points: usize,
    /// RMS height of those points above `base_link`'s floor with the configured mount,
    /// metres …
    pub rms_before_m: f64,
    /// … and with the fitted one.
    pub rms_after_m: f64,
    /// The mount's `z`: the camera's height above the floor, metres.
    pub z: Interval,
    /// The mount's roll and pitch (the `[sensor.base_from_sensor]` fields of the optical
    /// frame), radians.
    pub roll: Interval,
    /// See `roll`.
    pub pitch: Interval,
    /// The corrected mount: the configured one with the floor's roll and pitch and the
    /// fitted height as its `z`.
    pub base_from_optical: Pose3,
}

/// The plane `z = a·x + b·y + c` through `points` (camera-relative, base-oriented) by
/// least squares, or `None` when they do not span a plane.
fn plane(points: impl Iterator<Item = [f64; 3]>) -> Option<[f64; 3]> {
    // Normal equations of [x y 1]·[a b c]ᵀ = z, centred for conditioning.
    let pts: Vec<[f64; 3]> = points.collect();
    let n = pts.len() as f64;
    if pts.len() < 3 {
        return None;
    }
    let mean = [0, 1, 2].map(|k| pts.iter().map(|p| p[k]).sum::<f64>() / n);
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in &pts {
        let [x, y, z] = [p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]];
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * z;
        syz += y * z;
    }
    let det = sxx * syy - sxy * sxy;
    // Points on a line (or one point) leave the tilt across it free; NaN spans nothing.
    let spans = det > 1e-9 * (sxx * syy) && sxx > 1e-6 && syy > 1e-6;
    if !spans {
        return None;
    }
    let a = (sxz * syy - syz * sxy) / det;
    let b = (syz * sxx - sxz * sxy) / det;
    let c = mean[2] - a * mean[0] - b * mean[1];
    [a, b, c].iter().all(|v| v.is_finite()).then_some([a, b, c])
}

/// The mount `configured` corrected by the floor plane `z = a·x + b·y + c` (camera-relative,
/// rotated by the configured mount): its roll and pitch those that put the plane's normal
/// on the vertical, its yaw kept, its `z` the plane's distance below the camera.
///
/// The vertical in the sensor's frame, `Rᵀ·e_z = (−sin p, sin r·cos p, cos r·cos p)` for
/// `R = R_z(yaw)·R_y(p)·R_x(r)`, does not depend on the yaw: roll and pitch are the tilt,
/// exactly, and the yaw is the lidar's to find.
fn corrected(configured: &Pose3, [a, b, c]: [f64; 3]) -> Pose3 {
    let norm = (a * a + b * b + 1.0).sqrt();
    let up = configured.inverse().rotate([-a / norm, -b / norm, 1.0 / norm]);
    let pitch = (-up[0]).atan2(up[1].hypot(up[2]));
    let roll = up[1].atan2(up[2]);
    let yaw = configured.to_mount().yaw;
    let rotation = Mount3 { roll, pitch, yaw, ..Default::default() }.quaternion();
    Pose3::new([configured.translation[0], configured.translation[1], -c / norm], rotation)
}

/// The camera's height and tilt from the floor in `frames` (each frame's depth points in the
/// optical frame), with `configured` the mount the pass used. An error says why the floor
/// cannot fix them (too few frames or points, no plane).
pub fn camera_floor<'a>(
    frames: impl IntoIterator<Item = &'a [[f32; 3]]>,
    configured: &Pose3,
) -> Result<FloorFit, String> {
    let rotate = |q: &[f32; 3]| configured.rotate(q.map(f64::from));
    let relative: Vec<Vec<[f64; 3]>> = frames.into_iter().map(|f| f.iter().map(rotate).collect()).collect();
    let z0 = configured.translation[2];
    // Rounds of narrowing bands: the first around the configured floor (z = −z0).
    let mut fit = [0.0, 0.0, -z0];
    let inlier =
        |fit: [f64; 3], band: f64, p: &[f64; 3]| (p[2] - (fit[0] * p[0] + fit[1] * p[1] + fit[2])).abs() < band;
    for &band in &BANDS_M {
        let inliers = relative.iter().flatten().filter(|p| inlier(fit, band, p)).copied();
        fit = plane(inliers).ok_or("the depth points near the floor do not span a plane")?;
    }
    // Each frame's inliers of the last round's plane, frames without any left out.
    let band = BANDS_M[BANDS_M.len() - 1];
    let used: Vec<Vec<[f64; 3]>> = relative
        .iter()
        .map(|f| f.iter().filter(|p| inlier(fit, band, p)).copied().collect::<Vec<_>>())
        .filter(|f| !f.is_empty())
        .collect();
    let points: usize = used.iter().map(|f| f.len()).sum();
    if used.len() < MIN_FRAMES || points < MIN_POINTS {
        return Err(format!(
            "{} frames with {points} floor points (at least {MIN_FRAMES} frames and {MIN_POINTS} points are needed)",
            used.len()
        ));
    }
    let fit = plane(used.iter().flat_map(|f| f.iter().copied())).ok_or("the floor points do not span a plane")?;
    let mount = corrected(configured, fit);
    // Leave-one-group-out estimates: (z, roll, pitch).
    let per_group = used.len().div_ceil(GROUPS);
    let mut est: [Vec<f64>; 3] = Default::default();
    for g in 0..GROUPS {
        let rest = used.iter().enumerate().filter(|(i, _)| i / per_group != g).flat_map(|(_, f)| f.iter().copied());
        let Some(p) = plane(rest) else { continue };
        let m = corrected(configured, p).to_mount();
        for (k, v) in [m.z, m.roll, m.pitch].into_iter().enumerate() {
            est[k].push(v);
        }
    }
    let m = mount.to_mount();
    let rms = |f: &dyn Fn(&[f64; 3]) -> f64| {
        (used.iter().flat_map(|p| p.iter()).map(|p| f(p).powi(2)).sum::<f64>() / points as f64).sqrt()
    };
    // After: the points' heights above the fitted floor, through the fitted mount (the
    // points are rotated by the configured mount: turned back, then by the fitted one).
    let refit = Pose3::new([0.0; 3], mount.rotation).compose(&Pose3::new([0.0; 3], configured.inverse().rotation));
    let after = |p: &[f64; 3]| refit.rotate(*p)[2] + mount.translation[2];
    Ok(FloorFit {
        frames: used.len(),
        points,
        rms_before_m: rms(&|p| p[2] + z0),
        rms_after_m: rms(&after),
        z: Interval::of(m.z, jackknife_sigma(&est[0], false)),
        roll: Interval::of(m.roll, jackknife_sigma(&est[1], true)),
        pitch: Interval::of(normalize_angle(m.pitch), jackknife_sigma(&est[2], true)),
        base_from_optical: mount,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::camera::optical_mount;

    /// A number in [−1, 1) from `k` (SplitMix64): depth noise independent pixel to pixel
    /// and frame to frame.
    fn uniform(k: u64) -> f64 {
        let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// Depth points of a camera at `mount` (its true optical frame) looking at a flat
    /// floor, `frames` frames of a 16 × 12 grid of pixels, with `noise` metres of depth
    /// noise (uniform, seeded), plus a box 0.2 m high in front on every frame.
    fn floor_frames(mount: &Pose3, frames: usize, noise: f64) -> Vec<FloorPoints> {
        (0..frames)
            .map(|f| {
                let mut out = Vec::new();
                for i in 0..16 {
                    for j in 0..12 {
                        // A ray through the image: x right, y down, z forward.
                        let ray = [(i as f64 - 7.5) * 0.06, (j as f64 - 2.0) * 0.06, 1.0];
                        let dir = mount.rotate(ray);
                        let t = mount.translation;
                        // The floor (z = 0), or the box top (z = 0.2) within 1.5..2 m ahead.
                        let mut d = -t[2] / dir[2];
                        let hit = [t[0] + d * dir[0], t[1] + d * dir[1]];
                        if (1.5..2.0).contains(&hit[0]) && hit[1].abs() < 0.3 {
                            d = (0.2 - t[2]) / dir[2];
                        }
                        if !(d > 0.3 && d < 8.0) {
                            continue;
                        }
                        let wobble = noise * uniform((f * 1000 + i * 100 + j) as u64);
                        let q = [ray[0] * (d + wobble), ray[1] * (d + wobble), d + wobble];
                        out.push(q.map(|v| v as f32));
                    }
                }
                out
            })
            .collect()
    }

    fn mount_of(height: f64, pitch_down_deg: f64, roll_deg: f64) -> Pose3 {
        let m = optical_mount([0.25, 0.0, height], 0.0, pitch_down_deg.to_radians());
        // Roll about the camera's optical axis (its z), applied in the optical frame.
        let roll = Pose3::new([0.0; 3], Mount3 { yaw: roll_deg.to_radians(), ..Default::default() }.quaternion());
        Pose3::new(m.translation, m.compose(&roll).rotation)
    }

    #[test]
    fn recovers_height_and_tilt_from_a_wrong_configuration() {
        let truth = mount_of(1.0, 25.0, 1.5);
        let frames = floor_frames(&truth, 40, 0.01);
        let wrong = mount_of(1.05, 22.0, 0.0);
        let fit = camera_floor(frames.iter().map(Vec::as_slice), &wrong).unwrap();
        let t = truth.to_mount();
        assert!((fit.z.value - 1.0).abs() < 0.005, "{fit:?}");
        // The vertical as the camera sees it (its tilt): a roll about the optical axis of a
        // camera looking down also turns its heading, which the floor cannot see.
        let up = |p: &Pose3| p.inverse().rotate([0.0, 0.0, 1.0]);
        let (u, v) = (up(&fit.base_from_optical), up(&truth));
        let dot: f64 = (0..3).map(|k| u[k] * v[k]).sum();
        assert!(dot.min(1.0).acos() < 0.05f64.to_radians(), "{fit:?}");
        assert!((fit.roll.value - t.roll).abs() < 0.003 && (fit.pitch.value - t.pitch).abs() < 0.003, "{fit:?} {t:?}");
        assert!(fit.z.contains(1.0) && fit.roll.contains(t.roll) && fit.pitch.contains(t.pitch), "{fit:?} {t:?}");
        assert!(fit.rms_after_m < 0.5 * fit.rms_before_m, "{fit:?}");
        // The yaw is the configured one: the floor cannot see it.
        assert!((fit.base_from_optical.to_mount().yaw - wrong.to_mount().yaw).abs() < 1e-12);
    }

    #[test]
    fn the_right_configuration_stays_within_its_interval() {
        let truth = mount_of(1.0, 25.0, 0.0);
        let fit = camera_floor(floor_frames(&truth, 30, 0.02).iter().map(Vec::as_slice), &truth).unwrap();
        let t = truth.to_mount();
        assert!(fit.z.contains(t.z) && fit.roll.contains(t.roll) && fit.pitch.contains(t.pitch), "{fit:?}");
        assert!(fit.z.half_width() < 0.01, "{fit:?}");
    }

    #[test]
    fn without_enough_floor_it_says_why() {
        let truth = mount_of(1.0, 25.0, 0.0);
        let few = floor_frames(&truth, 5, 0.0);
        assert!(camera_floor(few.iter().map(Vec::as_slice), &truth).unwrap_err().contains("frames"));
        // A camera looking up sees no floor.
        let up = mount_of(1.0, -30.0, 0.0);
        assert!(camera_floor(floor_frames(&up, 40, 0.0).iter().map(Vec::as_slice), &truth).is_err());
        assert!(camera_floor(std::iter::empty(), &truth).is_err());
    }
}
