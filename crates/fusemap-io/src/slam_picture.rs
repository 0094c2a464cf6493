//! `slam.png`: the optimised trajectory and its loop closures drawn over the map.
//!
//! An RGB PNG (colour type 2) of the map shaded as `map.png` is (see [`crate::picture`]),
//! with the trajectory through the pose-graph nodes in blue and every accepted loop
//! closure as a red segment from the submap's origin to the node it was matched with, so
//! a user sees at a glance where the lidar closed loops and whether the walls agree. The
//! GNSS fixes the graph took as position priors are green crosses. Closures and fixes are
//! blended over the map (a run closes hundreds of loops: drawn opaque, 34,000 red and green
//! pixels buried the demo's trajectory), and the trajectory is drawn last, two pixels wide.

use crate::atomic::{check_raster, write_atomic};
use crate::picture::{scale_factor, shade};
use crate::{Error, Location, Result};
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{LogOddsTable, Raster};
use std::io;
use std::path::Path;

/// The trajectory's colour.
pub const TRAJECTORY: [u8; 3] = [30, 90, 230];
/// The loop closures' colour (blended over the map).
pub const LOOP_CLOSURE: [u8; 3] = [230, 30, 30];
/// The GNSS fix priors' colour (blended over the map).
pub const FIX: [u8; 3] = [20, 150, 50];
/// The opacity of the closures and the fixes over the map.
const OVERLAY_ALPHA: f32 = 0.35;

struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

impl Canvas {
    /// Paints a pixel with `c` at opacity `alpha` (1: opaque).
    fn put(&mut self, x: i64, y: i64, c: [u8; 3], alpha: f32) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            for (p, &v) in self.rgb[i..i + 3].iter_mut().zip(&c) {
                *p = (alpha * v as f32 + (1.0 - alpha) * *p as f32).round() as u8;
            }
        }
    }

    /// A straight segment between two pixels (Bresenham), bounded in length.
    fn line(&mut self, a: (i64, i64), b: (i64, i64), c: [u8; 3], alpha: f32) {
        let (dx, dy) = ((b.0 - a.0).abs(), -(b.1 - a.1).abs());
        if dx > 100_000 || dy < -100_000 {
            return;
        }
        let (sx, sy) = (if a.0 < b.0 { 1 } else { -1 }, if a.1 < b.1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (a.0, a.1, dx + dy);
        loop {
            self.put(x, y, c, alpha);
            if (x, y) == b {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }
}

/// Writes the picture (atomically) and returns the enlargement factor.
pub fn write_pose_graph_png(
    path: &Path,
    raster: &Raster,
    trajectory: &[Point2],
    loop_closures: &[(Point2, Point2)],
    fixes: &[Point2],
) -> Result<usize> {
    check_raster(path, raster, true)?;
    let factor = scale_factor(raster.width, raster.height);
    let (width, height) = (raster.width * factor, raster.height * factor);
    if width > 32_768 || height > 32_768 {
        return Err(Error::format(path, Location::File, format!("a {width} × {height} picture is too large")));
    }
    let table = LogOddsTable::new(&raster.params);
    let mut canvas = Canvas { width, height, rgb: vec![0; width * height * 3] };
    for py in 0..height {
        let row = raster.height - 1 - py / factor;
        for px in 0..width {
            let i = row * raster.width + px / factor;
            let s = shade(raster.log_odds[i], raster.known[i], table.min, table.max);
            canvas.put(px as i64, py as i64, [s, s, s], 1.0);
        }
    }
    let to_px = |p: Point2| {
        let u = (p.x - raster.origin.x) / raster.resolution * factor as f64;
        let v = (p.y - raster.origin.y) / raster.resolution * factor as f64;
        (u.floor() as i64, height as i64 - 1 - v.floor() as i64)
    };
    let finite = |p: &Point2| p.is_finite() && p.x.abs() < 1e9 && p.y.abs() < 1e9;
    for (a, b) in loop_closures.iter().filter(|(a, b)| finite(a) && finite(b)) {
        canvas.line(to_px(*a), to_px(*b), LOOP_CLOSURE, OVERLAY_ALPHA);
    }
    for (x, y) in fixes.iter().filter(|p| finite(p)).map(|p| to_px(*p)) {
        canvas.line((x - 2, y), (x + 2, y), FIX, OVERLAY_ALPHA);
        // (The centre once: blended twice it would be darker than the arms.)
        canvas.line((x, y - 2), (x, y - 1), FIX, OVERLAY_ALPHA);
        canvas.line((x, y + 1), (x, y + 2), FIX, OVERLAY_ALPHA);
    }
    for w in trajectory.windows(2) {
        if finite(&w[0]) && finite(&w[1]) {
            let (a, b) = (to_px(w[0]), to_px(w[1]));
            canvas.line(a, b, TRAJECTORY, 1.0);
            // The second pixel across the segment: below a flat one, beside a steep one.
            let (dx, dy) = if (b.0 - a.0).abs() > (b.1 - a.1).abs() { (0, 1) } else { (1, 0) };
            canvas.line((a.0 + dx, a.1 + dy), (b.0 + dx, b.1 + dy), TRAJECTORY, 1.0);
        }
    }
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .add_text_chunk(
                "Description".into(),
                format!(
                    "fusemap pose graph over the map: {} x {} cells of {} m, lower-left corner at ({}, {}) m, {} pixels per cell; blue the optimised trajectory, red the {} loop closures (submap origin to node), green the {} GNSS fixes taken as priors",
                    raster.width, raster.height, raster.resolution, raster.origin.x, raster.origin.y, factor, loop_closures.len(), fixes.len()
                ),
            )
            .map_err(io::Error::from)?;
        let mut writer = encoder.write_header().map_err(io::Error::from)?;
        writer.write_image_data(&canvas.rgb).map_err(io::Error::from)?;
        writer.finish().map_err(io::Error::from)?;
        Ok(())
    })?;
    Ok(factor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fusemap_core::grid::{CellIndex, OccupancyParams};

    #[test]
    fn the_trajectory_closures_and_fixes_are_drawn_in_their_colours() {
        let d = crate::testdata::temp_dir("slam-picture");
        let p = d.join("slam.png");
        // 20 × 10 cells of 0.1 m, all free.
        let r = Raster {
            width: 20,
            height: 10,
            resolution: 0.1,
            origin: Point2::new(0.0, 0.0),
            first_cell: CellIndex { x: 0, y: 0 },
            log_odds: vec![-2.0; 200],
            known: vec![true; 200],
            params: OccupancyParams::default(),
        };
        let trajectory = [Point2::new(0.05, 0.55), Point2::new(1.95, 0.55)];
        let closures = [(Point2::new(0.55, 0.05), Point2::new(0.55, 0.95))];
        let fixes = [Point2::new(1.55, 0.25), Point2::new(f64::NAN, 0.0)];
        let factor = write_pose_graph_png(&p, &r, &trajectory, &closures, &fixes).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&p).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut px = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut px).unwrap();
        let (w, h) = (info.width as usize, info.height as usize);
        assert_eq!((w, h), (20 * factor, 10 * factor));
        let at = |x: f64, y: f64| {
            let (u, v) = ((x / 0.1 * factor as f64) as usize, h - 1 - (y / 0.1 * factor as f64) as usize);
            let i = 3 * (v * w + u);
            [px[i], px[i + 1], px[i + 2]]
        };
        // The trajectory is opaque; the closure and the fix are blended over the grey.
        assert_eq!(at(1.0, 0.55), TRAJECTORY);
        let free = at(1.0, 0.9);
        assert_eq!(free[0], free[1], "free cells stay grey");
        let blend =
            |c: [u8; 3]| c.map(|v| (OVERLAY_ALPHA * v as f32 + (1.0 - OVERLAY_ALPHA) * free[0] as f32).round() as u8);
        assert_eq!(at(0.55, 0.8), blend(LOOP_CLOSURE));
        assert_eq!(at(1.55, 0.25), blend(FIX));
    }
}
