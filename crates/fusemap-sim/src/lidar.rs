//! The lidar: each beam is cast at its own time along the sweep from the true pose of
//! that instant (the motion distortion de-skewing removes, design document §2.2, §4.1),
//! then the failures of glass, polished steel, depth edges and dropouts are applied.
//! The walking person is traced at the beam's own time too (a cheap circle test beside the
//! static caster, which stays unchanged).

use crate::messages::SimScan;
use crate::path::Trajectory;
use crate::person::{ray_circle, PersonConfig};
use crate::sensors::LidarConfig;
use crate::world::{Caster, Material};
use fusemap_core::geometry::Point2;
use fusemap_core::sim::SplitMix64;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::sensor_msgs::LaserScan;
use fusemap_io::log::ros2::msgs::std_msgs::Header;

/// What the lidar did over a run, for reports and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LidarStats {
    /// Beams simulated.
    pub beams: u64,
    /// Beams whose first surface was glass.
    pub glass_hits: u64,
    /// Of those, beams that passed through.
    pub glass_passed: u64,
    /// Beams whose (first reflecting) surface was steel.
    pub steel_hits: u64,
    /// Of those, beams turned into flying points.
    pub flying_points: u64,
    /// Beams replaced by a mixed pixel at a depth edge.
    pub mixed_pixels: u64,
    /// Beams reported as NaN, inf or 0 by a dropout.
    pub dropouts: u64,
    /// Beams whose return came from the walking person.
    pub person_hits: u64,
}

/// Intensity of a return from the person (clothing: between machine and wall).
const PERSON_INTENSITY: f32 = 30.0;

fn intensity(m: Option<Material>) -> f32 {
    match m {
        None => 0.0,
        Some(Material::Glass) => 10.0,
        Some(Material::Machine) => 40.0,
        Some(Material::Wall) => 50.0,
        Some(Material::Steel) => 90.0,
    }
}

/// The range one beam measures before noise, and the intensity of what returned it.
/// `person` is the person's circle (centre, radius) at the beam's time, if present: it
/// returns the beam when it stands before the surface the beam would otherwise return
/// from (also behind glass the beam passed).
fn trace(
    caster: &Caster,
    cfg: &LidarConfig,
    (origin, dir): (Point2, (f64, f64)),
    person: Option<(Point2, f64)>,
    rng: &mut SplitMix64,
    stats: &mut LidarStats,
) -> (Option<f64>, f32) {
    let person_range = person.and_then(|(c, r)| ray_circle(origin, dir, c, r));
    let mut skip: Vec<usize> = Vec::new();
    let mut first = true;
    while skip.len() < 4 {
        let hit = caster.cast(origin, dir, &skip);
        if let Some(rp) = person_range {
            if hit.is_none_or(|h| rp < h.range) {
                stats.person_hits += 1;
                return (Some(rp), PERSON_INTENSITY);
            }
        }
        let Some(hit) = hit else { return (None, intensity(None)) };
        match hit.material {
            Material::Glass => {
                if first {
                    stats.glass_hits += 1;
                }
                if rng.next_f64() < cfg.glass_pass_probability {
                    if first {
                        stats.glass_passed += 1;
                    }
                    skip.push(hit.object);
                    first = false;
                    continue;
                }
            }
            Material::Steel => {
                stats.steel_hits += 1;
                if rng.next_f64() < cfg.steel_flying_probability {
                    stats.flying_points += 1;
                    // Mirror reflection r = d − 2 (d·n) n; the echo travels the bounced path.
                    let dn = dir.0 * hit.normal.0 + dir.1 * hit.normal.1;
                    let r = (dir.0 - 2.0 * dn * hit.normal.0, dir.1 - 2.0 * dn * hit.normal.1);
                    let at = Point2::new(origin.x + dir.0 * hit.range, origin.y + dir.1 * hit.range);
                    let bounce = caster.cast(at, r, &[hit.object]);
                    return (bounce.map(|b| hit.range + b.range), intensity(bounce.map(|b| b.material)));
                }
            }
            Material::Wall | Material::Machine => {}
        }
        return (Some(hit.range), intensity(Some(hit.material)));
    }
    (None, intensity(None))
}

/// Simulates every scan of the run. `start` is the clock at t = 0.
pub fn simulate_scans(
    cfg: &LidarConfig,
    frame_id: &str,
    caster: &Caster,
    person: &PersonConfig,
    traj: &Trajectory,
    start: Stamp,
    rng: &mut SplitMix64,
) -> (Vec<SimScan>, LidarStats) {
    let mut stats = LidarStats::default();
    // Validated before: the mount is level.
    let mount = cfg.mount.to_planar(1e-6).unwrap_or_default();
    let (a0, inc, ti) = (cfg.angle_min(), cfg.angle_increment(), cfg.time_increment());
    let period = 1.0 / cfg.rate_hz;
    let mut scans = Vec::new();
    let mut k = 0usize;
    loop {
        let t0 = k as f64 * period;
        if t0 + cfg.sweep_time_s > traj.duration() {
            break;
        }
        let mut truth: Vec<(Option<f64>, f32)> = Vec::with_capacity(cfg.beams);
        for i in 0..cfg.beams {
            let t = t0 + i as f64 * ti;
            let pose = traj.pose_at(t);
            let origin = pose * mount.origin_in_base();
            let (s, c) = (pose.theta + mount.beam_angle_in_base(a0 + i as f64 * inc)).sin_cos();
            let who = person.position_at(t).map(|p| (p, person.radius_m));
            truth.push(trace(caster, cfg, (origin, (c, s)), who, rng, &mut stats));
        }
        stats.beams += cfg.beams as u64;
        let mut ranges: Vec<Option<f64>> = truth.iter().map(|t| t.0).collect();
        // Mixed pixels: a beam whose footprint straddles a depth edge returns a blend.
        for i in 0..cfg.beams.saturating_sub(1) {
            if let (Some(a), Some(b)) = (truth[i].0, truth[i + 1].0) {
                if (a - b).abs() > cfg.edge_jump_m && rng.next_f64() < cfg.edge_mixed_probability {
                    ranges[i] = Some(rng.uniform(a.min(b), a.max(b)));
                    stats.mixed_pixels += 1;
                }
            }
        }
        let mut out = Vec::with_capacity(cfg.beams);
        for r in ranges {
            let mut v = match r {
                Some(r) => r + cfg.range_noise_std_m * rng.gaussian(),
                None => f64::INFINITY,
            };
            if v > cfg.range_max_m {
                v = f64::INFINITY;
            }
            if rng.next_f64() < cfg.dropout_probability {
                stats.dropouts += 1;
                v = [f64::NAN, f64::INFINITY, 0.0][(rng.next_u64() % 3) as usize];
            }
            out.push(v as f32);
        }
        let stamp = Stamp(start.0 + ((t0 + cfg.time_offset_s) * 1e9).round() as i64);
        scans.push(SimScan::new(
            &cfg.topic,
            LaserScan {
                header: Header::new(stamp, frame_id),
                angle_min: a0 as f32,
                angle_max: (a0 + inc * (cfg.beams - 1) as f64) as f32,
                angle_increment: inc as f32,
                time_increment: ti as f32,
                scan_time: period as f32,
                range_min: cfg.range_min_m as f32,
                range_max: cfg.range_max_m as f32,
                ranges: out,
                intensities: truth.iter().map(|t| t.1).collect(),
            },
        ));
        k += 1;
    }
    (scans, stats)
}
