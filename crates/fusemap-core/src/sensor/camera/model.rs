//! The semantic camera's sensor model: label + depth pixels to class-labelled points in
//! the map plane, and the rule that turns such a point into occupancy and semantic
//! evidence.
//!
//! ## Projection
//! A pixel `(u, v)` at the stride, through its centre (at `(u, v)` itself in the
//! convention of `CameraInfo`, see [`Pinhole`]), with depth `d` along the optical axis, is
//! the optical-frame point `d · ray(u, v)`
//! ([`Pinhole::ray`]); the mount `base_from_optical` (full 3D, REP 103 optical axes)
//! takes it to the base frame, whose `z` (floor at 0) decides its [`Band`]; the robot's
//! planar pose `world_from_base` takes its `(x, y)` to the map. The rays of the used
//! pixels, rotated into the base frame, are precomputed once per model (the pinhole, the
//! stride and the mount do not change between frames) as one vector per column plus one
//! per row, so the tables cost `O(width + height)` memory and a pixel costs a few
//! multiply-adds.
//!
//! ## Depth weight
//! Depth error grows with the square of depth (§3.4): `σ = k·d²`. A point's weight is the
//! probability that its true position lies in the cell it was measured in: for an error
//! along the ray with a Gaussian of `σ` and a cell of side `c` around the measured point,
//! `P(|e| < c/2) = erf(c / (2√2·σ))` (1 when `σ = 0`). It is the mass of the Gaussian
//! measurement model that falls in the cell, the quantity a Gaussian `p_hit` spreads over
//! the cells of a beam (Thrun et al., *Probabilistic Robotics*, §6.3.1). Near points get
//! ≈1, points at 6 m with the default `k` and 5 cm cells about 0.11: their log-odds
//! contributions shrink as the depth grows.
//!
//! ## Evidence: geometry decides the sign, the class the strength
//! A point's height band says whether it is floor or obstacle; its label only says how
//! strongly. A floor-band point is free evidence whatever its label, an obstacle-band
//! point occupied evidence (or none). Labels are what the camera is bad at under
//! backlight (§1's opening picture: facing the light, the camera takes shadows on the
//! floor for obstacles): a backlit floor patch labelled "wall" still has floor depth, so
//! it stays floor in the occupancy layer, and its "wall" label enters the semantic layer
//! only at `inconsistent_label_weight`. See [`CameraModel::occupancy_evidence`] and
//! [`CameraModel::semantic_weight`].

use super::{
    Band, CameraError, CameraObservation, CameraParams, CameraPoint, ClassTable, DepthImage, LabelImage, Pinhole,
    PixelCounts,
};
use crate::geometry::{Mount3, Point2, Pose2, Pose3};

/// The semantic camera model: intrinsics, mount, parameters, the map's cell size and the
/// class table, with the per-pixel rays precomputed.
#[derive(Clone, Debug)]
pub struct CameraModel {
    pinhole: Pinhole,
    base_from_optical: Pose3,
    params: CameraParams,
    cell_size_m: f64,
    classes: ClassTable,
    /// Per used column `u`: `x_u · R·e_x`, with `x_u = (u - cx) / fx`.
    cols: Vec<[f64; 3]>,
    /// Per used row `v`: `y_v · R·e_y + R·e_z`, with `y_v = (v - cy) / fy`.
    rows: Vec<[f64; 3]>,
    /// Per class index: its pixels are skipped.
    ignored: Vec<bool>,
}

impl CameraModel {
    /// A model, checked: `params` valid, the mount finite, the cell size finite and > 0.
    ///
    /// `base_from_optical` is the camera's optical frame (REP 103: x right, y down,
    /// z forward) in `base_link`; [`optical_mount`] builds one from a heading and a pitch.
    /// `cell_size_m` is the map's resolution (it sets the depth weight). `classes` are the
    /// ids the label images use.
    pub fn new(
        pinhole: Pinhole,
        base_from_optical: Pose3,
        params: CameraParams,
        cell_size_m: f64,
        classes: ClassTable,
    ) -> Result<CameraModel, CameraError> {
        params.validate()?;
        // Renormalised: a hand-written Pose3 may carry a non-unit quaternion.
        let base_from_optical = Pose3::new(base_from_optical.translation, base_from_optical.rotation);
        if !base_from_optical.is_finite() {
            return Err(CameraError::Mount {
                translation: base_from_optical.translation,
                rotation: base_from_optical.rotation,
            });
        }
        if !cell_size_m.is_finite() || cell_size_m <= 0.0 {
            return Err(CameraError::Parameter {
                name: "cell_size_m",
                message: format!("must be a finite number > 0 metres, got {cell_size_m}"),
            });
        }
        let ex = base_from_optical.rotate([1.0, 0.0, 0.0]);
        let ey = base_from_optical.rotate([0.0, 1.0, 0.0]);
        let ez = base_from_optical.rotate([0.0, 0.0, 1.0]);
        let s = params.stride as usize;
        let cols = (0..pinhole.width)
            .step_by(s)
            .map(|u| {
                let x = (f64::from(u) - pinhole.cx) / pinhole.fx;
                ex.map(|e| x * e)
            })
            .collect();
        let rows = (0..pinhole.height)
            .step_by(s)
            .map(|v| {
                let y = (f64::from(v) - pinhole.cy) / pinhole.fy;
                [0, 1, 2].map(|k| y * ey[k] + ez[k])
            })
            .collect();
        let ignored = classes.iter().map(|c| c.ignore).collect();
        Ok(CameraModel { pinhole, base_from_optical, params, cell_size_m, classes, cols, rows, ignored })
    }

    /// The intrinsics.
    pub fn pinhole(&self) -> &Pinhole {
        &self.pinhole
    }

    /// The mount `base_from_optical` (unit quaternion).
    pub fn base_from_optical(&self) -> &Pose3 {
        &self.base_from_optical
    }

    /// The parameters.
    pub fn params(&self) -> &CameraParams {
        &self.params
    }

    /// The map cell size the depth weights refer to, metres.
    pub fn cell_size_m(&self) -> f64 {
        self.cell_size_m
    }

    /// The class table of the label images.
    pub fn classes(&self) -> &ClassTable {
        &self.classes
    }

    /// The weight of a point at depth `d` metres: `erf(c / (2√2·σ))`, `σ = k·d²`, `c` the
    /// cell size (see [`depth_weight`]).
    #[inline]
    pub fn point_weight(&self, d: f64) -> f32 {
        (depth_weight(self.cell_size_m, self.params.depth_sigma(d)) as f32).max(f32::MIN_POSITIVE)
    }

    /// Refuses a frame whose images are not the camera's size, or a pose that is not finite.
    fn check_frame(&self, labels: &LabelImage, depth: &DepthImage, world_from_base: Pose2) -> Result<(), CameraError> {
        let (w, h) = (self.pinhole.width, self.pinhole.height);
        if (labels.width, labels.height) != (w, h)
            || (depth.width, depth.height) != (w, h)
            || labels.labels.len() as u64 != self.pinhole.pixels()
            || depth.metres.len() as u64 != self.pinhole.pixels()
        {
            return Err(CameraError::ImageSize {
                labels: (labels.width, labels.height),
                depth: (depth.width, depth.height),
                camera: (w, h),
            });
        }
        if !world_from_base.is_finite() {
            let Pose2 { x, y, theta } = world_from_base;
            return Err(CameraError::Pose { x, y, theta });
        }
        Ok(())
    }

    /// Projects one label + depth frame taken from `world_from_base` into `out` (its
    /// points are cleared and its buffer reused; `stamp` and `sensor` are left for the
    /// caller to set), and adds what became of each pixel to `counts`.
    ///
    /// Both images must have the pinhole's size, else an error naming all three sizes.
    /// Bad pixels are counted, never an error (see [`PixelCounts`]).
    pub fn project(
        &self,
        labels: &LabelImage,
        depth: &DepthImage,
        world_from_base: Pose2,
        out: &mut CameraObservation,
        counts: &mut PixelCounts,
    ) -> Result<(), CameraError> {
        self.check_frame(labels, depth, world_from_base)?;
        let w = self.pinhole.width;
        out.points.clear();
        let (sin, cos) = world_from_base.theta.sin_cos();
        let (px, py) = (world_from_base.x, world_from_base.y);
        let to_map = |bx: f64, by: f64| Point2::new(px + cos * bx - sin * by, py + sin * bx + cos * by);
        let t = self.base_from_optical.translation;
        out.origin = to_map(t[0], t[1]);

        let p = &self.params;
        let (floor, top) = (p.floor_band_m, p.obstacle_max_z_m);
        let mut c = PixelCounts::default();
        let stride = p.stride as usize;
        for (row, r) in self.rows.iter().enumerate() {
            let start = row * stride * w as usize;
            let label_row = &labels.labels[start..start + w as usize];
            let depth_row = &depth.metres[start..start + w as usize];
            for (col, a) in self.cols.iter().enumerate() {
                let u = col * stride;
                c.seen += 1;
                let Some(class) = self.classes.index_of(label_row[u]) else {
                    c.unknown_class += 1;
                    continue;
                };
                if self.ignored[class as usize] {
                    c.ignored_class += 1;
                    continue;
                }
                let d = depth_row[u] as f64;
                if !d.is_finite() || d <= 0.0 {
                    c.no_depth += 1;
                    continue;
                }
                if d < p.min_depth_m || d > p.max_depth_m {
                    c.out_of_depth_range += 1;
                    continue;
                }
                let z = t[2] + d * (a[2] + r[2]);
                let band = if z < -floor {
                    c.below_floor += 1;
                    continue;
                } else if z < floor {
                    Band::Floor
                } else if z <= top {
                    Band::Obstacle
                } else {
                    c.above_band += 1;
                    continue;
                };
                let bx = t[0] + d * (a[0] + r[0]);
                let by = t[1] + d * (a[1] + r[1]);
                c.used += 1;
                out.points.push(CameraPoint {
                    end: to_map(bx, by),
                    class,
                    weight: self.point_weight(d),
                    band,
                    height: z as f32,
                });
            }
        }
        counts.add(&c);
        Ok(())
    }

    /// The occupancy evidence of a point at its own cell, as `(probability, scale)`: the
    /// occupancy layer adds `scale · (logit(probability) - l_0)`. `None`: the point gives
    /// no occupancy evidence.
    ///
    /// Geometry decides the sign, the class the strength:
    /// * a floor-band point is free evidence of probability `min(class.p_occupied,
    ///   p_free)` at scale `point.weight · occupancy_weight`: a floor label gives its own
    ///   (stronger) free evidence, any other label only the camera's weak `p_free`, so a
    ///   backlit floor patch labelled "wall" stays floor;
    /// * an obstacle-band point is occupied evidence of probability `class.p_occupied` at
    ///   scale `class.weight · point.weight · occupancy_weight`; a label with
    ///   `p_occupied ≤ 0.5` there (a "floor" label on something 1 m high) cannot say how
    ///   strongly it is occupied and gives `None` rather than free evidence, which
    ///   would contradict the geometry;
    /// * dynamic classes give `None`: they belong in the dynamic layer, never in static
    ///   occupancy (§2.4); ignored classes and indices outside `classes` give `None` too.
    ///
    /// `classes` is the table the model was built with. The free evidence along the ray
    /// from the observation's origin to the point (`p_free` at `occupancy_weight`) is the
    /// layer's to apply.
    pub fn occupancy_evidence(&self, p: &CameraPoint, classes: &ClassTable) -> Option<(f64, f32)> {
        let class = classes.try_get(p.class)?;
        if class.dynamic || class.ignore {
            return None;
        }
        let occupancy_weight = self.params.occupancy_weight as f32;
        match p.band {
            Band::Floor => Some((class.p_occupied.min(self.params.p_free), p.weight * occupancy_weight)),
            Band::Obstacle if class.p_occupied > 0.5 => {
                Some((class.p_occupied, class.weight as f32 * p.weight * occupancy_weight))
            }
            Band::Obstacle => None,
        }
    }

    /// The weight of a point's label in the semantic layer: `class.weight · point.weight`,
    /// times `inconsistent_label_weight` when the label contradicts the point's band (a
    /// class with `p_occupied > 0.5` on a floor-band point, the backlit shadow; one with
    /// `p_occupied < 0.5` inside the obstacle band). 0 for ignored classes and indices
    /// outside `classes`.
    pub fn semantic_weight(&self, p: &CameraPoint, classes: &ClassTable) -> f32 {
        let Some(class) = classes.try_get(p.class) else { return 0.0 };
        if class.ignore {
            return 0.0;
        }
        let w = class.weight as f32 * p.weight;
        let inconsistent = match p.band {
            Band::Floor => class.p_occupied > 0.5,
            Band::Obstacle => class.p_occupied < 0.5,
        };
        if inconsistent {
            w * self.params.inconsistent_label_weight as f32
        } else {
            w
        }
    }
}

/// The probability that a point measured with a Gaussian error of `sigma` along its ray
/// lies in the cell of side `cell` centred on it: `erf(cell / (2√2·sigma))`, 1 when
/// `sigma` is 0. In (0, 1] for finite positive `cell` and `sigma`.
pub fn depth_weight(cell: f64, sigma: f64) -> f64 {
    if sigma <= 0.0 {
        return 1.0;
    }
    let w = erf(cell / (2.0 * std::f64::consts::SQRT_2 * sigma));
    // erf of a tiny positive argument may round to 0 in the tail of the series: keep the
    // weight positive, as documented.
    w.clamp(f64::MIN_POSITIVE, 1.0)
}

/// The error function for `x ≥ 0` (negative `x` by symmetry), absolute error below 2e-7:
/// its Maclaurin series up to `x¹¹` below 0.5 (truncation error < 2e-8 there), and
/// Abramowitz & Stegun 7.1.26 above (|ε| ≤ 1.5e-7).
pub(crate) fn erf(x: f64) -> f64 {
    if x < 0.0 {
        return -erf(-x);
    }
    if x < 0.5 {
        // 2/√π · Σ (-1)^n x^(2n+1) / (n! (2n+1)), n = 0..5, in Horner form in x².
        let x2 = x * x;
        let s = 1.0
            + x2 * (-1.0 / 3.0 + x2 * (1.0 / 10.0 + x2 * (-1.0 / 42.0 + x2 * (1.0 / 216.0 + x2 * (-1.0 / 1320.0)))));
        return std::f64::consts::FRAC_2_SQRT_PI * x * s;
    }
    if x > 6.0 {
        return 1.0;
    }
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly =
        t * (0.254_829_592 + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    1.0 - poly * (-x * x).exp()
}

/// The mount `base_from_optical` of a camera at `translation` in `base_link`, looking
/// along heading `yaw` (radians, about the base's z axis; 0 = forward) and pitched down by
/// `pitch_down` radians. The optical frame follows REP 103 (x right, y down,
/// z forward): a level forward camera is roll = -π/2, pitch = 0, yaw = -π/2 in the RPY
/// of the optical frame.
pub fn optical_mount(translation: [f64; 3], yaw: f64, pitch_down: f64) -> Pose3 {
    let body = Mount3 { pitch: pitch_down, yaw, ..Default::default() };
    let level = Mount3 { roll: -std::f64::consts::FRAC_PI_2, yaw: -std::f64::consts::FRAC_PI_2, ..Default::default() };
    let r = Pose3::new([0.0; 3], body.quaternion()).compose(&Pose3::new([0.0; 3], level.quaternion()));
    Pose3::new(translation, r.rotation)
}
