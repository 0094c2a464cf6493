//! 2.5D rendering of the hall: the floor plane, the objects' vertical faces up to their
//! heights, the person's cylinder, and the ceiling above everything.
//!
//! The robot moves in the plane, so each pixel's ray in `base_link` is fixed; only its
//! heading turns with the robot. Rays are grouped by their horizontal heading into
//! narrow fans ("columns" of the ray fan, one pixel pitch `1/fx` wide): each fan casts
//! one horizontal ray through the world with [`Caster::cast_all`] (every face along it,
//! nearest first, since a low machine may stand before a tall wall), and each of the
//! fan's pixels intersects its own 3D ray with the floor plane and with the vertical
//! planes of those faces, up to each object's height. Grouping by heading rather than by
//! image column keeps the faces right for a pitched camera, whose image columns are not
//! vertical planes (vertical lines converge): at the image edge of the default camera a
//! column's rays differ by 14° in heading from top to bottom.

use super::{class_id, CameraConfig, CLASS_CEILING, CLASS_FLOOR, CLASS_GLASS, CLASS_PERSON};
use crate::person::ray_circle;
use crate::world::{Caster, EdgeHit, Material, WorldObject};
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::sim::SplitMix64;

/// What the renderer needs of one object.
#[derive(Clone, Copy, Debug)]
struct ObjectView {
    class: u16,
    height: f64,
    glass: bool,
}

/// One rendered frame before noise: true labels and true depths (NaN: none), and which
/// pixels show the floor.
#[derive(Clone, Debug, Default)]
pub(crate) struct Frame {
    pub labels: Vec<u16>,
    pub depth: Vec<f32>,
    /// True where the pixel's true label is the floor (also beyond `max_depth`).
    pub floor: Vec<bool>,
    /// The floor depth of every pixel (infinite for rays that do not point down).
    pub floor_depth: Vec<f32>,
}

/// The camera prepared for rendering one world.
pub(crate) struct Renderer<'a> {
    caster: &'a Caster,
    objects: Vec<ObjectView>,
    /// Per pixel, row-major: the ray in `base_link`, scaled so that its optical-z
    /// component is 1 (so the ray parameter is the depth).
    rays: Vec<[f64; 3]>,
    /// Per pixel: its fan.
    fan_of: Vec<u32>,
    /// Heading of each fan's ray in `base_link`, radians.
    fan_heading: Vec<f64>,
    /// The optical centre in `base_link`.
    centre: [f64; 3],
    /// Heading of the optical axis in `base_link`.
    pub axis_heading: f64,
    glass_depth_probability: f64,
    // Reused buffers.
    hits: Vec<EdgeHit>,
    fan_start: Vec<u32>,
    fan_hits: Vec<EdgeHit>,
    fan_person: Vec<bool>,
}

impl<'a> Renderer<'a> {
    /// Prepares `cfg`'s camera for `objects` (validated: every class is known).
    pub fn new(cfg: &CameraConfig, objects: &[WorldObject], caster: &'a Caster) -> Self {
        let objects = objects
            .iter()
            .map(|o| ObjectView {
                class: class_id(&o.class).unwrap_or(0),
                height: o.height_m,
                glass: o.material == Material::Glass,
            })
            .collect();
        let k = cfg.k_matrix();
        let (fx, cx, fy, cy) = (k[0], k[2], k[4], k[5]);
        let bo = cfg.base_from_optical();
        let (w, h) = (cfg.width as usize, cfg.height as usize);
        let mut rays = Vec::with_capacity(w * h);
        let mut headings = Vec::with_capacity(w * h);
        for v in 0..h {
            for u in 0..w {
                let d = bo.rotate([(u as f64 - cx) / fx, (v as f64 - cy) / fy, 1.0]);
                rays.push(d);
                headings.push(d[1].atan2(d[0]));
            }
        }
        let axis = bo.rotate([0.0, 0.0, 1.0]);
        let axis_heading = axis[1].atan2(axis[0]);
        // Fans one pixel pitch wide, measured from the optical axis heading so a heading
        // range across ±π (a camera looking backwards) stays contiguous.
        let step = 1.0 / fx;
        let rel: Vec<f64> =
            headings.iter().map(|&a| fusemap_core::geometry::normalize_angle(a - axis_heading)).collect();
        let lo = rel.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = rel.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let fans = (((hi - lo) / step).floor() as usize + 1).min(1 << 16);
        let step = if fans > 1 { (hi - lo) / (fans - 1) as f64 } else { 1.0 };
        let fan_of = rel.iter().map(|&a| (((a - lo) / step).round() as usize).min(fans - 1) as u32).collect();
        let fan_heading = (0..fans).map(|i| axis_heading + lo + i as f64 * step).collect();
        Self {
            caster,
            objects,
            rays,
            fan_of,
            fan_heading,
            centre: bo.translation,
            axis_heading,
            glass_depth_probability: cfg.glass_depth_probability,
            hits: Vec::new(),
            fan_start: Vec::new(),
            fan_hits: Vec::new(),
            fan_person: Vec::new(),
        }
    }

    /// The optical centre in the map frame (x, y, z) for the robot at `pose`.
    pub fn centre_in_map(&self, pose: Pose2) -> [f64; 3] {
        let c = pose * Point2::new(self.centre[0], self.centre[1]);
        [c.x, c.y, self.centre[2]]
    }

    /// The map-frame ray of pixel `i` (scaled to unit optical depth) for the robot at `pose`.
    pub fn ray_in_map(&self, pose: Pose2, i: usize) -> [f64; 3] {
        let (s, c) = pose.theta.sin_cos();
        let d = self.rays[i];
        [c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]]
    }

    /// One horizontal cast per fan from the camera's centre `c`: each fan's walls in order
    /// of distance, and whether it passes near the person (tested per pixel only there).
    fn cast_fans(&mut self, pose: Pose2, c: Point2, person: Option<(Point2, f64, f64)>) {
        self.fan_start.clear();
        self.fan_hits.clear();
        self.fan_person.clear();
        for &hd in &self.fan_heading {
            let (s, co) = (pose.theta + hd).sin_cos();
            self.caster.cast_all(c, (co, s), f64::INFINITY, &mut self.hits);
            self.fan_start.push(self.fan_hits.len() as u32);
            self.fan_hits.extend_from_slice(&self.hits);
            let near = person.is_some_and(|(p, r, _)| {
                let (dx, dy) = (p.x - c.x, p.y - c.y);
                let along = dx * co + dy * s;
                along > 0.0 && (dx * s - dy * co).abs() < r + 0.05 * along.max(1.0)
            });
            self.fan_person.push(near);
        }
        self.fan_start.push(self.fan_hits.len() as u32);
    }

    /// Renders the robot at `pose` with the person (centre, radius, height) if present.
    /// Glass draws its depth-or-transmission choice from `rng`.
    pub fn render(&mut self, pose: Pose2, person: Option<(Point2, f64, f64)>, rng: &mut SplitMix64, out: &mut Frame) {
        let c3 = self.centre_in_map(pose);
        let c = Point2::new(c3[0], c3[1]);
        self.cast_fans(pose, c, person);
        let n = self.rays.len();
        out.labels.clear();
        out.depth.clear();
        out.floor.clear();
        out.floor_depth.clear();
        let (st, ct) = pose.theta.sin_cos();
        for i in 0..n {
            let r = self.rays[i];
            let d = (ct * r[0] - st * r[1], st * r[0] + ct * r[1], r[2]);
            let s_floor = if d.2 < -1e-12 { -c3[2] / d.2 } else { f64::INFINITY };
            let f = self.fan_of[i] as usize;
            let s_person = match person {
                Some((p, radius, height)) if self.fan_person[f] => {
                    ray_circle(c, (d.0, d.1), p, radius).filter(|s| (0.0..=height).contains(&(c3[2] + s * d.2)))
                }
                _ => None,
            }
            .unwrap_or(f64::INFINITY);
            let nearest_plain = s_floor.min(s_person);
            let mut label: Option<u16> = None;
            let mut depth: Option<f64> = None;
            let mut through = usize::MAX;
            let hits = &self.fan_hits[self.fan_start[f] as usize..self.fan_start[f + 1] as usize];
            for h in hits {
                if h.object == through {
                    continue;
                }
                let (a, b) = h.edge;
                let e = (b.x - a.x, b.y - a.y);
                let den = d.0 * e.1 - d.1 * e.0;
                if den.abs() < 1e-12 {
                    continue;
                }
                let s = ((a.x - c.x) * e.1 - (a.y - c.y) * e.0) / den;
                // Nothing beyond the floor point or the person is visible.
                if nearest_plain < s {
                    break;
                }
                let o = self.objects[h.object];
                let z = c3[2] + s * d.2;
                if !(s > 0.0 && (0.0..=o.height).contains(&z)) {
                    continue;
                }
                if o.glass {
                    label.get_or_insert(CLASS_GLASS);
                    if rng.next_f64() < self.glass_depth_probability {
                        depth = Some(s);
                        break;
                    }
                    through = h.object;
                    continue;
                }
                label.get_or_insert(o.class);
                depth = Some(s);
                break;
            }
            let mut is_floor = false;
            if depth.is_none() {
                if s_person < s_floor {
                    label.get_or_insert(CLASS_PERSON);
                    depth = Some(s_person);
                } else if s_floor.is_finite() {
                    is_floor = label.is_none();
                    label.get_or_insert(CLASS_FLOOR);
                    depth = Some(s_floor);
                } else {
                    label.get_or_insert(CLASS_CEILING);
                }
            }
            out.labels.push(label.unwrap_or(CLASS_CEILING));
            out.depth.push(depth.map_or(f32::NAN, |v| v as f32));
            out.floor.push(is_floor);
            out.floor_depth.push(s_floor as f32);
        }
    }
}

/// A smooth random field in image coordinates and time (value noise: random values on
/// an integer lattice, interpolated with the smoothstep `3t² − 2t³` in each of u, v and
/// t; Perlin 1985), in [0, 1). Stateless: the lattice value is a hash of its coordinates
/// and the seed, so frames can be rendered in any order.
#[cfg(test)]
pub(crate) fn value_noise(seed: u64, u: f64, v: f64, t: f64) -> f64 {
    let (iu, iv, it) = (u.floor(), v.floor(), t.floor());
    let (fu, fv, ft) = (smooth(u - iu), smooth(v - iv), smooth(t - it));
    let (iu, iv, it) = (iu as i64, iv as i64, it as i64);
    let mut acc = 0.0;
    for (dt, wt) in [(0, 1.0 - ft), (1, ft)] {
        for (dv, wv) in [(0, 1.0 - fv), (1, fv)] {
            for (du, wu) in [(0, 1.0 - fu), (1, fu)] {
                acc += wt * wv * wu * lattice(seed, iu + du, iv + dv, it + dt);
            }
        }
    }
    acc
}

fn smooth(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

fn lattice(seed: u64, u: i64, v: i64, t: i64) -> f64 {
    let h = seed
        ^ (u as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (v as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (t as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    SplitMix64::new(h).next_f64()
}

/// [`value_noise`] over a whole image at one time, fast: the lattice values of the
/// frame's time slice are interpolated once, and each pixel's lattice cell and smoothstep
/// weights are fixed per column and per row.
pub(crate) struct BlobField {
    cols: Vec<(usize, f32)>,
    rows: Vec<(usize, f32)>,
    nu: usize,
    lattice: Vec<f32>,
}

impl BlobField {
    pub fn new(width: usize, height: usize, scale: f64) -> Self {
        let axis = |n: usize| -> Vec<(usize, f32)> {
            (0..n)
                .map(|i| {
                    let x = i as f64 / scale;
                    (x.floor() as usize, smooth(x - x.floor()) as f32)
                })
                .collect()
        };
        let (cols, rows) = (axis(width), axis(height));
        let nu = cols.last().map_or(0, |c| c.0) + 2;
        let nv = rows.last().map_or(0, |r| r.0) + 2;
        Self { cols, rows, nu, lattice: vec![0.0; nu * nv] }
    }

    /// Fixes the time slice `t` (in field periods).
    pub fn field_at(&mut self, seed: u64, t: f64) {
        let it = t.floor();
        let ft = smooth(t - it);
        let it = it as i64;
        let nu = self.nu;
        for (k, l) in self.lattice.iter_mut().enumerate() {
            let (u, v) = ((k % nu) as i64, (k / nu) as i64);
            *l = ((1.0 - ft) * lattice(seed, u, v, it) + ft * lattice(seed, u, v, it + 1)) as f32;
        }
    }

    /// The field at pixel `(u, v)`.
    pub fn value(&self, u: usize, v: usize) -> f32 {
        let ((iu, fu), (iv, fv)) = (self.cols[u], self.rows[v]);
        let l = |du: usize, dv: usize| self.lattice[(iv + dv) * self.nu + iu + du];
        let top = l(0, 0) + fu * (l(1, 0) - l(0, 0));
        let bottom = l(0, 1) + fu * (l(1, 1) - l(0, 1));
        top + fv * (bottom - top)
    }
}
