//! A simulated world mapped along a trajectory: each pose's scans simulated from the
//! world and inserted with that pose (the design document's corridor, `--world` files).
//! No log and no pose track: the poses are the truth, less those a glitch check refuses.

use crate::progress::Progress;
use crate::{PipelineError, Stage};
use fusemap_core::config::Plan;
use fusemap_core::fusion::Engine;
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::FusionGrid;
use fusemap_core::measurement::SensorId;
use fusemap_core::sim::{simulate_scan, ScannerSpec, World};
use fusemap_core::time::{plausible_samples, Stamp};

/// A mapped world: the engine with its map, and the notes of the run.
pub struct WorldRun {
    /// The engine, holding the map and its counters.
    pub engine: Engine,
    /// Facts a user should know (poses left out as glitches).
    pub notes: Vec<String>,
}

/// Maps `world` seen by `scanner` from each of `poses` with the plan's grid and lidars.
///
/// Scan `i` is taken at `i / rate`: a pose implying an impossible motion from its
/// neighbours is a glitch (as on a log's pose streams), left out and counted in a note.
/// An engine refusal (a map past `limits.map_cells`) names the scan.
pub fn map_world(
    plan: &Plan,
    world: &World,
    scanner: &ScannerSpec,
    poses: &[Pose2],
    progress: &mut dyn FnMut(Progress),
) -> Result<WorldRun, PipelineError> {
    let mut engine = Engine::new(FusionGrid::new(plan.geometry, plan.occupancy));
    engine.set_limits(&plan.limits);
    let ids: Vec<SensorId> = plan.lidars.iter().map(|l| engine.add_lidar(l.name.clone(), l.model)).collect();
    let stamp = |i: usize| Stamp::from_secs_f64(i as f64 / scanner.rate_hz).unwrap_or_default();
    let timed: Vec<_> = poses.iter().enumerate().map(|(i, p)| (stamp(i), *p)).collect();
    let keep = plausible_samples(&timed, &plan.log.motion_limits());
    let glitches = keep.iter().filter(|k| !**k).count() as u64;
    progress(Progress::Phase { name: "mapping", total: poses.len() as u64 });
    for (i, pose) in poses.iter().enumerate() {
        if keep[i] {
            for (k, id) in ids.iter().enumerate() {
                let scan = simulate_scan(world, scanner, plan.lidars[k].model.mount(), *pose, stamp(i));
                engine.insert_scan(*id, &scan, *pose).map_err(|e| {
                    PipelineError::refused(Stage::of_engine_error(&e).unwrap_or(Stage::World), format!("scan {i}: {e}"))
                })?;
            }
        }
        progress(Progress::Advance(1));
    }
    progress(Progress::Done);
    let notes = if glitches > 0 {
        vec![crate::track::glitch_note("the world file's trajectory", glitches, &plan.log)]
    } else {
        Vec::new()
    };
    Ok(WorldRun { engine, notes })
}
