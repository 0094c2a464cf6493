//! The camera's clock offset and mount yaw against the lidar: the offset and yaw at which
//! the camera's obstacle points fall on the walls of the lidar's map.
//!
//! The criterion is the "scan-match residual against the other sensors' map":
//! each obstacle point of each frame, placed with the pose track at its stamp plus a
//! trial offset `δ` and rotated by a trial yaw `ε` about the camera, costs its squared
//! distance to the nearest wall face of the lidar-only map, truncated (a point on
//! something the lidar cannot see costs the same wherever it lands), read between cell
//! centres so the summed cost moves smoothly ([`DistanceField`]). A late clock places a
//! turning robot's frames at the wrong heading: the walls smear, and the cost rises on
//! either side of the true offset. A straight drive at constant speed shifts points along
//! the walls it drives beside and fixes the offset only through the walls across its
//! path; the search reports a flat cost as undetermined rather than inventing a minimum.
//!
//! Coarse to fine: the yaw over a wide grid with the configured offset, then the offset
//! over its grid at that yaw, then both on fine grids in turn. The truncation narrows
//! with the grids, as an ICP's correspondence distance does: the coarse grids need a
//! reach as wide as the errors they search (a 0.2 s clock error moves a point 0.3 m at
//! walking speed), but at the fine grids, already within a few centimetres, every point
//! between the narrow and the wide reach is one on something the lidar's map lacks or
//! holds elsewhere (a shelf above its plane, a window it sees through), and a truncated
//! quadratic pulls hardest on exactly those. On the production line the camera's clock
//! came out 11 ms late with 0.3 m throughout and 4 ms with 0.1 m at the fine grids, the
//! response to a 40 ms late clock unchanged. Each minimum is the vertex of
//! the parabola through the best grid value and its neighbours; its interval is the
//! delete-a-block jackknife's (blocks of consecutive frames, so a turn's frames, which
//! share their pose errors, leave together), read from the same grid costs with one
//! block subtracted. This is Kalibr's idea of fitting the offset inside the estimate
//! rather than from a cross-correlation of rates, on the map instead of a spline, and
//! unlike `lidar_align`'s crispness of one sensor's own cloud it scores one sensor on the
//! other's map, so it cannot drift to a minimum where both are wrong together.

use super::{jackknife_sigma, DistanceField, Interval};
use crate::geometry::{Point2, Pose2};
use crate::time::Stamp;
use serde::Serialize;

/// One camera frame's obstacle points, base frame, at the frame's stamp (with the
/// configured clock offset).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSample {
    /// The frame's stamp, as placed by the mapping pass.
    pub stamp: Stamp,
    /// Its obstacle-band points of obstacle classes, base frame (x forward, y left).
    pub points: Vec<Point2>,
    /// Its depth points near the configured floor, optical frame: what
    /// [`camera_floor`](super::camera_floor) fits.
    pub floor: super::FloorPoints,
}

/// The search's grids.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSearch {
    /// The offsets searched, `±` this, seconds.
    pub clock_span_s: f64,
    /// The coarse offset step, seconds.
    pub clock_step_s: f64,
    /// The fine offset step, seconds.
    pub clock_fine_step_s: f64,
    /// The yaws searched, `±` this, radians.
    pub yaw_span_rad: f64,
    /// The coarse yaw step, radians.
    pub yaw_step_rad: f64,
    /// The fine yaw step, radians.
    pub yaw_fine_step_rad: f64,
    /// The truncation of the fine searches, metres (the coarse ones use the field's own,
    /// [`DistanceField::max_m`]; the smaller of the two is used).
    pub fine_reach_m: f64,
}

impl Default for CameraSearch {
    /// ±0.3 s by 10 ms then 1 ms; ±8° by 0.25° then 0.02°; fine searches truncated at
    /// 0.1 m (two cells of the default map, and more than a fine step's error moves a
    /// point).
    fn default() -> Self {
        Self {
            clock_span_s: 0.3,
            clock_step_s: 0.01,
            clock_fine_step_s: 0.001,
            yaw_span_rad: 8f64.to_radians(),
            yaw_step_rad: 0.25f64.to_radians(),
            yaw_fine_step_rad: 0.02f64.to_radians(),
            fine_reach_m: 0.1,
        }
    }
}

/// What the search found; offsets and yaws are corrections to add to the configured ones.
#[derive(Clone, Debug, Serialize)]
pub struct CameraLidarFit {
    /// The clock correction, seconds; `None` when the cost does not fix it.
    pub clock: Option<Interval>,
    /// The mount-yaw correction, radians; `None` when the cost does not fix it.
    pub yaw: Option<Interval>,
    /// The root of the mean squared distance, truncated at the field's reach, with the
    /// configured offset and mount, metres …
    pub cost_before_m: f64,
    /// … and with the corrections.
    pub cost_after_m: f64,
    /// The cost the fine searches minimise (as `cost_*_m`, but truncated at
    /// [`CameraSearch::fine_reach_m`]) over the offsets searched at the found yaw:
    /// `[δ, cost]`.
    pub clock_curve: Vec<[f64; 2]>,
    /// The same cost over the yaws searched at the found offset: `[ε, cost]`.
    pub yaw_curve: Vec<[f64; 2]>,
    /// Frames and points scored.
    pub frames: usize,
    /// …
    pub points: usize,
}

/// The most rounds of fine searches.
const ROUNDS: usize = 6;
/// Blocks of frames for the jackknife.
const BLOCKS: usize = 20;
/// Fewer frames or points than these fix nothing.
const MIN_FRAMES: usize = 20;
const MIN_POINTS: usize = 1000;
/// A cost that varies by less than this share of its level over the coarse search is flat.
const FLAT: f64 = 1e-3;

/// The frames the pose track covers at every offset searched, each with its base-frame
/// points' mount rotation centre applied by `cost`.
struct Scorer<'a> {
    frames: Vec<(&'a CameraSample, usize)>,
    pose_at: &'a (dyn Fn(Stamp) -> Option<Pose2> + Sync),
    field: &'a DistanceField,
    centre: Point2,
    points: usize,
    /// The fine searches' truncation, metres (at most the field's).
    narrow: f64,
}

/// A curve: `(value, block sums)` over the values of one parameter.
type Curve = Vec<(f64, Vec<f64>)>;

impl Scorer<'_> {
    /// Per-block sums of the squared distances at offset `dt` and yaw `eps`, truncated at
    /// the field's reach (`[0]`) and at the narrow one (`[1]`): one walk over the points
    /// gives both.
    fn blocks(&self, dt: f64, eps: f64) -> [Vec<f64>; 2] {
        let (s, c) = eps.sin_cos();
        let shift = (dt * 1e9).round() as i64;
        let (mut wide, mut narrow) = (vec![0.0; BLOCKS], vec![0.0; BLOCKS]);
        for (f, b) in &self.frames {
            // A frame beyond the track at this offset costs as much as a point far from
            // every wall: fewer terms must not make an offset look better.
            let Some(pose) = (self.pose_at)(Stamp(f.stamp.0.saturating_add(shift))) else {
                wide[*b] += f.points.len() as f64 * self.field.max_m().powi(2);
                narrow[*b] += f.points.len() as f64 * self.narrow.powi(2);
                continue;
            };
            let (mut w, mut n) = (0.0, 0.0);
            for p in &f.points {
                let (dx, dy) = (p.x - self.centre.x, p.y - self.centre.y);
                let q = Point2::new(self.centre.x + c * dx - s * dy, self.centre.y + s * dx + c * dy);
                let d = self.field.at(pose.transform_point(q));
                w += d * d;
                n += d.min(self.narrow).powi(2);
            }
            wide[*b] += w;
            narrow[*b] += n;
        }
        [wide, narrow]
    }

    /// The costs over `values` of one parameter, the other fixed, at the wide reach
    /// (`[0]`) and the narrow one (`[1]`). The values are scored on every thread, each by
    /// one thread and collected in order, so the curves are the same whatever the thread
    /// count.
    fn curves(&self, values: &[f64], at: impl Fn(f64) -> (f64, f64) + Sync + Send) -> [Curve; 2] {
        let both = crate::parallel::map_all(values, |&v| {
            let (dt, eps) = at(v);
            (v, self.blocks(dt, eps))
        });
        let mut out: [Curve; 2] = [Vec::with_capacity(both.len()), Vec::with_capacity(both.len())];
        for (v, [w, n]) in both {
            out[0].push((v, w));
            out[1].push((v, n));
        }
        out
    }

    /// The costs at the narrow reach alone (the fine searches').
    fn curve(&self, values: &[f64], at: impl Fn(f64) -> (f64, f64) + Sync + Send) -> Curve {
        let [_, narrow] = self.curves(values, at);
        narrow
    }

    /// `√(mean)` of a total.
    fn rms(&self, total: f64) -> f64 {
        (total / self.points.max(1) as f64).sqrt()
    }
}

/// `centre ± span` by `step`.
fn grid(centre: f64, span: f64, step: f64) -> Vec<f64> {
    let n = (span / step).round() as i64;
    (-n..=n).map(|k| centre + k as f64 * step).collect()
}

/// The vertex of the parabola through the least cost of `costs` (at equal steps) and its
/// neighbours; `None` at an edge of the grid.
fn vertex(xs: &[f64], costs: &[f64]) -> Option<f64> {
    let best = (0..costs.len()).min_by(|&a, &b| costs[a].total_cmp(&costs[b]))?;
    if best == 0 || best + 1 >= costs.len() {
        return None;
    }
    let (y0, y1, y2) = (costs[best - 1], costs[best], costs[best + 1]);
    let h = xs[best + 1] - xs[best];
    let den = y0 - 2.0 * y1 + y2;
    let shift = if den > 0.0 { (0.5 * h * (y0 - y2) / den).clamp(-h, h) } else { 0.0 };
    Some(xs[best] + shift)
}

/// The least of a curve with its jackknife interval; `None` when its least cost lies at
/// an edge of the grid.
fn minimum(curve: &[(f64, Vec<f64>)]) -> Option<Interval> {
    let xs: Vec<f64> = curve.iter().map(|c| c.0).collect();
    let totals: Vec<f64> = curve.iter().map(|c| c.1.iter().sum()).collect();
    let best = vertex(&xs, &totals)?;
    let reduced: Vec<f64> = (0..BLOCKS)
        .filter(|&b| curve.iter().any(|c| c.1[b] > 0.0))
        .map(|b| {
            let costs: Vec<f64> = curve.iter().zip(&totals).map(|(c, t)| t - c.1[b]).collect();
            // A reduced curve whose least lies at the fine grid's edge counts at that edge.
            vertex(&xs, &costs).unwrap_or_else(|| {
                let i = (0..costs.len()).min_by(|&a, &b| costs[a].total_cmp(&costs[b])).unwrap_or(0);
                xs[i]
            })
        })
        .collect();
    Some(Interval::of(best, jackknife_sigma(&reduced, false)))
}

/// The grid value of a curve's least total cost.
fn least(curve: &[(f64, Vec<f64>)]) -> f64 {
    let total = |c: &(f64, Vec<f64>)| c.1.iter().sum::<f64>();
    curve.iter().min_by(|a, b| total(a).total_cmp(&total(b))).map_or(0.0, |c| c.0)
}

/// Whether a curve's least total cost lies inside its grid, not at an end.
fn interior(curve: &[(f64, Vec<f64>)]) -> bool {
    let total = |c: &(f64, Vec<f64>)| c.1.iter().sum::<f64>();
    let best = (0..curve.len()).min_by(|&a, &b| total(&curve[a]).total_cmp(&total(&curve[b])));
    best.is_some_and(|i| i > 0 && i + 1 < curve.len())
}

/// Whether a curve varies by less than [`FLAT`] of its level.
fn flat(curve: &[(f64, Vec<f64>)]) -> bool {
    let totals: Vec<f64> = curve.iter().map(|c| c.1.iter().sum()).collect();
    let (lo, hi) = totals.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &t| (l.min(t), h.max(t)));
    hi - lo <= FLAT * hi
}

/// The camera's clock and mount-yaw corrections against the lidar's map `field`, from its
/// frames `samples`, the pose track `pose_at` (the map frame's pose of the base at a
/// stamp) and the camera's position in the base frame `centre`. `Err` says why nothing
/// could be fitted; a parameter the log does not fix is `None` in the fit.
pub fn camera_against_map(
    samples: &[CameraSample],
    centre: Point2,
    pose_at: &(dyn Fn(Stamp) -> Option<Pose2> + Sync),
    field: &DistanceField,
    search: &CameraSearch,
) -> Result<CameraLidarFit, String> {
    // The coarse grid, and the fine grids around a minimum at its edge.
    let reach = ((search.clock_span_s + 1.5 * search.clock_step_s) * 1e9).round() as i64 + 1;
    let covered = |t: Stamp| [-reach, reach].iter().all(|&d| pose_at(Stamp(t.0.saturating_add(d))).is_some());
    let kept: Vec<&CameraSample> = samples.iter().filter(|f| !f.points.is_empty() && covered(f.stamp)).collect();
    let points: usize = kept.iter().map(|f| f.points.len()).sum();
    if kept.len() < MIN_FRAMES || points < MIN_POINTS {
        return Err(format!(
            "{} frames with {points} obstacle points lie within the pose track (at least {MIN_FRAMES} frames and \
             {MIN_POINTS} points are needed)",
            kept.len()
        ));
    }
    let n = kept.len();
    let frames = kept.into_iter().enumerate().map(|(i, f)| (f, i * BLOCKS / n)).collect();
    let narrow = search.fine_reach_m.min(field.max_m());
    let scorer = Scorer { frames, pose_at, field, centre, points, narrow };
    // The yaw first: a turned mount moves every point of every frame, a late clock only
    // those of a turning robot, and a wrong yaw searched for a clock reads as one.
    let [coarse_yaw, coarse_yaw_narrow] =
        scorer.curves(&grid(0.0, search.yaw_span_rad, search.yaw_step_rad), |e| (0.0, e));
    let yaw_fixed = !flat(&coarse_yaw);
    // A least cost at a grid's edge lies outside the search: not fixed.
    let yaw_fixed = yaw_fixed && interior(&coarse_yaw);
    let e0 = if yaw_fixed { least(&coarse_yaw) } else { 0.0 };
    let [coarse_clock, coarse_clock_narrow] =
        scorer.curves(&grid(0.0, search.clock_span_s, search.clock_step_s), |d| (d, e0));
    let clock_fixed = !flat(&coarse_clock);
    let clock_fixed = clock_fixed && interior(&coarse_clock);
    let d0 = if clock_fixed { least(&coarse_clock) } else { 0.0 };
    // The two trade off where the robot turns one way for long (a turn seen late looks
    // like a turned mount): fine searches in turn until neither moves by a fine step.
    let fine = |c: f64, coarse: f64, fine: f64| grid(c, 1.5 * coarse, fine);
    let (mut d1, mut e1) = (d0, e0);
    let (mut clock, mut yaw, mut clock_curve, mut yaw_curve) = (None, None, Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        clock_curve = scorer.curve(&fine(d1, search.clock_step_s, search.clock_fine_step_s), |d| (d, e1));
        clock = clock_fixed.then(|| minimum(&clock_curve)).flatten();
        let d = clock.map_or(d1, |c| c.value);
        yaw_curve = scorer.curve(&fine(e1, search.yaw_step_rad, search.yaw_fine_step_rad), |e| (d, e));
        yaw = yaw_fixed.then(|| minimum(&yaw_curve)).flatten();
        let e = yaw.map_or(e1, |y| y.value);
        let settled = (d - d1).abs() < search.clock_fine_step_s && (e - e1).abs() < search.yaw_fine_step_rad;
        (d1, e1) = (d, e);
        if settled {
            break;
        }
    }
    let (d1, e1) = (clock.map_or(0.0, |c| c.value), yaw.map_or(0.0, |y| y.value));
    let total = |dt, eps| scorer.blocks(dt, eps)[0].iter().sum::<f64>();
    // The fine curve, and the coarse one outside it, both at the narrow reach.
    let as_curve = |fine: &[(f64, Vec<f64>)], coarse: &[(f64, Vec<f64>)]| {
        let (lo, hi) = (fine.first().map_or(0.0, |c| c.0), fine.last().map_or(0.0, |c| c.0));
        let outside = coarse.iter().filter(|c| c.0 < lo || c.0 > hi);
        let mut all: Vec<[f64; 2]> = outside.chain(fine).map(|(x, b)| [*x, scorer.rms(b.iter().sum())]).collect();
        all.sort_by(|a, b| a[0].total_cmp(&b[0]));
        all
    };
    Ok(CameraLidarFit {
        clock,
        yaw,
        cost_before_m: scorer.rms(total(0.0, 0.0)),
        cost_after_m: scorer.rms(total(d1, e1)),
        clock_curve: as_curve(&clock_curve, &coarse_clock_narrow),
        yaw_curve: as_curve(&yaw_curve, &coarse_yaw_narrow),
        frames: n,
        points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{CellIndex, OccupancyParams, Raster};

    /// A square room 8 m across of walls one cell thick, at 0.05 m.
    fn room() -> DistanceField {
        let (n, res) = (200usize, 0.05);
        let mut log_odds = vec![-2.0f32; n * n];
        for i in 20..180 {
            for (c, r) in [(i, 20), (i, 179), (20, i), (179, i)] {
                log_odds[r * n + c] = 3.0;
            }
        }
        let raster = Raster {
            width: n,
            height: n,
            resolution: res,
            origin: Point2::new(-5.0, -5.0),
            first_cell: CellIndex::new(-100, -100),
            log_odds,
            known: vec![true; n * n],
            params: OccupancyParams::default(),
        };
        DistanceField::new(&raster, |l| l > 1.0, None, 0.3).unwrap()
    }

    /// A robot at the room's centre turning back and forth at up to `rate` rad/s, and a camera at `centre`
    /// seeing the walls ahead, whose stamps are `late` seconds late and whose mount yaw is
    /// `yaw_error` off.
    fn frames(
        rate: f64,
        late: f64,
        yaw_error: f64,
        centre: Point2,
    ) -> (Vec<CameraSample>, impl Fn(Stamp) -> Option<Pose2>) {
        let pose = move |t: f64| Pose2::new(0.0, 0.0, rate * 2.0 * (0.5 * t).sin());
        let mut samples = Vec::new();
        for k in 0..200 {
            let t = 0.5 + k as f64 * 0.1;
            let truth = pose(t);
            let mut points = Vec::new();
            for j in -20..=20 {
                // Where a ray at bearing j° from the camera meets the wall, true world frame.
                let bearing = truth.theta + (j as f64).to_radians();
                let cam = truth.transform_point(centre);
                let (dx, dy) = (bearing.cos(), bearing.sin());
                let reach = [(3.975 - cam.x) / dx, (-3.975 - cam.x) / dx, (3.975 - cam.y) / dy, (-3.975 - cam.y) / dy]
                    .into_iter()
                    .filter(|r| *r > 0.0)
                    .fold(f64::INFINITY, f64::min);
                let hit = Point2::new(cam.x + reach * dx, cam.y + reach * dy);
                // In the base frame the configured mount believes in: rotated by the error
                // about the camera.
                let b = truth.inverse().transform_point(hit);
                let (s, c) = yaw_error.sin_cos();
                let (ex, ey) = (b.x - centre.x, b.y - centre.y);
                points.push(Point2::new(centre.x + c * ex - s * ey, centre.y + s * ex + c * ey));
            }
            samples.push(CameraSample { stamp: Stamp(((t + late) * 1e9).round() as i64), points, floor: Vec::new() });
        }
        let at = move |s: Stamp| Some(pose(s.0 as f64 * 1e-9));
        (samples, at)
    }

    #[test]
    fn finds_a_late_clock_and_a_turned_mount() {
        let field = room();
        let centre = Point2::new(0.3, 0.0);
        let (samples, at) = frames(0.5, 0.04, 3f64.to_radians(), centre);
        let fit = camera_against_map(&samples, centre, &at, &field, &CameraSearch::default()).unwrap();
        let (clock, yaw) = (fit.clock.unwrap(), fit.yaw.unwrap());
        assert!((clock.value + 0.04).abs() < 0.002, "{clock:?}");
        assert!((yaw.value + 3f64.to_radians()).abs() < 0.1f64.to_radians(), "{yaw:?}");
        assert!(fit.cost_after_m < 0.2 * fit.cost_before_m, "{fit:?}");
        assert!(fit.clock_curve.windows(2).all(|w| w[0][0] < w[1][0]));
    }

    /// Points on something the lidar's map lacks, 15 cm in front of its walls on one side
    /// of every frame (a shelf above the lidar's plane), pull a truncated quadratic towards
    /// them; truncated at 0.1 m near the minimum they cost the same wherever they land.
    #[test]
    fn points_the_lidar_map_lacks_do_not_pull_the_fine_search() {
        let field = room();
        let centre = Point2::new(0.3, 0.0);
        let (mut samples, at) = frames(0.5, 0.04, 3f64.to_radians(), centre);
        for f in &mut samples {
            let shelf: Vec<Point2> = f.points[25..]
                .iter()
                .map(|p| {
                    let (dx, dy) = (p.x - centre.x, p.y - centre.y);
                    let k = 1.0 - 0.15 / dx.hypot(dy);
                    Point2::new(centre.x + k * dx, centre.y + k * dy)
                })
                .collect();
            f.points.extend(shelf);
        }
        let errors = |fine_reach_m: f64| {
            let search = CameraSearch { fine_reach_m, ..CameraSearch::default() };
            let fit = camera_against_map(&samples, centre, &at, &field, &search).unwrap();
            let (clock, yaw) = (fit.clock.unwrap(), fit.yaw.unwrap());
            ((clock.value + 0.04).abs(), (yaw.value + 3f64.to_radians()).abs().to_degrees())
        };
        let (narrow, wide) = (errors(CameraSearch::default().fine_reach_m), errors(0.3));
        eprintln!("clock and yaw errors: narrow {narrow:?}, wide {wide:?}");
        assert!(narrow.0 < 0.002 && narrow.1 < 0.1, "{narrow:?}");
        assert!(wide.0 > 2.0 * narrow.0 || wide.1 > 2.0 * narrow.1, "{wide:?} against {narrow:?}");
    }

    /// The curves are scored on every thread: the fit is the same to the bit on one.
    #[cfg(feature = "parallel")]
    #[test]
    fn the_fit_is_the_same_on_one_thread_and_on_two() {
        let field = room();
        let centre = Point2::new(0.3, 0.0);
        let (samples, at) = frames(0.5, 0.04, 3f64.to_radians(), centre);
        let fit = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let f = pool.install(|| camera_against_map(&samples, centre, &at, &field, &CameraSearch::default()));
            format!("{:?}", f.unwrap())
        };
        assert_eq!(fit(1), fit(2));
    }

    #[test]
    fn a_robot_that_never_turns_leaves_the_clock_undetermined() {
        let field = room();
        let centre = Point2::new(0.3, 0.0);
        let (samples, at) = frames(0.0, 0.04, 0.0, centre);
        let fit = camera_against_map(&samples, centre, &at, &field, &CameraSearch::default()).unwrap();
        assert!(fit.clock.is_none(), "{fit:?}");
        // Every frame the same: the jackknife's interval has no width.
        assert!(fit.yaw.unwrap().value.abs() < 1e-6, "{fit:?}");
    }

    #[test]
    fn too_few_frames_is_a_reason() {
        let field = room();
        let centre = Point2::new(0.3, 0.0);
        let (samples, at) = frames(0.5, 0.0, 0.0, centre);
        let e = camera_against_map(&samples[..5], centre, &at, &field, &CameraSearch::default()).unwrap_err();
        assert!(e.contains("5 frames"), "{e}");
    }
}
