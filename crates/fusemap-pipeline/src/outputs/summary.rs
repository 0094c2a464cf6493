//! `summary.json`: what a mapping run did, in figures a user can check.

use fusemap_core::grid::{InsertStats, Raster};
use fusemap_core::metrics::EntropyReport;
use fusemap_core::sensor::ReturnCounts;
use fusemap_io::text::printable;
use serde::Serialize;
use std::fmt;

/// The summary of one mapping run.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// fusemap's version.
    pub fusemap_version: &'static str,
    /// What was mapped: `world` (simulated) or a log format.
    pub source_kind: String,
    /// The input file.
    pub source: String,
    /// Lidar scans inserted into the map.
    pub scans: u64,
    /// Camera frames inserted into the map (counted apart from the scans).
    pub camera_frames: u64,
    /// Beams in those scans.
    pub beams: u64,
    /// Beams by kind of return (invalid kinds are never evidence).
    pub returns: ReturnCounts,
    /// Rays walked through the grid. This and the counts below are the primary map's
    /// (the one written): a run that also builds single-sensor maps beside it (`demo`)
    /// reports the same figures as a run that builds the primary alone.
    pub rays_walked: u64,
    /// Rays the grid refused (non-finite or absurdly long).
    pub rays_rejected: u64,
    /// Cells visited by the walks (a cell counts once per ray crossing it).
    pub cell_visits: u64,
    /// Of `cell_visits`, those whose free evidence had the reduced weight of the
    /// pass-through rule (`[map.pass_through]`): behind a confidently occupied cell.
    pub cell_visits_attenuated: u64,
    /// Cell updates applied (at most one per cell per scan).
    pub cells_updated: CellsUpdated,
    /// The exported raster.
    pub map: MapInfo,
    /// Entropy over the known bounding box.
    pub entropy: Option<EntropyReport>,
    /// Wall time of the whole run, seconds.
    pub wall_time_s: f64,
    /// Facts about the input a user should know (skipped records, clock faults…).
    pub notes: Vec<String>,
    /// Extra counters of log input (absent for simulated runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log: Option<serde_json::Value>,
    /// `fusemap validate`'s maps, hit rates, entropies and verdict (§5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation: Option<serde_json::Value>,
    /// `fusemap calibrate`'s estimates with their intervals, and what it could not determine.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibration: Option<serde_json::Value>,
    /// The other files of this run's set, each with its size and SHA-256: written before
    /// this summary, which comes last (a summary whose files all match is a whole set).
    pub files: Vec<fusemap_io::output_set::OutputFile>,
}

/// Cell updates by kind.
#[derive(Debug, Serialize)]
pub struct CellsUpdated {
    /// Occupied (hit) updates.
    pub occupied: u64,
    /// Free (miss) updates.
    pub free: u64,
    /// Both.
    pub total: u64,
}

impl From<&InsertStats> for CellsUpdated {
    fn from(s: &InsertStats) -> Self {
        Self { occupied: s.hit_updates, free: s.miss_updates, total: s.hit_updates + s.miss_updates }
    }
}

/// The exported raster's placement.
#[derive(Debug, Serialize)]
pub struct MapInfo {
    /// Cell side, metres.
    pub resolution: f64,
    /// Lower-left corner of the raster, metres.
    pub origin: [f64; 2],
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Allocated tiles of 64 × 64 cells.
    pub tiles: usize,
}

impl MapInfo {
    /// From a raster and the tile count.
    pub fn new(r: Option<&Raster>, resolution: f64, tiles: usize) -> Self {
        match r {
            Some(r) => Self { resolution, origin: [r.origin.x, r.origin.y], width: r.width, height: r.height, tiles },
            None => Self { resolution, origin: [0.0, 0.0], width: 0, height: 0, tiles },
        }
    }
}

/// The summary for a person, one figure a line.
impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "source        {} ({})", printable(&self.source), self.source_kind)?;
        writeln!(f, "scans         {}", self.scans)?;
        if self.camera_frames > 0 {
            writeln!(f, "camera frames {}", self.camera_frames)?;
        }
        let r = &self.returns;
        writeln!(
            f,
            "beams         {} (valid {}, no return {}, invalid {}: nan {}, inf {}, zero {}, negative {}, below min {})",
            self.beams,
            r.valid,
            r.no_return,
            r.invalid(),
            r.nan,
            r.infinite,
            r.zero,
            r.negative,
            r.below_min
        )?;
        writeln!(
            f,
            "cells updated {} (occupied {}, free {}); {} cell visits by {} rays",
            self.cells_updated.total,
            self.cells_updated.occupied,
            self.cells_updated.free,
            self.cell_visits,
            self.rays_walked
        )?;
        if self.rays_rejected > 0 {
            writeln!(f, "rays refused  {}", self.rays_rejected)?;
        }
        writeln!(
            f,
            "map           {} x {} cells at {} m, origin ({:.3}, {:.3}), {} tiles",
            self.map.width,
            self.map.height,
            self.map.resolution,
            self.map.origin[0],
            self.map.origin[1],
            self.map.tiles
        )?;
        if let Some(e) = &self.entropy {
            writeln!(
                f,
                "entropy       {:.4} nats mean over the known box; {:.1} % of its cells known",
                e.mean_entropy_nats,
                100.0 * e.known_share
            )?;
        }
        for n in &self.notes {
            writeln!(f, "note          {}", printable(n))?;
        }
        writeln!(f, "wall time     {:.3} s", self.wall_time_s)
    }
}
