//! A walking person: the dynamic object of the design document's scenario (§2.4, §3.4).
//! An upright cylinder walks back and forth along a segment at constant speed, and only
//! during configured time windows, so that it also leaves the scene (a map's dynamic layer
//! must then let its trail decay). It is seen by the lidar and the camera and is never
//! part of the ground-truth occupancy.

use crate::checks::{non_negative, positive};
use fusemap_core::field_error::FieldError;
use fusemap_core::geometry::Point2;
use serde::{Deserialize, Serialize};

/// The person (`[person]` in a scenario file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PersonConfig {
    /// Whether the person walks at all.
    pub enabled: bool,
    /// One end of the walk, metres in the map frame (the person starts here).
    pub from: [f64; 2],
    /// The other end.
    pub to: [f64; 2],
    /// Walking speed, m/s.
    pub speed_mps: f64,
    /// Cylinder radius, metres.
    pub radius_m: f64,
    /// Cylinder height, metres.
    pub height_m: f64,
    /// Time windows `[start, end]`, seconds since the start of the run, in which the
    /// person is present. In each window the walk starts again at `from`.
    pub windows: Vec<[f64; 2]>,
}

impl Default for PersonConfig {
    /// Crosses the loop's south leg (y = 3) through the gap between the two machines
    /// (x = 13..17), so the camera, looking east along that leg, meets the person on each
    /// lap; present twice so it also leaves twice.
    fn default() -> Self {
        Self {
            enabled: true,
            from: [16.0, 0.6],
            to: [16.0, 9.6],
            speed_mps: 1.0,
            radius_m: 0.25,
            height_m: 1.7,
            windows: vec![[2.0, 60.0], [85.0, 135.0]],
        }
    }
}

impl PersonConfig {
    pub(crate) fn validate(&self) -> Result<(), FieldError> {
        // The end at fault, so that the error points at its line.
        for (field, end) in [("person.from", self.from), ("person.to", self.to)] {
            if end.iter().any(|v| !v.is_finite()) {
                return Err(FieldError::new(field, "must be finite"));
            }
        }
        if (self.from[0] - self.to[0]).hypot(self.from[1] - self.to[1]) < 1e-6 {
            return Err(FieldError::new("person.to", "must differ from person.from"));
        }
        positive("person.speed_mps", self.speed_mps)?;
        positive("person.radius_m", self.radius_m)?;
        positive("person.height_m", self.height_m)?;
        for (i, w) in self.windows.iter().enumerate() {
            non_negative(&format!("person.windows[{i}][0]"), w[0])?;
            if !(w[1].is_finite() && w[1] > w[0]) {
                return Err(FieldError::new(
                    format!("person.windows[{i}]"),
                    format!("must end after it starts, got {w:?}"),
                ));
            }
        }
        Ok(())
    }

    /// Where the person stands at `t` seconds since the start, `None` when absent (or
    /// disabled). The walk is a triangle wave along the segment.
    pub fn position_at(&self, t: f64) -> Option<Point2> {
        if !self.enabled {
            return None;
        }
        let w = self.windows.iter().find(|w| t >= w[0] && t <= w[1])?;
        let (a, b) = (Point2::new(self.from[0], self.from[1]), Point2::new(self.to[0], self.to[1]));
        let len = a.distance(b);
        let s = (self.speed_mps * (t - w[0])).rem_euclid(2.0 * len);
        let u = if s <= len { s / len } else { 2.0 - s / len };
        Some(Point2::new(a.x + (b.x - a.x) * u, a.y + (b.y - a.y) * u))
    }
}

/// Distance along `origin + t·dir` to a circle, `None` when the ray misses it or starts
/// inside it. `dir` need not be a unit vector: `t` is in units of `|dir|`.
pub fn ray_circle(origin: Point2, dir: (f64, f64), centre: Point2, radius: f64) -> Option<f64> {
    let (fx, fy) = (origin.x - centre.x, origin.y - centre.y);
    let a = dir.0 * dir.0 + dir.1 * dir.1;
    let b = fx * dir.0 + fy * dir.1;
    let c = fx * fx + fy * fy - radius * radius;
    if a == 0.0 || c <= 0.0 {
        return None;
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walks_back_and_forth_only_in_its_windows() {
        let p = PersonConfig::default();
        assert_eq!(p.validate(), Ok(()));
        let w = p.windows[0];
        assert!(p.position_at(w[0] - 0.1).is_none());
        assert!(p.position_at(w[1] + 0.1).is_none());
        let start = p.position_at(w[0]).unwrap();
        assert!(start.distance(Point2::new(p.from[0], p.from[1])) < 1e-12);
        let len = Point2::new(p.from[0], p.from[1]).distance(Point2::new(p.to[0], p.to[1]));
        let end = p.position_at(w[0] + len / p.speed_mps).unwrap();
        assert!(end.distance(Point2::new(p.to[0], p.to[1])) < 1e-9);
        let back = p.position_at(w[0] + 2.0 * len / p.speed_mps).unwrap();
        assert!(back.distance(start) < 1e-9);
        // Speed: 0.1 s apart, 0.1 m apart (away from the turns).
        let (q0, q1) = (p.position_at(w[0] + 1.0).unwrap(), p.position_at(w[0] + 1.1).unwrap());
        assert!((q0.distance(q1) - 0.1 * p.speed_mps).abs() < 1e-9);
        let off = PersonConfig { enabled: false, ..PersonConfig::default() };
        assert!(off.position_at(w[0] + 1.0).is_none());
        let bad = PersonConfig { windows: vec![[5.0, 4.0]], ..PersonConfig::default() };
        assert!(bad.validate().unwrap_err().to_string().starts_with("person.windows[0]"));
    }

    #[test]
    fn ray_circle_cases() {
        let c = Point2::new(5.0, 0.0);
        assert!((ray_circle(Point2::new(0.0, 0.0), (1.0, 0.0), c, 1.0).unwrap() - 4.0).abs() < 1e-12);
        // A non-unit direction scales t.
        assert!((ray_circle(Point2::new(0.0, 0.0), (2.0, 0.0), c, 1.0).unwrap() - 2.0).abs() < 1e-12);
        assert!(ray_circle(Point2::new(0.0, 0.0), (-1.0, 0.0), c, 1.0).is_none(), "behind");
        assert!(ray_circle(Point2::new(0.0, 2.0), (1.0, 0.0), c, 1.0).is_none(), "passes by");
        assert!(ray_circle(Point2::new(5.0, 0.0), (1.0, 0.0), c, 1.0).is_none(), "inside");
    }
}
