//! Worlds made of line segments.

use super::SplitMix64;
use crate::geometry::Point2;
use serde::{Deserialize, Serialize};

/// A wall segment, world frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// One end.
    pub a: Point2,
    /// The other end.
    pub b: Point2,
}

impl Segment {
    /// A segment between two points.
    pub fn new(ax: f64, ay: f64, bx: f64, by: f64) -> Self {
        Self { a: Point2::new(ax, ay), b: Point2::new(bx, by) }
    }

    /// Distance along the ray `origin + t·(cos θ, sin θ)` to this segment, `None` when it
    /// misses or only touches it behind or at the origin (t ≤ 0). A ray parallel to the
    /// segment misses it.
    #[inline]
    pub fn intersect(&self, origin: Point2, dir: (f64, f64)) -> Option<f64> {
        let e = (self.b.x - self.a.x, self.b.y - self.a.y);
        let den = dir.0 * e.1 - dir.1 * e.0;
        if den == 0.0 {
            return None;
        }
        let w = (self.a.x - origin.x, self.a.y - origin.y);
        let t = (w.0 * e.1 - w.1 * e.0) / den;
        let u = (w.0 * dir.1 - w.1 * dir.0) / den;
        (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
    }
}

impl Segment {
    /// Euclidean distance from `p` to the nearest point of the segment.
    pub fn distance_to(&self, p: Point2) -> f64 {
        let (dx, dy) = (self.b.x - self.a.x, self.b.y - self.a.y);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 { (((p.x - self.a.x) * dx + (p.y - self.a.y) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
        p.distance(Point2::new(self.a.x + t * dx, self.a.y + t * dy))
    }
}

/// A world of wall segments.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct World {
    /// The walls.
    pub segments: Vec<Segment>,
}

impl World {
    /// Distance from `p` to the nearest wall (infinite for a world without walls): the
    /// ground truth that simulated runs measure their maps against.
    pub fn distance_to_walls(&self, p: Point2) -> f64 {
        self.segments.iter().map(|s| s.distance_to(p)).fold(f64::INFINITY, f64::min)
    }

    /// Distance to the nearest wall along the ray, `None` when no wall is hit.
    pub fn cast(&self, origin: Point2, angle: f64) -> Option<f64> {
        let (s, c) = angle.sin_cos();
        self.segments.iter().filter_map(|seg| seg.intersect(origin, (c, s))).min_by(f64::total_cmp)
    }
}

/// The design document's corridor (§3.1): walls y = +2 and y = -2, end wall x = 4. The
/// document's walls are infinite lines; here the side walls run from x = -20 to the end
/// wall, which no beam of the corridor run can tell apart.
pub fn corridor() -> World {
    World {
        segments: vec![
            Segment::new(-20.0, 2.0, 4.0, 2.0),
            Segment::new(-20.0, -2.0, 4.0, -2.0),
            Segment::new(4.0, -2.0, 4.0, 2.0),
        ],
    }
}

/// A square room with axis-aligned rectangular obstacles, and the rectangles.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxWorld {
    /// All walls: the room's four and four per rectangle.
    pub world: World,
    /// Half the room's side: walls at x, y = ±half.
    pub half: f64,
    /// Obstacles as (x_min, y_min, x_max, y_max).
    pub rects: Vec<[f64; 4]>,
}

impl BoxWorld {
    /// True when `p` is at least `margin` from every obstacle and inside the walls by
    /// `margin`.
    pub fn is_free(&self, p: Point2, margin: f64) -> bool {
        let inside = p.x.abs() < self.half - margin && p.y.abs() < self.half - margin;
        inside
            && !self
                .rects
                .iter()
                .any(|r| p.x > r[0] - margin && p.x < r[2] + margin && p.y > r[1] - margin && p.y < r[3] + margin)
    }
}

/// A `2·half` m square room with `n_rects` random rectangles of side 1–6 m kept 1 m
/// apart (the shape of the anchors' "big" reference world, with our own generator).
pub fn box_world(half: f64, n_rects: usize, seed: u64) -> BoxWorld {
    let mut rng = SplitMix64::new(seed);
    let mut rects: Vec<[f64; 4]> = Vec::new();
    let mut attempts = 0;
    while rects.len() < n_rects && attempts < 10_000 {
        attempts += 1;
        let (w, h) = (rng.uniform(1.0, 6.0), rng.uniform(1.0, 6.0));
        let (cx, cy) = (rng.uniform(-half + 3.0, half - 3.0), rng.uniform(-half + 3.0, half - 3.0));
        let r = [cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0];
        let apart = |q: &[f64; 4]| r[2] + 1.0 < q[0] || q[2] + 1.0 < r[0] || r[3] + 1.0 < q[1] || q[3] + 1.0 < r[1];
        if rects.iter().all(apart) {
            rects.push(r);
        }
    }
    let h = half;
    let mut segments = vec![
        Segment::new(-h, -h, h, -h),
        Segment::new(h, -h, h, h),
        Segment::new(h, h, -h, h),
        Segment::new(-h, h, -h, -h),
    ];
    for r in &rects {
        segments.push(Segment::new(r[0], r[1], r[2], r[1]));
        segments.push(Segment::new(r[2], r[1], r[2], r[3]));
        segments.push(Segment::new(r[2], r[3], r[0], r[3]));
        segments.push(Segment::new(r[0], r[3], r[0], r[1]));
    }
    BoxWorld { world: World { segments }, half, rects }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

    #[test]
    fn corridor_distances() {
        let w = corridor();
        let o = Point2::new(0.0, 0.0);
        assert!((w.cast(o, 0.0).unwrap() - 4.0).abs() < 1e-12);
        assert!((w.cast(o, FRAC_PI_2).unwrap() - 2.0).abs() < 1e-12);
        assert!((w.cast(o, -FRAC_PI_2).unwrap() - 2.0).abs() < 1e-12);
        assert!((w.cast(o, FRAC_PI_4).unwrap() - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        // Looking back down the corridor, the side walls end at x = -20.
        assert!(w.cast(o, std::f64::consts::PI).is_none());
    }

    #[test]
    fn distances_to_walls() {
        let w = corridor();
        assert!((w.distance_to_walls(Point2::new(1.0, 0.5)) - 1.5).abs() < 1e-12);
        assert!((w.distance_to_walls(Point2::new(5.0, 3.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert!((w.distance_to_walls(Point2::new(3.5, 0.0)) - 0.5).abs() < 1e-12);
        let dot = Segment::new(1.0, 1.0, 1.0, 1.0);
        assert!((dot.distance_to(Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-12);
        assert_eq!(World::default().distance_to_walls(Point2::default()), f64::INFINITY);
    }

    #[test]
    fn box_world_is_closed_and_obstacles_apart() {
        let b = box_world(19.5, 8, 12345);
        assert_eq!(b.rects.len(), 8);
        assert_eq!(b.world.segments.len(), 4 + 32);
        let mut rng = SplitMix64::new(1);
        for _ in 0..200 {
            let p = Point2::new(rng.uniform(-19.0, 19.0), rng.uniform(-19.0, 19.0));
            if b.is_free(p, 0.1) {
                let d = b.world.cast(p, rng.uniform(-3.2, 3.2)).expect("closed room");
                assert!(d > 0.0 && d < 56.0);
            }
        }
    }
}
