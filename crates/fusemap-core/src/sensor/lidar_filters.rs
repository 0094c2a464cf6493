//! Scan filters for the lidar's own faults, with the semantics ROS users know from the
//! `laser_filters` package (its `ScanShadowsFilter`, `LaserScanSpeckleFilter` in distance
//! mode, `LaserScanAngularBoundsFilter` and `LaserScanBoxFilter`).
//!
//! A beam a filter drops is **no evidence at all**: neither the hit at its end nor the
//! free space along it (a mixed pixel's ray is as wrong as its end point). Each filter
//! counts what it drops in [`ReturnCounts`](super::ReturnCounts), so a run's summary says
//! how many returns each one took. Every filter looks at the scan as it was received (as
//! `ScanShadowsFilter` does within itself), so the result does not depend on their order;
//! a beam that several filters would drop is counted once, by the first in the order
//! angular bounds, box, shadow, speckle.
//!
//! - **Shadow (veiling) filter.** Where a beam's footprint straddles a depth edge, many
//!   lidars report a *mixed pixel* somewhere between the foreground and the background
//!   (Tuley, Vandapel & Hebert, "Analysis and removal of artifacts in 3-D LADAR data",
//!   ICRA 2005). Such points lie on a line that runs almost along the beam. For two
//!   returns at most `window` beams apart, the angle at the farther point between the line
//!   back to the sensor and the line to the nearer point is computed; below
//!   `min_angle_deg` the pair is a veil and the farther point is dropped — and, with
//!   `neighbors > 0`, every return within `neighbors` beams of the nearer point that lies
//!   farther than it. `min_angle_deg` is `laser_filters`' `min_angle`; its `max_angle`
//!   (usually `180 − min_angle`) tests the same pair from the nearer point and is implied.
//! - **Speckle filter** (distance mode). A return is kept when it belongs to at least one
//!   run of `window` consecutive beams whose ranges all lie within
//!   `max_range_difference` of the run's first one (a NaN or non-finite range in the run
//!   breaks it); isolated returns in mid-air — dust, rain, a single spurious echo — are
//!   dropped.
//! - **Angular bounds.** Only beams whose angle in the sensor frame lies within
//!   `[lower_deg, upper_deg]` are used (`LaserScanAngularBoundsFilter`'s `lower_angle`,
//!   `upper_angle`); the others — the robot's own mast, a bumper in the field of view —
//!   give no evidence, no-returns included.
//! - **Box.** Returns whose end point lies inside an axis-aligned box in the **base
//!   frame** (`LaserScanBoxFilter` with `box_frame: base_link`; the plane only, z is
//!   ignored) are the robot's own body and are dropped.

use crate::field_error::FieldError;
use crate::geometry::PlanarMount;
use serde::{Deserialize, Serialize};

/// The shadow (veiling) filter for mixed pixels at range discontinuities.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ShadowFilter {
    /// Whether the filter runs.
    pub enabled: bool,
    /// A pair whose angle at the farther point (between the line to the sensor and the
    /// line to the nearer point) is below this is a veil, degrees.
    pub min_angle_deg: f64,
    /// How many beams apart the two points of a pair may be.
    pub window: u32,
    /// Also drop returns within this many beams of the nearer point that lie farther than
    /// it (0: only the farther point of the pair).
    pub neighbors: u32,
}

impl Default for ShadowFilter {
    fn default() -> Self {
        Self { enabled: false, min_angle_deg: 10.0, window: 1, neighbors: 0 }
    }
}

/// The speckle filter, distance mode.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpeckleFilter {
    /// Whether the filter runs.
    pub enabled: bool,
    /// Largest range difference within a run, metres.
    pub max_range_difference: f64,
    /// Length of a run, beams (1 keeps everything).
    pub window: u32,
}

impl Default for SpeckleFilter {
    fn default() -> Self {
        Self { enabled: false, max_range_difference: 0.1, window: 2 }
    }
}

/// Angular bounds in the sensor frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AngularBounds {
    /// Whether the filter runs.
    pub enabled: bool,
    /// Smallest beam angle used, degrees.
    pub lower_deg: f64,
    /// Largest beam angle used, degrees.
    pub upper_deg: f64,
}

impl Default for AngularBounds {
    fn default() -> Self {
        Self { enabled: false, lower_deg: -180.0, upper_deg: 180.0 }
    }
}

/// A box in the base frame whose returns are the robot's own body.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SelfBox {
    /// Whether the filter runs.
    pub enabled: bool,
    /// Lower corner `[x, y]`, metres, base frame.
    pub min: [f64; 2],
    /// Upper corner `[x, y]`, metres, base frame.
    pub max: [f64; 2],
}

impl Default for SelfBox {
    fn default() -> Self {
        Self { enabled: false, min: [0.0, 0.0], max: [0.0, 0.0] }
    }
}

/// The scan filters of one lidar (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScanFilters {
    /// Mixed pixels at depth edges.
    pub shadow: ShadowFilter,
    /// Isolated returns.
    pub speckle: SpeckleFilter,
    /// Beams outside an angular interval.
    pub angular_bounds: AngularBounds,
    /// Returns on the robot's own body.
    #[serde(rename = "box")]
    pub self_box: SelfBox,
}

/// Which filter dropped a beam.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dropped {
    /// Outside the angular bounds.
    Angle,
    /// Inside the self box.
    Box,
    /// A shadow (veiling) point.
    Shadow,
    /// A speckle.
    Speckle,
}

impl ScanFilters {
    /// Every filter off.
    pub const NONE: ScanFilters = ScanFilters {
        shadow: ShadowFilter { enabled: false, min_angle_deg: 10.0, window: 1, neighbors: 0 },
        speckle: SpeckleFilter { enabled: false, max_range_difference: 0.1, window: 2 },
        angular_bounds: AngularBounds { enabled: false, lower_deg: -180.0, upper_deg: 180.0 },
        self_box: SelfBox { enabled: false, min: [0.0, 0.0], max: [0.0, 0.0] },
    };

    /// Whether any filter runs.
    pub fn any(&self) -> bool {
        self.shadow.enabled || self.speckle.enabled || self.angular_bounds.enabled || self.self_box.enabled
    }

    /// Checks the parameters; the error names the key (below `filters.`).
    pub fn validate(&self) -> Result<(), FieldError> {
        let s = &self.shadow;
        if !(s.min_angle_deg.is_finite() && s.min_angle_deg > 0.0 && s.min_angle_deg < 90.0) {
            return Err(FieldError::new(
                "shadow.min_angle_deg",
                format!("must be within (0, 90) degrees, got {}", s.min_angle_deg),
            ));
        }
        for (k, v) in [("shadow.window", s.window), ("shadow.neighbors", s.neighbors)] {
            if v > MAX_WINDOW {
                return Err(FieldError::new(k, format!("must be at most {MAX_WINDOW} beams, got {v}")));
            }
        }
        if s.window == 0 {
            return Err(FieldError::new("shadow.window", "must be at least 1 beam"));
        }
        let p = &self.speckle;
        if !(p.max_range_difference.is_finite() && p.max_range_difference >= 0.0) {
            return Err(FieldError::new(
                "speckle.max_range_difference",
                format!("must be a finite distance >= 0, got {}", p.max_range_difference),
            ));
        }
        if p.window == 0 || p.window > MAX_WINDOW {
            return Err(FieldError::new(
                "speckle.window",
                format!("must be within [1, {MAX_WINDOW}] beams, got {}", p.window),
            ));
        }
        let a = &self.angular_bounds;
        if !(a.lower_deg.is_finite() && a.upper_deg.is_finite()) || a.lower_deg > a.upper_deg {
            // The key at fault when one is not finite, so that the error points at its line.
            let key = if !a.lower_deg.is_finite() {
                "angular_bounds.lower_deg"
            } else if !a.upper_deg.is_finite() {
                "angular_bounds.upper_deg"
            } else {
                "angular_bounds"
            };
            return Err(FieldError::new(
                key,
                format!("needs finite lower_deg <= upper_deg, got {} / {}", a.lower_deg, a.upper_deg),
            ));
        }
        let b = &self.self_box;
        if b.min.iter().chain(&b.max).any(|v| !v.is_finite()) || b.min[0] > b.max[0] || b.min[1] > b.max[1] {
            return Err(FieldError::new(
                "box",
                format!("needs finite corners with min <= max, got {:?} / {:?}", b.min, b.max),
            ));
        }
        Ok(())
    }

    /// Whether the beam at `angle` (sensor frame, radians) is outside the angular bounds.
    #[inline]
    pub(super) fn outside_angles(&self, angle: f64) -> bool {
        let a = &self.angular_bounds;
        // A hair of slack so that a bound written as the scan's own first or last angle
        // keeps that beam despite rounding.
        const EPS: f64 = 1e-9;
        a.enabled && !(angle >= a.lower_deg.to_radians() - EPS && angle <= a.upper_deg.to_radians() + EPS)
    }

    /// Why the return of beam `i` (a valid return) is dropped, `None` when it is kept.
    /// `ranges` is the scan as received, `increment` its angle step, `angle` beam `i`'s
    /// angle in the sensor frame, and `is_return(r)` whether a range is a valid return.
    pub(super) fn verdict(
        &self,
        ranges: &[f32],
        i: usize,
        increment: f64,
        angle: f64,
        mount: &PlanarMount,
        is_return: impl Fn(f32) -> bool,
    ) -> Option<Dropped> {
        let r = ranges[i] as f64;
        if self.outside_angles(angle) {
            return Some(Dropped::Angle);
        }
        if self.self_box.enabled {
            let o = mount.origin_in_base();
            let (s, c) = mount.beam_angle_in_base(angle).sin_cos();
            let (x, y) = (o.x + r * c, o.y + r * s);
            let b = &self.self_box;
            if x >= b.min[0] && x <= b.max[0] && y >= b.min[1] && y <= b.max[1] {
                return Some(Dropped::Box);
            }
        }
        if self.shadow.enabled && self.shadowed(ranges, i, increment, &is_return) {
            return Some(Dropped::Shadow);
        }
        if self.speckle.enabled && self.speckled(ranges, i) {
            return Some(Dropped::Speckle);
        }
        None
    }

    /// The shadow rule for beam `i` (see the module docs).
    fn shadowed(&self, ranges: &[f32], i: usize, increment: f64, is_return: &impl Fn(f32) -> bool) -> bool {
        let s = &self.shadow;
        let tan_min = s.min_angle_deg.to_radians().tan();
        let r_i = ranges[i];
        // Is `near` the nearer point of a veil with some return within the window?
        let veil = |far: usize, near: usize| -> bool {
            let (rf, rn) = (ranges[far] as f64, ranges[near] as f64);
            let gamma = far.abs_diff(near) as f64 * increment.abs();
            // tan of the angle at the farther point; its denominator is > 0 as rf > rn.
            rn * gamma.sin() < tan_min * (rf - rn * gamma.cos())
        };
        let window = |k: usize, w: usize| k.saturating_sub(w)..=(k + w).min(ranges.len() - 1);
        // The farther point of a veil.
        let far_of_pair =
            window(i, s.window as usize).any(|j| j != i && is_return(ranges[j]) && ranges[j] < r_i && veil(i, j));
        if far_of_pair || s.neighbors == 0 {
            return far_of_pair;
        }
        // Farther than the nearer point of a veil close by.
        window(i, s.neighbors as usize).any(|n| {
            n != i
                && is_return(ranges[n])
                && ranges[n] < r_i
                && window(n, s.window as usize).any(|j| {
                    j != n && is_return(ranges[j]) && ranges[j] != ranges[n] && {
                        let (far, near) = if ranges[j] > ranges[n] { (j, n) } else { (n, j) };
                        near == n && veil(far, near)
                    }
                })
        })
    }

    /// The speckle rule for beam `i`: no run of `window` consistent beams contains it.
    fn speckled(&self, ranges: &[f32], i: usize) -> bool {
        let p = &self.speckle;
        let w = p.window as usize;
        if w <= 1 || ranges.len() < w {
            return false;
        }
        let run_ok = |start: usize| {
            let first = ranges[start];
            ranges[start + 1..start + w].iter().all(|&r| (r as f64 - first as f64).abs() <= p.max_range_difference)
        };
        // `abs() <= d` is false for NaN and for infinite differences.
        let lo = (i + 1).saturating_sub(w);
        let hi = i.min(ranges.len() - w);
        !(lo..=hi).any(|start| ranges[start].is_finite() && run_ok(start))
    }
}

/// Largest window or neighbourhood accepted, beams (a bound on the per-beam work).
pub const MAX_WINDOW: u32 = 64;

#[cfg(test)]
mod tests;
