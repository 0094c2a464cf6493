//! A polygon world and an ideal 2D lidar for the SLAM tests.

use crate::geometry::{Point2, Pose2};

/// Wall segments.
pub struct World {
    pub walls: Vec<(Point2, Point2)>,
}

/// Walls are shifted off the cell borders of any round resolution, so a test never
/// depends on how a point exactly on a border rounds.
fn p(x: f64, y: f64) -> Point2 {
    Point2::new(x + 0.0131, y + 0.0277)
}

impl World {
    /// A 12 × 8 m room with an L-shaped obstacle and a pillar, so every pose is unique.
    pub fn room() -> Self {
        let mut walls = vec![
            (p(0.0, 0.0), p(12.0, 0.0)),
            (p(12.0, 0.0), p(12.0, 8.0)),
            (p(12.0, 8.0), p(0.0, 8.0)),
            (p(0.0, 8.0), p(0.0, 0.0)),
            (p(3.0, 2.0), p(5.0, 2.0)),
            (p(5.0, 2.0), p(5.0, 3.5)),
        ];
        walls.extend(square(8.5, 5.0, 0.4));
        walls.extend(square(2.0, 6.0, 0.6));
        Self { walls }
    }

    /// A 40 m long, 2 m wide corridor: featureless along x.
    pub fn corridor() -> Self {
        Self { walls: vec![(p(-20.0, -1.0), p(20.0, -1.0)), (p(-20.0, 1.0), p(20.0, 1.0))] }
    }

    /// Points (in the scan frame) of an ideal scan from `pose`: `beams` bearings over 360°,
    /// returns beyond `max_range` dropped.
    pub fn scan(&self, pose: Pose2, beams: usize, max_range: f64) -> Vec<Point2> {
        let mut out = Vec::new();
        for k in 0..beams {
            let a = -std::f64::consts::PI + k as f64 * 2.0 * std::f64::consts::PI / beams as f64;
            let (dx, dy) = ((pose.theta + a).cos(), (pose.theta + a).sin());
            let mut best = f64::INFINITY;
            for (a0, a1) in &self.walls {
                let (ex, ey) = (a1.x - a0.x, a1.y - a0.y);
                let den = dx * ey - dy * ex;
                if den.abs() < 1e-12 {
                    continue;
                }
                let (wx, wy) = (a0.x - pose.x, a0.y - pose.y);
                let t = (wx * ey - wy * ex) / den;
                let u = (wx * dy - wy * dx) / den;
                if t > 0.0 && (0.0..=1.0).contains(&u) {
                    best = best.min(t);
                }
            }
            if best <= max_range {
                out.push(Point2::new(best * a.cos(), best * a.sin()));
            }
        }
        out
    }

    /// [`scan`](Self::scan) with each range lengthened by `noise()` metres.
    pub fn noisy_scan(&self, pose: Pose2, beams: usize, max_range: f64, mut noise: impl FnMut() -> f64) -> Vec<Point2> {
        self.scan(pose, beams, max_range)
            .into_iter()
            .map(|q| {
                let r = q.x.hypot(q.y);
                let k = (r + noise()) / r;
                Point2::new(q.x * k, q.y * k)
            })
            .collect()
    }
}

fn square(cx: f64, cy: f64, half: f64) -> Vec<(Point2, Point2)> {
    let c = [p(cx - half, cy - half), p(cx + half, cy - half), p(cx + half, cy + half), p(cx - half, cy + half)];
    (0..4).map(|i| (c[i], c[(i + 1) % 4])).collect()
}
