//! `[validate]`: the design document's validation (§5) as `fusemap validate` runs it — how
//! much of the log is held out, and the thresholds of the verdict
//! ([`crate::metrics::judge`]).

use super::{err, finite, FieldError};
use serde::{Deserialize, Serialize};

/// The `[validate]` table.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ValidateConfig {
    /// The share of the log's time span, at its end, held out of the maps and projected
    /// onto them for the hit rates (§5.2's "later period").
    pub holdout_share: f64,
    /// The least drop in mean entropy, best single-sensor map to the fused map, that counts
    /// as help, nats (§5.2's rule of thumb: 0.05 indoors at 0.05 m, prior 0.5).
    pub min_gain_nats: f64,
    /// The least drop of a sensor's hit rate, its own map to the fused map, as a share of
    /// its own-map rate, that counts as a disagreement with the other sensors.
    pub hit_rate_drop: f64,
    /// The fewest held-out endpoints of a sensor for its hit rates to be judged.
    pub min_endpoints: u64,
}

impl Default for ValidateConfig {
    fn default() -> Self {
        Self { holdout_share: 0.3, min_gain_nats: 0.05, hit_rate_drop: 0.1, min_endpoints: 200 }
    }
}

impl ValidateConfig {
    /// Checks the numbers; the verdict's thresholds, with `mount_yaw_deg` the tolerance of
    /// a lidar's direction of travel against the pose sensors' (`log.extrinsics_tolerance_deg`).
    pub fn validate(&self, mount_yaw_deg: f64) -> Result<Thresholds, FieldError> {
        let share = finite("validate.holdout_share", self.holdout_share)?;
        if !(share > 0.0 && share < 1.0) {
            return Err(err("validate.holdout_share", format!("must be strictly between 0 and 1, got {share}")));
        }
        let gain = finite("validate.min_gain_nats", self.min_gain_nats)?;
        if !(0.0..=std::f64::consts::LN_2).contains(&gain) {
            return Err(err("validate.min_gain_nats", format!("must be within 0..=ln 2 nats, got {gain}")));
        }
        let drop = finite("validate.hit_rate_drop", self.hit_rate_drop)?;
        if !(drop > 0.0 && drop <= 1.0) {
            return Err(err("validate.hit_rate_drop", format!("must be within (0, 1], got {drop}")));
        }
        Ok(Thresholds { min_gain_nats: gain, hit_rate_drop: drop, min_endpoints: self.min_endpoints, mount_yaw_deg })
    }
}

/// The thresholds of the verdict.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Thresholds {
    /// The least entropy gain that counts as help, nats.
    pub min_gain_nats: f64,
    /// The least drop of a sensor's hit rate, own map to M3, as a share of its own-map
    /// rate, that counts as a disagreement (below it: noise of the later period).
    pub hit_rate_drop: f64,
    /// The fewest held-out endpoints of a sensor for its hit rates to count.
    pub min_endpoints: u64,
    /// The largest disagreement of a lidar's direction of travel with the pose sensors'
    /// that is not a fault, degrees (`log.extrinsics_tolerance_deg`).
    pub mount_yaw_deg: f64,
}
