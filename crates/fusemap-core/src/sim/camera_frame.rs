//! A synthetic label + depth frame for benchmarks and tests: what a pitched camera at
//! `base_link` sees of a box room (floor, four 3 m walls) around it.

use crate::sensor::camera::{CameraModel, DepthImage, LabelImage};

/// Label ids the frame uses (the production line's table).
const FLOOR: u16 = 1;
const WALL: u16 = 2;
const CEILING: u16 = 7;

/// Renders the room `[-half_x, half_x] × [-half_y, half_y]` (metres, base frame, walls 3 m
/// high) as `model`'s camera sees it: exact depths along the optical axis, floor and wall
/// labels, ceiling (no depth) above the walls.
pub fn room_frame(model: &CameraModel, half_x: f64, half_y: f64) -> (LabelImage, DepthImage) {
    let p = *model.pinhole();
    let mount = *model.base_from_optical();
    let t = mount.translation;
    let mut labels = Vec::with_capacity(p.width as usize * p.height as usize);
    let mut depth = Vec::with_capacity(labels.capacity());
    for v in 0..p.height {
        for u in 0..p.width {
            let r = mount.rotate([(f64::from(u) - p.cx) / p.fx, (f64::from(v) - p.cy) / p.fy, 1.0]);
            let mut s_wall = f64::INFINITY;
            for (axis, half) in [(0, half_x), (1, half_y)] {
                for side in [-1.0, 1.0] {
                    if r[axis] * side > 0.0 {
                        s_wall = s_wall.min((side * half - t[axis]) / r[axis]);
                    }
                }
            }
            let s_floor = if r[2] < 0.0 { -t[2] / r[2] } else { f64::INFINITY };
            let (s, label) = if s_floor < s_wall {
                (s_floor, FLOOR)
            } else if t[2] + s_wall * r[2] <= 3.0 {
                (s_wall, WALL)
            } else {
                (f64::NAN, CEILING)
            };
            labels.push(label);
            depth.push(s as f32);
        }
    }
    (
        LabelImage::new(p.width, p.height, labels).expect("sized by the pinhole"),
        DepthImage::new(p.width, p.height, depth).expect("sized by the pinhole"),
    )
}
