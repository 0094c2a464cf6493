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
    /// Where that time went, by phase.
    pub seconds: Seconds,
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

/// Where a run's wall time went, seconds by phase in the order the phases run. A phase
/// the run did not have is absent; `other` is what no named phase covers (a demo's scoring
/// and its other maps' files, validation's leave-one-out maps, calibration's searches), so
/// the phases add up to `total`, the summary's `wall_time_s`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Seconds {
    /// `fusemap demo`: the simulator (scans, images and pose sensors of the world),
    /// written as a rosbag2 bag as it runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulate: Option<f64>,
    /// The first pass over the log: the pose sensors read and the scans inventoried.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read: Option<f64>,
    /// The pose track from the pose sensors (the estimator's filter and smoother, or the
    /// odometry as it is): the track's seconds less SLAM's own (its run's report), so the
    /// bookkeeping around SLAM's result counts here.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<f64>,
    /// SLAM: scan matching, loop closure and the pose graph.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slam: Option<f64>,
    /// The second pass: the scans (and camera frames) read again and inserted into the
    /// maps; for a simulated world, its scans cast and inserted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map: Option<f64>,
    /// The primary map's rasters, pictures and files, up to `summary.json`.
    pub outputs: f64,
    /// What no phase above covers.
    pub other: f64,
    /// The whole run (`wall_time_s`).
    pub total: f64,
}

impl Seconds {
    /// The phases of a log's run as its report measured them: the first pass, the track
    /// (SLAM's share apart) and the second pass.
    pub fn of_log(report: &crate::report::LogReport) -> Self {
        let slam = report.slam.as_ref().map(|s| s.seconds);
        Self {
            read: Some(report.decode_s),
            estimator: Some((report.track_s - slam.unwrap_or(0.0)).max(0.0)),
            slam,
            map: Some(report.map_s),
            ..Self::default()
        }
    }

    /// Closes the account at `total` seconds, with `outputs` seconds of output: `other`
    /// is what the named phases leave.
    pub fn closed(mut self, outputs: f64, total: f64) -> Self {
        let named = [self.simulate, self.read, self.estimator, self.slam, self.map];
        let named: f64 = named.iter().flatten().sum::<f64>() + outputs;
        (self.outputs, self.total, self.other) = (outputs, total, (total - named).max(0.0));
        self
    }

    /// The phases as one line: `read 0.62, estimator 0.02, …, total 13.44`.
    fn line(&self) -> String {
        let named = [
            ("simulate", self.simulate),
            ("read", self.read),
            ("estimator", self.estimator),
            ("slam", self.slam),
            ("map", self.map),
            ("outputs", Some(self.outputs)),
            ("other", Some(self.other)),
        ];
        named.iter().filter_map(|(n, s)| Some(format!("{n} {:.2}", (*s)?))).collect::<Vec<_>>().join(", ")
    }
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
        writeln!(f, "wall time     {:.3} s ({})", self.wall_time_s, self.seconds.line())
    }
}

#[cfg(test)]
mod tests {
    use super::Seconds;

    #[test]
    fn the_phases_add_up_to_the_total() {
        let s =
            Seconds { read: Some(0.5), estimator: Some(0.25), map: Some(2.0), ..Seconds::default() }.closed(1.0, 4.0);
        assert_eq!((s.outputs, s.other, s.total), (1.0, 0.25, 4.0));
        assert_eq!(s.line(), "read 0.50, estimator 0.25, map 2.00, outputs 1.00, other 0.25");
        let json = serde_json::to_value(&s).unwrap();
        assert!(json.get("slam").is_none() && json.get("simulate").is_none(), "{json}");
        // Clock readings taken apart can overlap by a hair; `other` is never negative.
        assert_eq!(Seconds { map: Some(3.0), ..Seconds::default() }.closed(1.0, 3.9).other, 0.0);
    }
}
