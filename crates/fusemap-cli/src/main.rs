//! `fusemap`: multi-sensor occupancy-grid mapping.

mod commands;
mod progress;

use clap::{Parser, Subcommand};
use fusemap_core::metrics::RelationMatching;
use std::path::PathBuf;

/// Turns a robot's sensor observations into a probabilistic occupancy-grid map.
#[derive(Parser)]
#[command(name = "fusemap", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The design document's scenario end to end: the production line simulated (built
    /// in), mapped lidar-only, camera-only and fused, each scored against ground truth and
    /// drawn side by side (DIR/comparison.png). --corridor: the document's §3.3 corridor.
    Demo {
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// A config file (TOML) instead of the built-in one (configs/production_line.toml,
        /// or the defaults for --corridor).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Map the design document's corridor (40 poses, 181 beams, 0.05 m) instead.
        #[arg(long)]
        corridor: bool,
    },
    /// Map a robot log (CARMEN .log/.clf/.gz, ROS 1 .bag, .mcap, rosbag2 directory) or a
    /// simulated run of a world file.
    Map {
        /// Config file (TOML); see configs/example.toml. Default: built-in defaults.
        #[arg(long)]
        config: Option<PathBuf>,
        /// A world file (TOML) to simulate instead of a log.
        #[arg(long)]
        world: Option<PathBuf>,
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// The log, recognised by its content.
        log: Option<PathBuf>,
        /// Export this region densely (metres: x0,y0,x1,y1) instead of everything observed;
        /// also how to get a dense raster of part of a map past limits.export_cells.
        #[arg(long, value_parser = fusemap_pipeline::outputs::parse_crop, allow_hyphen_values = true)]
        crop: Option<fusemap_pipeline::outputs::Crop>,
    },
    /// The design document's §5 on a log: the lidar-only (M1), camera-only (M2) and
    /// fused (M3) maps built from the log's earlier part, the held-out later part's points
    /// projected onto each (hit rates), their entropies, and a verdict: fusion_helps,
    /// no_gain or check_sync_and_extrinsics (naming the sensor). Writes the fused map,
    /// DIR/fusion_validate.npz and summary.json's `validation`; exits 0 whatever the verdict.
    Validate {
        /// Config file (TOML); its `[validate]` table sets the held-out share and thresholds.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// The log, recognised by its content.
        log: PathBuf,
    },
    /// Estimate from the log what §4.3 tells a user to check by hand: the lidar's mount
    /// (yaw, x, y), its clock offset and the wheel odometry's scale, from the lidar's
    /// motion (SLAM) against the wheels', with 95 % intervals; parameters the log cannot fix are named, not
    /// invented. Writes DIR/calibration.toml (the `[[sensor]]` table to paste), the map and
    /// summary.json's `calibration`.
    Calibrate {
        /// Config file (TOML), as for `map`.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// The log, recognised by its content.
        log: PathBuf,
    },
    /// Check a log's timing: rates, jitter, delays, stamps going backwards, gaps, and how
    /// many scans get a pose.
    Doctor {
        /// Config file (TOML) for topics and sync settings.
        #[arg(long)]
        config: Option<PathBuf>,
        /// The log.
        log: PathBuf,
    },
    /// Score a trajectory (TUM) by the SLAM benchmark's relations (Kümmerle et al. 2009):
    /// mean ± standard deviation of the translational (m) and rotational (deg) errors of
    /// the relative motions, as Hess et al. 2016 report them.
    Relations {
        /// A relations file: `t1 t2 x y z roll pitch yaw` a line.
        #[arg(long)]
        relations: PathBuf,
        /// The trajectory to score, TUM format (`t x y z qx qy qz qw`).
        #[arg(long)]
        trajectory: PathBuf,
        /// How far (milliseconds) a pose's stamp may lie from a relation's stamp; the
        /// nearest pose is taken.
        #[arg(long, default_value_t = RelationMatching::TOLERANCE_MS)]
        tolerance_ms: f64,
        /// A stamp with no pose within the tolerance takes the pose interpolated between
        /// the two around it when they are at most this far apart, milliseconds (a
        /// trajectory written at the odometry's rate has no pose at the scan stamps the
        /// relations name).
        #[arg(long, default_value_t = RelationMatching::MAX_GAP_MS)]
        max_gap_ms: f64,
        /// `X,Y,YAW` (metres, radians): score the pose of a sensor mounted here on the
        /// trajectory's frame instead. The benchmark's relations are between laser poses and
        /// fusemap writes the base frame's: give `log.slam.sensor_in_base` of
        /// `summary.json`.
        #[arg(long, value_name = "X,Y,YAW")]
        sensor_in_base: Option<String>,
        /// One JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Simulate the design document's production line (or a scenario file's world) and
    /// write it as a rosbag2 bag (MCAP) with its ground truth: DIR/bag, DIR/truth.yaml +
    /// truth.pgm (map_server), DIR/truth.tum.
    Simulate {
        /// A scenario file (TOML); default: the built-in production line.
        scenario: Option<PathBuf>,
        /// Output directory (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// Cell side of the true map, metres.
        #[arg(long, default_value_t = 0.05)]
        resolution: f64,
        /// Replace an existing bag in DIR.
        #[arg(long)]
        overwrite: bool,
    },
    /// The SLAM generalisation bench: every corrected CARMEN log of the shared datasets
    /// turned into a raw log with odometry of a known error (none, mild, strong drift),
    /// mapped with SLAM and scored against the corrected poses (local and revisit
    /// relations, ATE), SLAM off beside it. Prints a markdown table.
    SlamBench {
        /// The shared directory holding `datasets/` (default: ../shared).
        #[arg(long, default_value = "../shared")]
        shared: PathBuf,
        /// Config file (TOML) whose `[slam]` and other settings the runs use.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Only these logs (comma-separated names; default: all eleven).
        #[arg(long, value_delimiter = ',')]
        logs: Vec<String>,
        /// Only these drifts (zero, mild, strong; comma-separated; default: all).
        #[arg(long, value_delimiter = ',')]
        drift: Vec<String>,
        /// Stamp every message 0.1 s after the last instead of as the log has it (some
        /// logs print every stamp as the same number).
        #[arg(long)]
        distinct_stamps: bool,
        /// One JSON object per case instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Insertion throughput on fixed synthetic workloads (a: corridor, b: corridor x500,
    /// c: 39 m box with 1,081-beam scans, d and e: 640 x 480 camera frames projected and
    /// fused at stride 4 and 1).
    Bench {
        /// Run one workload in this process (a, b, c, d or e); default: each in a child
        /// process.
        #[arg(long)]
        workload: Option<char>,
        /// Insert the scans of a SCAN2D01 scan file instead (the baselines' format), on
        /// its grid and range limits, for side-by-side comparisons.
        #[arg(long, conflicts_with = "workload")]
        scanfile: Option<PathBuf>,
        /// With --scanfile: insert only the first N scans (the baselines time slow systems
        /// on the first 250 scans of workload c).
        #[arg(long, requires = "scanfile")]
        max_scans: Option<usize>,
        /// Walk scans of at least N cell visits in waves of tiles on the pool's threads
        /// (default: 100,000 with two threads or more; 0: every scan); the map is the same.
        #[arg(long, value_name = "N")]
        waves_min_cells: Option<u64>,
        /// One JSON object per line per workload instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() {
    fusemap_core::slam::adopt_calling_thread();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo { out, config, corridor } => {
            if corridor {
                commands::demo::corridor(&out, config.as_deref())
            } else {
                commands::demo::production(&out, config.as_deref())
            }
        }
        Command::Map { config, world, out, log, crop } => {
            commands::map::map(config.as_deref(), world.as_deref(), log.as_deref(), &out, crop)
        }
        Command::Calibrate { config, out, log } => commands::calibrate::run(config.as_deref(), &log, &out),
        Command::Validate { config, out, log } => commands::validate::run(config.as_deref(), &log, &out),
        Command::Doctor { config, log } => commands::doctor::run(config.as_deref(), &log),
        Command::Relations { relations, trajectory, tolerance_ms, max_gap_ms, sensor_in_base, json } => {
            let sensor = sensor_in_base.as_deref();
            commands::relations::run(&relations, &trajectory, tolerance_ms, max_gap_ms, sensor, json)
        }
        Command::Simulate { scenario, out, resolution, overwrite } => {
            commands::simulate::run(scenario.as_deref(), &out, resolution, overwrite)
        }
        Command::SlamBench { shared, config, logs, drift, distinct_stamps, json } => {
            commands::slam_bench::run(&shared, config.as_deref(), &logs, &drift, distinct_stamps, json)
        }
        Command::Bench { workload, scanfile, max_scans, waves_min_cells, json } => {
            commands::bench::run(workload, scanfile.as_deref(), max_scans, waves_min_cells, json)
        }
    };
    if let Err(e) = result {
        eprintln!("error: {}", format_chain(&e));
        std::process::exit(1);
    }
}

/// The error and its causes on one line.
fn format_chain(e: &anyhow::Error) -> String {
    fusemap_io::text::error_line(e.as_ref())
}
