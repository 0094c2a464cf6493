//! The inverse sensor model of a 2D lidar (Thrun et al., *Probabilistic Robotics*, §9.2,
//! Table 9.2, simplified to the design document's two-level model).
//!
//! A return at range `r` is evidence that the cells the beam crossed are free
//! (`p_free`, default 0.4, `l ≈ -0.405`) and that its end cell is occupied (`p_occ`,
//! default 0.9, `l ≈ 2.197`). The asymmetry is deliberate: many beams cross a free cell,
//! few end in a wall cell, and strong free evidence would erase thin walls.
//!
//! **Invalid returns** — NaN, ±inf, 0, negative, or below `min_range` — are what lidars
//! report on glass, black or specular surfaces and when blinded. They are never evidence
//! of any kind (the document's §4.3 habit 2: a ring of ghosts means they were not
//! filtered), and each kind is counted. **No-returns** — at or beyond `max_range` — follow
//! [`MaxRangePolicy`].
//!
//! **The lidar's own faults** — mixed pixels at depth edges, speckles, the robot's own
//! body in the field of view — are removed by the [`ScanFilters`] of
//! [`LidarParams::filters`] before a beam becomes a ray; a dropped beam is no evidence
//! at all, and each filter's drops are counted in [`ReturnCounts`].

use super::lidar_filters::{Dropped, ScanFilters};
use crate::geometry::{PlanarMount, Point2, Pose2};
use crate::measurement::{Evidence, RangeData, Ray, SensorId};
use crate::time::Stamp;
use serde::{Deserialize, Serialize};

/// What to do with a return at or beyond `max_range`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaxRangePolicy {
    /// Ignore it (the design document's rule: `r >= max_range` is skipped).
    #[default]
    Skip,
    /// Free space up to `max_range` along the beam, no obstacle: "nothing within range",
    /// what ROS users expect from a no-return (costmap_2d's `inf_is_valid` clearing).
    Clear,
}

/// Parameters of the lidar inverse model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LidarParams {
    /// Occupancy probability of a beam's end cell.
    pub p_occ: f64,
    /// Occupancy probability of a cell a beam crossed.
    pub p_free: f64,
    /// Returns below this (metres) are invalid.
    pub min_range: f64,
    /// Returns at or beyond this (metres) are no-returns.
    pub max_range: f64,
    /// What no-returns do.
    pub max_range_policy: MaxRangePolicy,
    /// The scan filters for the lidar's own faults (all off by default).
    #[serde(default)]
    pub filters: ScanFilters,
}

impl Default for LidarParams {
    fn default() -> Self {
        Self {
            p_occ: 0.9,
            p_free: 0.4,
            min_range: 0.1,
            max_range: 10.0,
            max_range_policy: MaxRangePolicy::Skip,
            filters: ScanFilters::default(),
        }
    }
}

/// One 2D scan in the sensor frame, as `sensor_msgs/LaserScan` carries it.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScan {
    /// Acquisition time of the first beam.
    pub stamp: Stamp,
    /// Angle of beam 0 in the sensor frame, radians (counter-clockwise from x).
    pub angle_min: f64,
    /// Angle between consecutive beams, radians.
    pub angle_increment: f64,
    /// Ranges, metres, as the sensor reported them (invalid values included).
    pub ranges: Vec<f32>,
}

impl LaserScan {
    /// A scan of `n` evenly spaced beams from `angle_min` to `angle_max` inclusive.
    pub fn evenly_spaced(stamp: Stamp, angle_min: f64, angle_max: f64, ranges: Vec<f32>) -> Self {
        let n = ranges.len();
        let inc = if n > 1 { (angle_max - angle_min) / (n - 1) as f64 } else { 0.0 };
        Self { stamp, angle_min, angle_increment: inc, ranges }
    }
}

/// Counts of each kind of return, per run. Every beam lands in exactly one field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ReturnCounts {
    /// Valid returns in `[min_range, max_range)`: free along the beam, occupied at the end.
    pub valid: u64,
    /// At or beyond `max_range`, finite (cleared or skipped by the policy).
    pub no_return: u64,
    /// NaN.
    pub nan: u64,
    /// +inf or -inf.
    pub infinite: u64,
    /// Exactly zero.
    pub zero: u64,
    /// Negative.
    pub negative: u64,
    /// Positive but below `min_range`.
    pub below_min: u64,
    /// Valid returns dropped by the shadow (veiling) filter: mixed pixels at depth edges.
    #[serde(default)]
    pub shadow: u64,
    /// Valid returns dropped by the speckle filter.
    #[serde(default)]
    pub speckle: u64,
    /// Returns and no-returns outside the angular bounds.
    #[serde(default)]
    pub out_of_angle: u64,
    /// Valid returns inside the self box (the robot's own body).
    #[serde(default)]
    pub in_box: u64,
}

impl ReturnCounts {
    /// Beams of every kind.
    pub fn total(&self) -> u64 {
        self.valid + self.no_return + self.invalid() + self.filtered()
    }

    /// Beams the scan filters dropped: shadow, speckle, out of angle, in the self box.
    pub fn filtered(&self) -> u64 {
        self.shadow + self.speckle + self.out_of_angle + self.in_box
    }

    /// Beams that are never evidence: NaN, ±inf, zero, negative, below `min_range`.
    pub fn invalid(&self) -> u64 {
        self.nan + self.infinite + self.zero + self.negative + self.below_min
    }

    /// Adds another run's counts.
    pub fn add(&mut self, o: &ReturnCounts) {
        self.valid += o.valid;
        self.no_return += o.no_return;
        self.nan += o.nan;
        self.infinite += o.infinite;
        self.zero += o.zero;
        self.negative += o.negative;
        self.below_min += o.below_min;
        self.shadow += o.shadow;
        self.speckle += o.speckle;
        self.out_of_angle += o.out_of_angle;
        self.in_box += o.in_box;
    }
}

/// The lidar inverse model with its mount on the robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LidarModel {
    params: LidarParams,
    mount: PlanarMount,
}

/// How one range reading is classified.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Valid,
    NoReturn,
    Nan,
    Infinite,
    Zero,
    Negative,
    BelowMin,
}

impl LidarModel {
    /// A model with validated `params` and the sensor's planar mount.
    pub fn new(params: LidarParams, mount: PlanarMount) -> Self {
        Self { params, mount }
    }

    /// The model's parameters.
    pub fn params(&self) -> &LidarParams {
        &self.params
    }

    /// The sensor's mount.
    pub fn mount(&self) -> &PlanarMount {
        &self.mount
    }

    /// This model restricted to the limits a message states for its sensor
    /// (`sensor_msgs/LaserScan` `range_min` / `range_max`): the valid interval becomes
    /// `[max(min_range, range_min), min(max_range, range_max))`. Readings at or beyond
    /// the sensor's own `range_max` are its "no return" values (CARMEN's 81.91, a ROS
    /// driver's `range_max + 1`) and must never become obstacles. Non-finite or
    /// non-positive limits mean "not stated" and are ignored.
    pub fn limited_to(&self, range_min: f32, range_max: f32) -> LidarModel {
        let mut p = self.params;
        if range_min.is_finite() && range_min > 0.0 {
            p.min_range = p.min_range.max(range_min as f64);
        }
        if range_max.is_finite() && range_max > 0.0 {
            p.max_range = p.max_range.min(range_max as f64);
        }
        if p.min_range >= p.max_range {
            // A message claiming an empty interval: nothing it reports is valid.
            p.min_range = p.max_range;
        }
        LidarModel { params: p, mount: self.mount }
    }

    /// The evidence probabilities of this model.
    pub fn evidence(&self) -> Evidence {
        Evidence { p_hit: self.params.p_occ, p_miss: self.params.p_free }
    }

    #[inline]
    fn classify(&self, r: f32) -> Kind {
        let r = r as f64;
        if r.is_nan() {
            Kind::Nan
        } else if r.is_infinite() {
            Kind::Infinite
        } else if r == 0.0 {
            Kind::Zero
        } else if r < 0.0 {
            Kind::Negative
        } else if r < self.params.min_range {
            Kind::BelowMin
        } else if r >= self.params.max_range {
            Kind::NoReturn
        } else {
            Kind::Valid
        }
    }

    /// Turns a scan taken from `world_from_base` into rays in the world frame, written
    /// into `out` (its buffer is reused), and adds the scan's returns to `counts`.
    pub fn scan_to_range_data(
        &self,
        sensor: SensorId,
        scan: &LaserScan,
        world_from_base: Pose2,
        out: &mut RangeData,
        counts: &mut ReturnCounts,
    ) {
        self.scan_to_range_data_with(sensor, scan, |_| world_from_base, out, counts)
    }

    /// Like [`scan_to_range_data`](Self::scan_to_range_data), with the robot pose given
    /// per beam (`pose_of_beam(i)`), for de-skewing scans taken while moving.
    pub fn scan_to_range_data_with(
        &self,
        sensor: SensorId,
        scan: &LaserScan,
        mut pose_of_beam: impl FnMut(usize) -> Pose2,
        out: &mut RangeData,
        counts: &mut ReturnCounts,
    ) {
        out.stamp = scan.stamp;
        out.sensor = sensor;
        out.evidence = self.evidence();
        out.rays.clear();
        let clear = self.params.max_range_policy == MaxRangePolicy::Clear;
        let origin_in_base = self.mount.origin_in_base();
        let filters = &self.params.filters;
        let filtering = filters.any();
        let beam_angle = |i: usize| scan.angle_min + i as f64 * scan.angle_increment;
        for (i, &r) in scan.ranges.iter().enumerate() {
            let kind = self.classify(r);
            let (range, hit) = match kind {
                Kind::Valid => {
                    if filtering {
                        let valid = |x: f32| self.classify(x) == Kind::Valid;
                        let verdict =
                            filters.verdict(&scan.ranges, i, scan.angle_increment, beam_angle(i), &self.mount, valid);
                        if let Some(d) = verdict {
                            match d {
                                Dropped::Angle => counts.out_of_angle += 1,
                                Dropped::Box => counts.in_box += 1,
                                Dropped::Shadow => counts.shadow += 1,
                                Dropped::Speckle => counts.speckle += 1,
                            }
                            continue;
                        }
                    }
                    counts.valid += 1;
                    (r as f64, true)
                }
                Kind::NoReturn => {
                    if filtering && filters.outside_angles(beam_angle(i)) {
                        counts.out_of_angle += 1;
                        continue;
                    }
                    counts.no_return += 1;
                    if !clear {
                        continue;
                    }
                    (self.params.max_range, false)
                }
                Kind::Nan => {
                    counts.nan += 1;
                    continue;
                }
                Kind::Infinite => {
                    counts.infinite += 1;
                    continue;
                }
                Kind::Zero => {
                    counts.zero += 1;
                    continue;
                }
                Kind::Negative => {
                    counts.negative += 1;
                    continue;
                }
                Kind::BelowMin => {
                    counts.below_min += 1;
                    continue;
                }
            };
            let world_from_base = pose_of_beam(i);
            let angle = world_from_base.theta + self.mount.beam_angle_in_base(beam_angle(i));
            let origin = world_from_base * origin_in_base;
            let (s, c) = angle.sin_cos();
            out.rays.push(Ray { origin, end: Point2::new(origin.x + range * c, origin.y + range * s), hit });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mount3;
    use std::f64::consts::FRAC_PI_2;

    fn run(policy: MaxRangePolicy, ranges: Vec<f32>) -> (RangeData, ReturnCounts) {
        let model =
            LidarModel::new(LidarParams { max_range_policy: policy, ..Default::default() }, PlanarMount::default());
        let scan = LaserScan::evenly_spaced(Stamp(7), -FRAC_PI_2, FRAC_PI_2, ranges);
        let mut out = RangeData::empty(SensorId(0), model.evidence());
        let mut counts = ReturnCounts::default();
        model.scan_to_range_data(SensorId(3), &scan, Pose2::IDENTITY, &mut out, &mut counts);
        (out, counts)
    }

    #[test]
    fn invalid_returns_are_counted_never_used() {
        let corpus = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -1.0, 1e-9, 10.0, 25.0, 3.0];
        let (rd, c) = run(MaxRangePolicy::Skip, corpus.clone());
        assert_eq!(rd.rays.len(), 1);
        assert_eq!(rd.stamp, Stamp(7));
        assert_eq!(rd.sensor, SensorId(3));
        assert_eq!(
            c,
            ReturnCounts {
                valid: 1,
                no_return: 2,
                nan: 1,
                infinite: 2,
                zero: 1,
                negative: 1,
                below_min: 1,
                ..Default::default()
            }
        );
        assert_eq!(c.total(), corpus.len() as u64);
        // Under `clear` the two no-returns clear to max_range without a hit.
        let (rd, c) = run(MaxRangePolicy::Clear, corpus);
        assert_eq!(rd.rays.len(), 3);
        let misses: Vec<_> = rd.rays.iter().filter(|r| !r.hit).collect();
        assert_eq!(misses.len(), 2);
        for m in misses {
            assert!((m.end.distance(m.origin) - 10.0).abs() < 1e-9);
        }
        assert_eq!(c.invalid(), 6);
    }

    #[test]
    fn message_limits_narrow_the_model() {
        let m = LidarModel::new(LidarParams { max_range: 40.0, ..Default::default() }, PlanarMount::default());
        let l = m.limited_to(0.2, 30.0);
        assert_eq!(l.params().min_range, 0.2f32 as f64);
        assert_eq!(l.params().max_range, 30.0);
        // Limits wider than the model's, or unstated, change nothing.
        assert_eq!(m.limited_to(0.0, f32::INFINITY), m);
        assert_eq!(m.limited_to(f32::NAN, 80.0).params().max_range, 40.0);
        // CARMEN's 81.91 no-return under a line's range_max of 81 is a no-return.
        assert_eq!(m.limited_to(0.0, 81.0).classify(81.91), Kind::NoReturn);
        let empty = m.limited_to(50.0, 20.0);
        assert_eq!(empty.classify(25.0), Kind::NoReturn);
        assert_eq!(empty.classify(15.0), Kind::BelowMin);
    }

    #[test]
    fn beams_follow_pose_and_mount() {
        let mount = Mount3 { x: 0.5, yaw: FRAC_PI_2, ..Default::default() }.to_planar(0.01).unwrap();
        let model = LidarModel::new(LidarParams::default(), mount);
        let scan = LaserScan { stamp: Stamp(0), angle_min: 0.0, angle_increment: 0.0, ranges: vec![2.0] };
        let mut out = RangeData::empty(SensorId(0), model.evidence());
        let mut counts = ReturnCounts::default();
        // Robot at (1, 1) facing +x; lidar 0.5 m ahead looking left: hit at (1.5, 3).
        model.scan_to_range_data(SensorId(0), &scan, Pose2::new(1.0, 1.0, 0.0), &mut out, &mut counts);
        let r = out.rays[0];
        assert!(r.origin.distance(Point2::new(1.5, 1.0)) < 1e-12);
        assert!(r.end.distance(Point2::new(1.5, 3.0)) < 1e-6, "{:?}", r.end);
    }
}
