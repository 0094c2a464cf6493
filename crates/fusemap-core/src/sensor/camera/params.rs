//! The camera model's parameters.

use super::CameraError;
use serde::{Deserialize, Serialize};

/// The largest pixel stride accepted (every 64th pixel of every 64th row).
pub const MAX_STRIDE: u32 = 64;
/// The largest `max_depth_m` accepted, metres: beyond this no depth camera measures.
pub const MAX_DEPTH_LIMIT_M: f64 = 100.0;

/// Parameters of the semantic camera model. Heights are base-frame `z`, with the floor
/// at `z = 0` (REP 103: `base_link` on the floor plane, z up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraParams {
    /// Use every `stride`-th pixel of every `stride`-th row (default 4: a 640×480 frame
    /// gives 19,200 points, already several per 5 cm cell near the robot).
    pub stride: u32,
    /// Depths below this are skipped and counted, metres (default 0.3: below the range of
    /// usual RGB-D cameras).
    pub min_depth_m: f64,
    /// Depths beyond this are skipped and counted, metres (default 6.0: at σ = k·d² with
    /// the default k the error there is 18 cm, several cells).
    pub max_depth_m: f64,
    /// `k` of the depth noise `σ = k·d²`, metres⁻¹ (default 0.005: 5 mm at 1 m, 18 cm at
    /// 6 m). The quadratic growth is that of structured-light and stereo depth
    /// (Khoshelham & Oude Elberink 2012, *Accuracy and resolution of Kinect depth data*;
    /// Nguyen, Izadi & Lovell 2012, *Modeling Kinect sensor noise*), and the design
    /// document's "depth error grows with the square of depth" (§3.4). 0: exact depth.
    pub depth_sigma_k: f64,
    /// Base-frame `z` below which a point is floor, metres (default 0.08: floor noise, a
    /// cable, a threshold). Points with `z` below `-floor_band_m` are a depth or mount
    /// error and are counted, not used.
    pub floor_band_m: f64,
    /// The top of the obstacle band, metres (default 2.5): points from `floor_band_m` up
    /// to this are obstacles the robot could hit; higher ones (ceiling, lamps, ducts) are
    /// skipped and counted.
    pub obstacle_max_z_m: f64,
    /// The camera's weak free evidence along its rays (default 0.45, §3.4: the camera's
    /// free-space evidence is poor; weaker than the lidar's 0.4). Also the ceiling of a
    /// floor point's own evidence (see `CameraModel::occupancy_evidence`).
    pub p_free: f64,
    /// Scales every occupancy contribution of the camera (default 0.5, §2.2: geometry
    /// comes from the geometric sensor; the camera writes occupancy only at a lower
    /// weight, so a backlit shadow labelled "wall" cannot build a wall on its own).
    pub occupancy_weight: f64,
    /// Factor on the semantic weight of a label that contradicts its point's band
    /// (default 0.2): a "wall" label on a floor-band point (the backlit shadow) or a
    /// "floor" label inside the obstacle band.
    pub inconsistent_label_weight: f64,
}

impl Default for CameraParams {
    fn default() -> Self {
        Self {
            stride: 4,
            min_depth_m: 0.3,
            max_depth_m: 6.0,
            depth_sigma_k: 0.005,
            floor_band_m: 0.08,
            obstacle_max_z_m: 2.5,
            p_free: 0.45,
            occupancy_weight: 0.5,
            inconsistent_label_weight: 0.2,
        }
    }
}

impl CameraParams {
    /// Checks every parameter; the error names the field.
    pub fn validate(&self) -> Result<(), CameraError> {
        let bad = |name: &'static str, message: String| Err(CameraError::Parameter { name, message });
        if self.stride == 0 || self.stride > MAX_STRIDE {
            return bad("stride", format!("must be within 1..={MAX_STRIDE} pixels, got {}", self.stride));
        }
        for (name, v) in [
            ("min_depth_m", self.min_depth_m),
            ("max_depth_m", self.max_depth_m),
            ("depth_sigma_k", self.depth_sigma_k),
            ("floor_band_m", self.floor_band_m),
            ("obstacle_max_z_m", self.obstacle_max_z_m),
            ("p_free", self.p_free),
            ("occupancy_weight", self.occupancy_weight),
            ("inconsistent_label_weight", self.inconsistent_label_weight),
        ] {
            if !v.is_finite() {
                return bad(name, format!("must be a finite number, got {v}"));
            }
        }
        if self.min_depth_m < 0.0 {
            return bad("min_depth_m", format!("must be >= 0 metres, got {}", self.min_depth_m));
        }
        if self.max_depth_m <= self.min_depth_m || self.max_depth_m > MAX_DEPTH_LIMIT_M {
            return bad(
                "max_depth_m",
                format!(
                    "must be above min_depth_m ({}) and at most {MAX_DEPTH_LIMIT_M} metres, got {}",
                    self.min_depth_m, self.max_depth_m
                ),
            );
        }
        if self.depth_sigma_k < 0.0 {
            return bad("depth_sigma_k", format!("must be >= 0 (sigma = k d^2), got {}", self.depth_sigma_k));
        }
        if self.floor_band_m <= 0.0 {
            return bad("floor_band_m", format!("must be > 0 metres, got {}", self.floor_band_m));
        }
        if self.obstacle_max_z_m <= self.floor_band_m {
            return bad(
                "obstacle_max_z_m",
                format!("must be above floor_band_m ({}), got {}", self.floor_band_m, self.obstacle_max_z_m),
            );
        }
        if self.p_free <= 0.0 || self.p_free >= 0.5 {
            return bad("p_free", format!("must be a probability in (0, 0.5): free evidence, got {}", self.p_free));
        }
        for (name, v) in
            [("occupancy_weight", self.occupancy_weight), ("inconsistent_label_weight", self.inconsistent_label_weight)]
        {
            if !(0.0..=1.0).contains(&v) {
                return bad(name, format!("must be within [0, 1], got {v}"));
            }
        }
        Ok(())
    }

    /// The depth's standard deviation at depth `d` metres, `σ = k·d²`.
    #[inline]
    pub fn depth_sigma(&self, d: f64) -> f64 {
        self.depth_sigma_k * d * d
    }
}
