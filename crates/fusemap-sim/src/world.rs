//! The production hall: objects with materials, floor grooves, and a ray caster that
//! reports which material a beam hit and the surface normal there.

use fusemap_core::field_error::FieldError;
use fusemap_core::geometry::Point2;
use serde::{Deserialize, Serialize};

/// What a surface is made of: it decides how the lidar sees it (design document, §2.2:
/// specular reflection, transmission through glass).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Material {
    /// Matte wall: a clean return.
    #[default]
    Wall,
    /// Glass: the beam passes through with the lidar's `glass_pass_probability`.
    Glass,
    /// Polished stainless steel: specular, so a beam may bounce and return a too-long
    /// range (a "flying point").
    Steel,
    /// Painted machine body: a clean return.
    Machine,
}

/// An axis-aligned rectangle of the floor, metres in the map frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rect {
    /// Lowest x and y.
    pub min: [f64; 2],
    /// Highest x and y.
    pub max: [f64; 2],
}

impl Rect {
    /// A rectangle from its corners.
    pub const fn new(x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        Self { min: [x0, y0], max: [x1, y1] }
    }

    /// True when `p` lies inside or on the border.
    pub fn contains(&self, p: Point2) -> bool {
        p.x >= self.min[0] && p.x <= self.max[0] && p.y >= self.min[1] && p.y <= self.max[1]
    }

    pub(crate) fn check(&self, field: &str) -> Result<(), FieldError> {
        let all = [self.min[0], self.min[1], self.max[0], self.max[1]];
        if all.iter().any(|v| !v.is_finite()) || self.min[0] >= self.max[0] || self.min[1] >= self.max[1] {
            return Err(FieldError::new(
                field,
                format!("a rectangle needs finite min < max, got {:?}..{:?}", self.min, self.max),
            ));
        }
        Ok(())
    }
}

/// An object's outline in the plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A straight wall or fence from `a` to `b`, `thickness_m` thick (centred on the line).
    Segment {
        /// One end, metres.
        a: [f64; 2],
        /// The other end, metres.
        b: [f64; 2],
        /// Full thickness, metres (0 for an ideal line).
        thickness_m: f64,
    },
    /// A closed polygon (vertices in order; the last connects back to the first).
    Polygon {
        /// Vertices, metres.
        points: Vec<[f64; 2]>,
    },
}

/// One object of the hall. `height_m` and `class` are carried now so that 3D and
/// camera (semantic class) simulation can use the same world later.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldObject {
    /// A name for reports (`pillar_3`).
    pub name: String,
    /// Semantic class a camera would report, one of the class table's names (`wall`, `glass`,
    /// `pillar`, `machine`; see [`crate::camera::class_id`]).
    pub class: String,
    /// Surface material.
    pub material: Material,
    /// Height above the floor, metres.
    pub height_m: f64,
    /// Outline.
    pub shape: Shape,
}

impl WorldObject {
    /// The closed outline used for ray casting: a segment with thickness becomes its
    /// rectangle, an ideal line stays one edge.
    pub fn outline(&self) -> Vec<(Point2, Point2)> {
        match &self.shape {
            Shape::Segment { a, b, thickness_m } => {
                let (a, b) = (Point2::new(a[0], a[1]), Point2::new(b[0], b[1]));
                let len = a.distance(b);
                let h = thickness_m / 2.0;
                if h <= 0.0 || len == 0.0 {
                    return vec![(a, b)];
                }
                let (nx, ny) = (-(b.y - a.y) / len * h, (b.x - a.x) / len * h);
                let c = [
                    Point2::new(a.x + nx, a.y + ny),
                    Point2::new(b.x + nx, b.y + ny),
                    Point2::new(b.x - nx, b.y - ny),
                    Point2::new(a.x - nx, a.y - ny),
                ];
                (0..4).map(|i| (c[i], c[(i + 1) % 4])).collect()
            }
            Shape::Polygon { points } => {
                let n = points.len();
                (0..n)
                    .map(|i| {
                        let (p, q) = (points[i], points[(i + 1) % n]);
                        (Point2::new(p[0], p[1]), Point2::new(q[0], q[1]))
                    })
                    .collect()
            }
        }
    }

    /// Distance from `p` to the object's solid (0 inside it).
    pub fn distance(&self, p: Point2) -> f64 {
        match &self.shape {
            Shape::Segment { a, b, thickness_m } => {
                (point_segment_distance(p, Point2::new(a[0], a[1]), Point2::new(b[0], b[1])) - thickness_m / 2.0)
                    .max(0.0)
            }
            Shape::Polygon { points } => {
                if polygon_contains(points, p) {
                    return 0.0;
                }
                self.outline().iter().map(|&(a, b)| point_segment_distance(p, a, b)).fold(f64::INFINITY, f64::min)
            }
        }
    }

    pub(crate) fn check(&self, field: &str) -> Result<(), FieldError> {
        if !(self.height_m.is_finite() && self.height_m > 0.0) {
            return Err(FieldError::new(format!("{field}.height_m"), format!("must be > 0, got {}", self.height_m)));
        }
        match &self.shape {
            Shape::Segment { a, b, thickness_m } => {
                if a.iter().chain(b).any(|v| !v.is_finite()) || a == b {
                    return Err(FieldError::new(format!("{field}.shape"), "a segment needs two distinct finite ends"));
                }
                if !(thickness_m.is_finite() && *thickness_m >= 0.0) {
                    return Err(FieldError::new(
                        format!("{field}.shape.thickness_m"),
                        format!("must be >= 0, got {thickness_m}"),
                    ));
                }
            }
            Shape::Polygon { points } => {
                if points.len() < 3 || points.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(FieldError::new(format!("{field}.shape"), "a polygon needs at least 3 finite points"));
                }
            }
        }
        Ok(())
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance(p: Point2, a: Point2, b: Point2) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 { (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    p.distance(Point2::new(a.x + t * dx, a.y + t * dy))
}

/// Even-odd point-in-polygon test (W. R. Franklin's crossing rule).
pub fn polygon_contains(points: &[[f64; 2]], p: Point2) -> bool {
    let n = points.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (pi, pj) = (points[i], points[j]);
        if (pi[1] > p.y) != (pj[1] > p.y) && p.x < (pj[0] - pi[0]) * (p.y - pi[1]) / (pj[1] - pi[1]) + pi[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// A regular `n`-gon approximating a circle (round pillars).
pub fn circle(cx: f64, cy: f64, r: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [cx + r * a.cos(), cy + r * a.sin()]
        })
        .collect()
}

/// The default production hall, 30 m × 15 m with its south-west corner at the map
/// origin: outer walls, two machine bodies along the line, a glass fence north of them,
/// six round stainless-steel pillars.
pub fn production_hall_objects() -> Vec<WorldObject> {
    let obj = |name: &str, class: &str, material, height_m, shape| WorldObject {
        name: name.into(),
        class: class.into(),
        material,
        height_m,
        shape,
    };
    let wall = |name: &str, a: [f64; 2], b: [f64; 2]| {
        obj(name, "wall", Material::Wall, 4.0, Shape::Segment { a, b, thickness_m: 0.2 })
    };
    let machine = |name: &str, r: Rect| {
        let points = vec![r.min, [r.max[0], r.min[1]], r.max, [r.min[0], r.max[1]]];
        obj(name, "machine", Material::Machine, 2.2, Shape::Polygon { points })
    };
    let mut objects = vec![
        wall("wall_south", [0.0, 0.0], [30.0, 0.0]),
        wall("wall_east", [30.0, 0.0], [30.0, 15.0]),
        wall("wall_north", [30.0, 15.0], [0.0, 15.0]),
        wall("wall_west", [0.0, 15.0], [0.0, 0.0]),
        machine("machine_press", Rect::new(6.0, 5.5, 13.0, 9.0)),
        machine("machine_welder", Rect::new(17.0, 5.5, 24.0, 9.0)),
        obj(
            "glass_fence",
            "glass",
            Material::Glass,
            2.0,
            Shape::Segment { a: [5.0, 10.5], b: [25.0, 10.5], thickness_m: 0.02 },
        ),
    ];
    let pillars = [(8.0, 1.3), (15.0, 1.3), (22.0, 1.3), (15.0, 7.25), (1.3, 7.5), (28.7, 7.5)];
    for (i, (x, y)) in pillars.into_iter().enumerate() {
        let shape = Shape::Polygon { points: circle(x, y, 0.2, 16) };
        objects.push(obj(&format!("pillar_{i}"), "pillar", Material::Steel, 6.0, shape));
    }
    objects
}

/// A ray's first hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, metres.
    pub range: f64,
    /// Index of the object hit in the world's object list.
    pub object: usize,
    /// Material of that object.
    pub material: Material,
    /// Unit normal of the edge hit (either side).
    pub normal: (f64, f64),
}

/// One object prepared for ray casting.
#[derive(Clone, Debug)]
struct CastObject {
    material: Material,
    /// `[x_min, y_min, x_max, y_max]`.
    bbox: [f64; 4],
    edges: Vec<(Point2, Point2)>,
}

/// The objects prepared for fast ray casting: edges and a bounding box per object, so a
/// beam only tests the edges of objects whose box it crosses.
#[derive(Clone, Debug)]
pub struct Caster {
    objects: Vec<CastObject>,
}

impl Caster {
    /// Prepares `objects`.
    pub fn new(objects: &[WorldObject]) -> Self {
        let objects = objects
            .iter()
            .map(|o| {
                let edges = o.outline();
                let mut bbox = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
                for (a, b) in &edges {
                    for p in [a, b] {
                        bbox = [bbox[0].min(p.x), bbox[1].min(p.y), bbox[2].max(p.x), bbox[3].max(p.y)];
                    }
                }
                CastObject { material: o.material, bbox, edges }
            })
            .collect();
        Self { objects }
    }

    /// The first hit along `origin + t·dir` (`dir` a unit vector) with `t > 0`, ignoring
    /// the objects in `skip`.
    pub fn cast(&self, origin: Point2, dir: (f64, f64), skip: &[usize]) -> Option<Hit> {
        let inv = (1.0 / dir.0, 1.0 / dir.1);
        let mut best: Option<Hit> = None;
        for (k, o) in self.objects.iter().enumerate() {
            let limit = best.map_or(f64::INFINITY, |h| h.range);
            if skip.contains(&k) || !ray_hits_box(origin, inv, &o.bbox, limit) {
                continue;
            }
            for &(a, b) in &o.edges {
                if let Some(t) = ray_segment(origin, dir, a, b) {
                    if t < best.map_or(f64::INFINITY, |h| h.range) {
                        let (ex, ey) = (b.x - a.x, b.y - a.y);
                        let len = ex.hypot(ey);
                        let normal = (-ey / len, ex / len);
                        best = Some(Hit { range: t, object: k, material: o.material, normal });
                    }
                }
            }
        }
        best
    }
}

/// One crossing of a ray with an object's outline edge, for renderers that need every
/// surface along the ray (a low machine in front of a tall wall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeHit {
    /// Distance along the ray, metres.
    pub range: f64,
    /// Index of the object in the world's object list.
    pub object: usize,
    /// The edge's ends (its vertical face spans the object's height above it).
    pub edge: (Point2, Point2),
}

impl Caster {
    /// Every crossing of `origin + t·dir` (`dir` a unit vector) with an outline edge,
    /// `0 < t ≤ max_range`, nearest first, appended to `out` (cleared first; a buffer the
    /// caller reuses, so a renderer allocates nothing per ray).
    pub fn cast_all(&self, origin: Point2, dir: (f64, f64), max_range: f64, out: &mut Vec<EdgeHit>) {
        out.clear();
        let inv = (1.0 / dir.0, 1.0 / dir.1);
        for (k, o) in self.objects.iter().enumerate() {
            if !ray_hits_box(origin, inv, &o.bbox, max_range) {
                continue;
            }
            for &(a, b) in &o.edges {
                if let Some(t) = ray_segment(origin, dir, a, b) {
                    if t <= max_range {
                        out.push(EdgeHit { range: t, object: k, edge: (a, b) });
                    }
                }
            }
        }
        out.sort_by(|x, y| x.range.total_cmp(&y.range));
    }
}

/// Slab test: does the ray meet the box `[x0, y0, x1, y1]` before `limit`?
fn ray_hits_box(o: Point2, inv: (f64, f64), bb: &[f64; 4], limit: f64) -> bool {
    let (tx0, tx1) = ((bb[0] - o.x) * inv.0, (bb[2] - o.x) * inv.0);
    let (ty0, ty1) = ((bb[1] - o.y) * inv.1, (bb[3] - o.y) * inv.1);
    // NaN (0·∞ for a ray exactly along a box side) must not reject: f64::max/min skip NaN.
    let enter = tx0.min(tx1).max(ty0.min(ty1));
    let exit = tx0.max(tx1).min(ty0.max(ty1));
    exit >= enter.max(0.0) && enter <= limit
}

/// Distance along the ray to the segment `a`–`b`, `None` when it misses or is parallel.
fn ray_segment(o: Point2, d: (f64, f64), a: Point2, b: Point2) -> Option<f64> {
    let e = (b.x - a.x, b.y - a.y);
    let den = d.0 * e.1 - d.1 * e.0;
    if den == 0.0 {
        return None;
    }
    let w = (a.x - o.x, a.y - o.y);
    let t = (w.0 * e.1 - w.1 * e.0) / den;
    let u = (w.0 * d.1 - w.1 * d.0) / den;
    (t > 1e-9 && (0.0..=1.0).contains(&u)).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn casts_hit_the_right_material() {
        let objects = production_hall_objects();
        let caster = Caster::new(&objects);
        // From (3, 12.5) looking south: glass fence at y = 10.5 + 0.01.
        let h = caster.cast(Point2::new(10.0, 12.5), (0.0, -1.0), &[]).unwrap();
        assert_eq!(h.material, Material::Glass);
        assert!((h.range - 1.99).abs() < 1e-9, "{h:?}");
        // Skipping the fence, the beam reaches the press's north face at y = 9.
        let behind = caster.cast(Point2::new(10.0, 12.5), (0.0, -1.0), &[h.object]).unwrap();
        assert_eq!(behind.material, Material::Machine);
        assert!((behind.range - 3.5).abs() < 1e-9);
        // Pillar 0 at (8, 1.3), radius 0.2 (16-gon: the flat side is 0.2·cos(π/16) away).
        let p = caster.cast(Point2::new(8.0, 3.0), (0.0, -1.0), &[]).unwrap();
        assert_eq!(p.material, Material::Steel);
        assert!((p.range - (1.7 - 0.2)).abs() < 0.01, "{p:?}");
        // East wall inner face at x = 29.9.
        let w = caster.cast(Point2::new(27.0, 3.0), (1.0, 0.0), &[]).unwrap();
        assert_eq!(w.material, Material::Wall);
        assert!((w.range - 2.9).abs() < 1e-9);
        assert!((w.normal.0.abs() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn cast_all_lists_every_surface_in_order() {
        let objects = production_hall_objects();
        let caster = Caster::new(&objects);
        let mut hits = Vec::new();
        // South from (10, 12.5): the fence's two faces, the press's two faces, the south wall's two.
        caster.cast_all(Point2::new(10.0, 12.5), (0.0, -1.0), 100.0, &mut hits);
        let names: Vec<&str> = hits.iter().map(|h| objects[h.object].name.as_str()).collect();
        assert_eq!(
            names,
            ["glass_fence", "glass_fence", "machine_press", "machine_press", "wall_south", "wall_south"],
            "{hits:?}"
        );
        assert!(hits.windows(2).all(|w| w[0].range <= w[1].range));
        assert_eq!(hits[0].range, caster.cast(Point2::new(10.0, 12.5), (0.0, -1.0), &[]).unwrap().range);
        caster.cast_all(Point2::new(10.0, 12.5), (0.0, -1.0), 3.0, &mut hits);
        assert_eq!(hits.len(), 2, "the range limit drops the far faces");
    }

    #[test]
    fn distances_and_containment() {
        let objects = production_hall_objects();
        let press = objects.iter().find(|o| o.name == "machine_press").unwrap();
        assert_eq!(press.distance(Point2::new(9.0, 7.0)), 0.0);
        assert!((press.distance(Point2::new(9.0, 3.0)) - 2.5).abs() < 1e-12);
        let wall = &objects[0];
        assert!((wall.distance(Point2::new(5.0, 3.0)) - 2.9).abs() < 1e-12);
        assert!(Rect::new(0.0, 0.0, 1.0, 1.0).contains(Point2::new(0.5, 1.0)));
        assert!(Rect::new(0.0, 0.0, 1.0, 1.0).check("r").is_ok());
        assert!(Rect::new(1.0, 0.0, 1.0, 1.0).check("r").is_err());
        for (i, o) in objects.iter().enumerate() {
            assert!(o.check(&format!("objects[{i}]")).is_ok());
        }
    }
}
