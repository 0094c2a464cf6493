//! `fusemap bench`: insertion throughput on the fixed synthetic workloads.
//!
//! Without `--workload`, each workload runs in its own child process (this binary with
//! `--workload X --json`) so that every peak-RSS figure is that workload's whole run,
//! its scans included, and not the high-water mark of an earlier one.

use anyhow::{bail, Context, Result};
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::PlanarMount;
use fusemap_core::grid::{FusionGrid, GridGeometry, OccupancyParams, PassThroughParams};
use fusemap_core::sensor::LidarModel;
use fusemap_core::sim::{workload, WORKLOADS};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One workload's figures.
#[derive(Debug, Serialize, Deserialize)]
pub struct BenchRow {
    /// `a`, `b` or `c`.
    pub workload: String,
    /// What it is.
    pub description: String,
    /// Scans inserted.
    pub scans: u64,
    /// Beams inserted (valid or not).
    pub beams: u64,
    /// Rays walked.
    pub rays: u64,
    /// Cells visited by the walks.
    pub cell_visits: u64,
    /// Mean cells visited per walked ray.
    pub cell_visits_per_ray: f64,
    /// Seconds simulating (or reading) the scans (not part of the rates).
    pub simulate_s: f64,
    /// Seconds inserting (the rates' denominator).
    pub insert_s: f64,
    /// Scans per second of insertion.
    pub scans_per_s: f64,
    /// Beams per second of insertion.
    pub beams_per_s: f64,
    /// Cell visits per second of insertion.
    pub cell_visits_per_s: f64,
    /// Peak resident memory of the whole process (VmHWM), bytes.
    pub peak_rss_bytes: u64,
    /// Allocated tiles at the end.
    pub tiles: u64,
}

impl BenchRow {
    /// The figures of a finished run of `engine` over `beams` beams.
    fn new(workload: String, description: String, engine: &Engine, beams: u64, simulate_s: f64, insert_s: f64) -> Self {
        let st = engine.stats().insert;
        let scans = engine.stats().measurements;
        Self {
            workload,
            description,
            scans,
            beams,
            rays: st.rays,
            cell_visits: st.cell_visits,
            cell_visits_per_ray: st.cell_visits as f64 / st.rays.max(1) as f64,
            simulate_s,
            insert_s,
            scans_per_s: scans as f64 / insert_s,
            beams_per_s: beams as f64 / insert_s,
            cell_visits_per_s: st.cell_visits as f64 / insert_s,
            peak_rss_bytes: peak_rss_bytes(),
            tiles: engine.grid().tile_count() as u64,
        }
    }
}

/// The camera workloads: a 640 × 480 label + depth pair of a box room, projected and
/// fused at stride 4 (`d`) and 1 (`e`), 200 frames from poses walking and turning.
pub const CAMERA_WORKLOADS: [char; 2] = ['d', 'e'];

/// Runs camera workload `name` (`d`: stride 4, `e`: stride 1). Beams are pixels looked at.
pub fn run_camera(name: char) -> Result<BenchRow> {
    use fusemap_core::sensor::camera::{optical_mount, CameraModel, CameraParams, ClassTable, Pinhole};
    let stride = if name == 'd' { 4 } else { 1 };
    let t0 = Instant::now();
    let pinhole = Pinhole { width: 640, height: 480, fx: 457.0, fy: 457.0, cx: 319.5, cy: 239.5 };
    let mount = optical_mount([0.25, 0.0, 1.0], 0.0, 25f64.to_radians());
    let params = CameraParams { stride, ..Default::default() };
    let model = CameraModel::new(pinhole, mount, params, 0.05, ClassTable::production_default())?;
    let (labels, depth) = fusemap_core::sim::camera_frame::room_frame(&model, 4.0, 3.0);
    let simulate_s = t0.elapsed().as_secs_f64();
    let mut engine = Engine::new(FusionGrid::new(GridGeometry::centered(0.05)?, OccupancyParams::default()));
    let camera = engine.add_camera("camera", model);
    engine.set_dynamic(fusemap_core::grid::DynamicParams::default(), true);
    let frames = 200;
    let t1 = Instant::now();
    for k in 0..frames {
        let pose = fusemap_core::geometry::Pose2::new(0.01 * k as f64, 0.0, 0.02 * k as f64);
        let stamp = fusemap_core::time::Stamp(k as i64 * 33_000_000);
        engine.insert_camera_frame(camera, None, stamp, &labels, &depth, pose)?;
    }
    let insert_s = t1.elapsed().as_secs_f64();
    let pixels = engine.sensor_stats().map(|s| s.pixels.seen).sum();
    let description = format!("{frames} camera frames 640 x 480 label + depth, stride {stride} (beams = pixels)");
    Ok(BenchRow::new(name.to_string(), description, &engine, pixels, simulate_s, insert_s))
}

/// Runs workload `name` in this process, walking scans of at least `waves` cell visits
/// in waves of tiles (`None`: the engine's default).
pub fn run_one(name: char, waves: Option<u64>) -> Result<BenchRow> {
    if CAMERA_WORKLOADS.contains(&name) {
        return run_camera(name);
    }
    let t0 = Instant::now();
    let Some(w) = workload(name) else { bail!("unknown workload `{name}` (expected a, b, c, d or e)") };
    let simulate_s = t0.elapsed().as_secs_f64();
    // The map a `fusemap map` run gets by default (its pass-through rule included), so the
    // figures are what a user's run costs.
    let params = OccupancyParams { pass_through: PassThroughParams::default(), ..OccupancyParams::default() };
    let grid = FusionGrid::new(GridGeometry::centered(w.resolution)?, params);
    let mut engine = Engine::new(grid);
    if let Some(n) = waves {
        engine.set_waves_min_cells(n);
    }
    let laser = engine.add_lidar("laser", LidarModel::new(w.lidar, PlanarMount::default()));
    let t1 = Instant::now();
    for (scan, pose) in w.run.scans.iter().zip(&w.run.poses) {
        engine.insert_scan(laser, scan, *pose)?;
    }
    let insert_s = t1.elapsed().as_secs_f64();
    let beams: u64 = w.run.scans.iter().map(|s| s.ranges.len() as u64).sum();
    Ok(BenchRow::new(name.to_string(), w.description.to_string(), &engine, beams, simulate_s, insert_s))
}

/// Maps the scans of a `SCAN2D01` scan file (the baselines' input) in this process, on
/// the file's grid alignment and range limits, so that fusemap and the baselines insert
/// exactly the same beams; `waves` as for [`run_one`].
pub fn run_scanfile(path: &std::path::Path, max_scans: Option<usize>, waves: Option<u64>) -> Result<BenchRow> {
    let t0 = Instant::now();
    let mut f = fusemap_io::scanfile::read_scanfile(path)?;
    if let Some(n) = max_scans {
        let Some(beams) = n.checked_mul(f.beams) else {
            bail!(
                "--max-scans {n}: {n} scans of {} beams overflow a count; give at most {}",
                f.beams,
                usize::MAX / f.beams.max(1)
            );
        };
        f.poses.truncate(n);
        f.ranges.truncate(beams);
    }
    let simulate_s = t0.elapsed().as_secs_f64();
    let geometry = GridGeometry::new(f.resolution, fusemap_core::geometry::Point2::new(f.origin[0], f.origin[1]))?;
    let mut engine = Engine::new(FusionGrid::new(geometry, OccupancyParams::default()));
    if let Some(n) = waves {
        engine.set_waves_min_cells(n);
    }
    let params =
        fusemap_core::sensor::LidarParams { min_range: f.range_min, max_range: f.range_max, ..Default::default() };
    let laser = engine.add_lidar("laser", LidarModel::new(params, PlanarMount::default()));
    let mut scan = fusemap_core::sensor::LaserScan {
        stamp: fusemap_core::time::Stamp::ZERO,
        angle_min: f.angle_min,
        angle_increment: f.angle_increment,
        ranges: Vec::new(),
    };
    let t1 = Instant::now();
    for (i, pose) in f.poses.iter().enumerate() {
        scan.ranges.clear();
        scan.ranges.extend_from_slice(&f.ranges[i * f.beams..(i + 1) * f.beams]);
        engine.insert_scan(laser, &scan, *pose)?;
    }
    let insert_s = t1.elapsed().as_secs_f64();
    let workload =
        format!("scanfile:{}", path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()));
    let description = format!("{} scans x {} beams from {}", f.poses.len(), f.beams, path.display());
    Ok(BenchRow::new(workload, description, &engine, f.ranges.len() as u64, simulate_s, insert_s))
}

/// Peak resident set size of this process (`VmHWM` in `/proc/self/status`), 0 where
/// unavailable.
pub fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// `fusemap bench`.
pub fn run(
    which: Option<char>,
    scanfile: Option<&std::path::Path>,
    max_scans: Option<usize>,
    waves: Option<u64>,
    json: bool,
) -> Result<()> {
    let rows = match (which, scanfile) {
        (_, Some(path)) => vec![run_scanfile(path, max_scans, waves)?],
        (Some(w), None) => vec![run_one(w, waves)?],
        (None, None) => {
            let exe = std::env::current_exe().context("cannot find the fusemap executable to run workloads")?;
            let mut rows = Vec::new();
            for w in WORKLOADS.into_iter().chain(CAMERA_WORKLOADS) {
                let mut child = std::process::Command::new(&exe);
                child.args(["bench", "--json", "--workload", &w.to_string()]);
                if let Some(n) = waves {
                    child.args(["--waves-min-cells", &n.to_string()]);
                }
                let out = child.output().with_context(|| format!("running workload {w}"))?;
                if !out.status.success() {
                    bail!("workload {w} failed: {}", String::from_utf8_lossy(&out.stderr).trim());
                }
                let line = String::from_utf8_lossy(&out.stdout);
                rows.push(serde_json::from_str(line.trim()).with_context(|| format!("workload {w} printed `{line}`"))?);
            }
            rows
        }
    };
    if json {
        for r in &rows {
            println!("{}", serde_json::to_string(r)?);
        }
    } else {
        println!(
            "| workload | scans | beams | cells/ray | insert s | scans/s | beams/s | cell visits/s | peak RSS MiB |"
        );
        println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
        for r in &rows {
            println!(
                "| {} | {} | {} | {:.1} | {:.3} | {:.0} | {:.0} | {:.3e} | {:.1} |",
                r.workload,
                r.scans,
                r.beams,
                r.cell_visits_per_ray,
                r.insert_s,
                r.scans_per_s,
                r.beams_per_s,
                r.cell_visits_per_s,
                r.peak_rss_bytes as f64 / 1048576.0
            );
        }
    }
    Ok(())
}
