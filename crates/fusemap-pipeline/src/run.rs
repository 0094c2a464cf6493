//! One mapping pass over a recording: the whole log → map pipeline in one library call.
//!
//! Steps: the first pass reads the pose sensors and an inventory of the scans; the sensors
//! are bound to topics; the pose track is chosen and built (the estimator and its smoother
//! over the whole log, when the log has the sensors for it); each lidar's mount is
//! resolved; then the second pass streams every lidar's scans through the time-ordered
//! merge into the engine, each scan with the pose at its own stamp (or each beam's,
//! de-skewed). Every scan that cannot be posed is skipped and counted with its reason;
//! clock faults are reported, and the usable part of the log is still mapped.

pub use crate::map_pass::{map_with_track, MapRun, PassMaps};
pub use crate::progress::Progress;
use crate::recording::Inventory;
pub use crate::sensors::topics_by_kind;
use crate::sensors::{bind, Bound};
pub use crate::sync::{limits, sync_mode};
use crate::track::{choose, ChosenTrack};
use crate::{PipelineError, Stage};
use fusemap_core::config::Plan;
use std::path::Path;
use std::time::Instant;

/// Maps the log at `path` with `plan`.
pub fn map_log(plan: &Plan, path: &Path, progress: &mut dyn FnMut(Progress)) -> Result<MapRun, PipelineError> {
    progress(Progress::Phase { name: "reading", total: 0 });
    let inv = Inventory::read_with(path, &plan.limits)?;
    progress(Progress::Done);
    map_inventory(plan, &inv, progress)
}

/// Binds the sensors and builds the pose track from the pose sensors alone.
pub fn prepare_track(plan: &Plan, inv: &Inventory) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    if inv.scans.is_empty() && inv.stats.malformed > 0 {
        return Err(PipelineError::refused(
            Stage::Sensors,
            format!(
                "the log holds no usable laser scans; {} records could not be decoded, the first: {}",
                inv.stats.malformed,
                inv.stats.malformed_examples.first().map_or("", |s| s.as_str())
            ),
        ));
    }
    let bound = bind(plan, &topics_by_kind(inv))?;
    let t0 = Instant::now();
    let chosen = choose(inv, &plan.log, &bound, || crate::estimation::estimator_track(plan, inv, &bound))?;
    Ok((bound, chosen, t0.elapsed().as_secs_f64()))
}

/// A SLAM run that leaves more than this share of its scans without an optimised pose is
/// reported with a warning, not as a correction.
const LOST_POSES_NOTE_SHARE: f64 = 0.01;

/// [`prepare_track`], then SLAM corrects the track when [`crate::slam::applies`] says so.
pub fn prepare(plan: &Plan, inv: &Inventory) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    prepare_with(plan, inv, &mut |_| {})
}

/// [`prepare`] with progress reports.
pub fn prepare_with(
    plan: &Plan,
    inv: &Inventory,
    progress: &mut dyn FnMut(Progress),
) -> Result<(Bound, ChosenTrack, f64), PipelineError> {
    let (bound, chosen, track_s) = prepare_track(plan, inv)?;
    let (chosen, track_s) = correct(plan, inv, &bound, chosen, track_s, progress)?;
    Ok((bound, chosen, track_s))
}

/// SLAM's correction of the track from [`prepare_track`], when [`crate::slam::applies`]
/// says so (else the track as it is); the seconds spent on the track so far.
pub fn correct(
    plan: &Plan,
    inv: &Inventory,
    bound: &Bound,
    chosen: ChosenTrack,
    track_s: f64,
    progress: &mut dyn FnMut(Progress),
) -> Result<(ChosenTrack, f64), PipelineError> {
    let (on, reason) = crate::slam::applies(plan, inv, bound, &chosen);
    if !on {
        return Ok((chosen, track_s));
    }
    let t0 = Instant::now();
    let mut run = crate::slam::run(plan, inv, bound, &chosen, reason, progress)?;
    let mut track = crate::slam::track(chosen, &mut run, &plan.log);
    // Scans SLAM was given but left without an optimised pose: a few (a refused reading)
    // are normal; more means the run did not correct the log (equal stamps collapsing the
    // track did this once), and the note says so instead of "corrected".
    let given = run.summary.counts.scans;
    let placed = run.summary.scan_poses.len() as u64;
    let lost = given.saturating_sub(placed);
    let verb = if lost as f64 > LOST_POSES_NOTE_SHARE * given as f64 {
        format!(
            "WARNING: SLAM lost the pose of {lost} of {given} scans ({:.1} %), which keep the uncorrected track; the map may be wrong",
            100.0 * lost as f64 / given.max(1) as f64
        )
    } else {
        "SLAM corrected the poses".to_string()
    };
    track.notes.push(format!(
        "{verb} ({}): {} scans matched ({} degenerate), {} nodes, {} submaps, {} of {} loop-closure searches accepted",
        run.summary.reason,
        run.summary.counts.matched + run.summary.counts.degenerate,
        run.summary.counts.degenerate,
        run.summary.counts.nodes,
        run.summary.counts.submaps,
        run.summary.counts.loop_accepted,
        run.summary.counts.loop_searches,
    ));
    // Why the result is what it is: no loop closed, a corridor, unmatched scans, searches
    // the budget left out.
    for f in run.summary.counts.findings(plan.slam.loop_closure, plan.slam.loop_closure_global_after_m) {
        track.notes.push(format!("SLAM: {f}"));
    }
    track.slam = Some(Box::new(run.summary));
    Ok((track, track_s + t0.elapsed().as_secs_f64()))
}

/// Maps a recording whose first pass is done.
pub fn map_inventory(
    plan: &Plan,
    inv: &Inventory,
    progress: &mut dyn FnMut(Progress),
) -> Result<MapRun, PipelineError> {
    let (bound, chosen, track_s) = prepare_with(plan, inv, progress)?;
    let maps = PassMaps { endpoints: plan.output.endpoint_clouds(), ..Default::default() };
    map_with_track(plan, inv, &bound, chosen, track_s, maps, progress)
}
