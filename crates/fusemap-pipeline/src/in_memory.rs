//! A log mapped into memory instead of files: the arrays `map.npz` would hold, the track
//! and the run report, for a front end that hands them over directly (the Python
//! package's `map_log`). The map is the same raster [`crate::outputs::finish`] writes,
//! cell for cell: the same pass, the same export view.

use crate::job::JobError;
use crate::outputs::{layers_of, view_of, ExportOptions, ExportRoom, Layers, MapView};
use crate::{PipelineError, Progress};
use fusemap_core::config::{Plan, PointsMode};
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::Raster;
use fusemap_core::time::Stamp;
use std::path::Path;

/// A log's map, in memory.
pub struct MappedLog {
    /// The occupancy map over the observed cells' bounding box (`map.npz`'s raster).
    pub raster: Raster,
    /// The semantic and dynamic layers, with a camera.
    pub layers: Option<Layers>,
    /// The base's track (`trajectory.tum`'s poses).
    pub trajectory: Vec<(Stamp, Pose2)>,
    /// The log's format, its run report (`summary.json`'s `log`) and the run's notes.
    pub report: serde_json::Value,
}

/// Maps the log at `path` with `plan`. A map with no observed cell, or one past
/// `limits.export_cells` (which the files would hold sparsely), is an error that says so.
pub fn map_log_in_memory(plan: &Plan, path: &Path) -> Result<MappedLog, JobError> {
    let input = path.display().to_string();
    // No file is written, so no endpoint cloud: its returns are not kept.
    let mut plan = plan.clone();
    plan.output.points = PointsMode::Cells;
    let plan = &plan;
    let run = crate::map_log(plan, path, &mut |_: Progress| {}).map_err(|error| match error {
        PipelineError::Read(e) => JobError::File(e),
        error => JobError::Run { input: input.clone(), error },
    })?;
    let mut notes = run.notes.clone();
    let grid = run.engine.grid();
    let room = ExportRoom::of(run.engine.export_room(run.engine.maps().primary()));
    let view = view_of(grid, &ExportOptions::of(plan, None), room, &mut notes)?;
    let raster = match view {
        MapView::Dense(r) => r,
        MapView::Empty => return Err(JobError::Arguments(format!("{input}: no cell was observed"))),
        MapView::Sparse { .. } => {
            return Err(JobError::Arguments(format!(
                "{input}: the map's box holds more than limits.export_cells ({}) cells; `fusemap map` writes it \
                 sparsely, in memory it is refused: raise limits.export_cells",
                plan.limits.export_cells
            )))
        }
    };
    let layers = layers_of(&run.engine, grid, &raster);
    let report = serde_json::json!({
        "source": input,
        "format": run.format.to_string(),
        "notes": notes,
        "log": serde_json::to_value(&run.report)?,
    });
    Ok(MappedLog { raster, layers, trajectory: run.trajectory, report })
}
