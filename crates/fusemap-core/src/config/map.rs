//! `[map]`: the grid's placement and probabilities, and their validation.

use super::{err, finite, probability, FieldError};
use crate::geometry::Point2;
use crate::grid::{GridGeometry, OccupancyParams, PassThroughParams};
use serde::{Deserialize, Serialize};

/// The map's geometry and probabilities.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapConfig {
    /// Cell side, metres.
    pub resolution: f64,
    /// Lower-left corner of cell (0, 0), metres; `None` puts cell centres on multiples of
    /// the resolution.
    pub origin: Option<[f64; 2]>,
    /// Prior occupancy probability of an unobserved cell.
    pub prior: f64,
    /// Lower clamp on a cell's probability.
    pub clamp_min: f64,
    /// Upper clamp on a cell's probability.
    pub clamp_max: f64,
    /// A cell is occupied above this probability.
    pub occupied_threshold: f64,
    /// A cell is free below this probability.
    pub free_threshold: f64,
    /// Free evidence behind confidently occupied cells (`[map.pass_through]`).
    #[serde(default)]
    pub pass_through: PassThroughParams,
}

impl Default for MapConfig {
    fn default() -> Self {
        let p = OccupancyParams::default();
        Self {
            resolution: 0.05,
            origin: None,
            prior: p.prior,
            clamp_min: p.clamp_min,
            clamp_max: p.clamp_max,
            occupied_threshold: p.occupied_threshold,
            free_threshold: p.free_threshold,
            // The configured map handles the lidar's pass-throughs; the core type's
            // default is the plain model.
            pass_through: PassThroughParams::default(),
        }
    }
}

impl MapConfig {
    /// The grid's geometry and probabilities; the error names the first bad field.
    pub(super) fn validate(&self) -> Result<(GridGeometry, OccupancyParams), FieldError> {
        let res = finite("map.resolution", self.resolution)?;
        if res <= 0.0 {
            return Err(err("map.resolution", format!("must be > 0 metres, got {res}")));
        }
        let geometry = match self.origin {
            Some([x, y]) => {
                finite("map.origin", x)?;
                finite("map.origin", y)?;
                // Beyond 10⁹ m an f64 no longer resolves a position to 10⁻⁷ m, and the cell
                // of a point near the origin is rounded (at 10¹⁵ a quarter of the updates
                // went to the wrong cell); no pose a robot has is that far out either.
                let max = crate::geometry::MAX_POSITION_M;
                if x.abs() > max || y.abs() > max {
                    return Err(err("map.origin", format!("must be within ±{max:e} m, got [{x}, {y}]")));
                }
                GridGeometry::new(res, Point2::new(x, y))
            }
            None => GridGeometry::centered(res),
        }
        .map_err(|e| err("map", e.to_string()))?;
        Ok((geometry, self.occupancy()?))
    }

    /// The probabilities: prior inside the clamps, thresholds ordered, the pass-through
    /// rule above the prior.
    fn occupancy(&self) -> Result<OccupancyParams, FieldError> {
        let prior = probability("map.prior", self.prior)?;
        let cmin = probability("map.clamp_min", self.clamp_min)?;
        let cmax = probability("map.clamp_max", self.clamp_max)?;
        if !(cmin < prior && prior < cmax) {
            return Err(err("map", format!("need clamp_min < prior < clamp_max, got {cmin} / {prior} / {cmax}")));
        }
        let occ_t = probability("map.occupied_threshold", self.occupied_threshold)?;
        let free_t = probability("map.free_threshold", self.free_threshold)?;
        if free_t >= occ_t {
            return Err(err("map.free_threshold", format!("must be below occupied_threshold ({occ_t}), got {free_t}")));
        }
        let pt = self.pass_through;
        probability("map.pass_through.threshold", pt.threshold)?;
        if pt.threshold <= prior {
            return Err(err(
                "map.pass_through.threshold",
                format!("must be above the prior {prior}, got {}", pt.threshold),
            ));
        }
        if !(0.0..=1.0).contains(&finite("map.pass_through.weight", pt.weight)?) {
            return Err(err("map.pass_through.weight", format!("must be within [0, 1], got {}", pt.weight)));
        }
        if pt.margin_cells > 10_000 {
            return Err(err(
                "map.pass_through.margin_cells",
                format!("must be at most 10000, got {}", pt.margin_cells),
            ));
        }
        Ok(OccupancyParams {
            prior,
            clamp_min: cmin,
            clamp_max: cmax,
            occupied_threshold: occ_t,
            free_threshold: free_t,
            pass_through: pt,
        })
    }
}
