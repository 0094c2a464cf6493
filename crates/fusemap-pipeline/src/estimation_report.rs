//! What the estimation stage reports (`summary.json`'s `log.estimator`): a leaf of the
//! pipeline, so the pose track and the run report can carry it without importing the
//! stage itself.

use fusemap_core::estimator::EstimatorReport;
use serde::Serialize;

/// What the pipeline did with the GNSS fixes before the estimator saw them.
#[derive(Debug, Default, Clone, Serialize)]
pub struct GnssInputReport {
    /// The topic.
    pub topic: String,
    /// Fixes read.
    pub read: u64,
    /// Given to the estimator.
    pub passed: u64,
    /// `STATUS_NO_FIX`: ignored.
    pub no_fix: u64,
    /// NaN or infinite latitude, longitude or altitude.
    pub not_finite: u64,
    /// Latitude beyond ±90°, longitude beyond ±180° or altitude outside the sensor's
    /// `altitude_range_m`: receiver faults, dropped.
    pub out_of_range: u64,
    /// A status or covariance type `NavSatFix` does not define: dropped.
    pub invalid_field: u64,
    /// Early fixes that the fixes after them contradicted (far from the datum's fix):
    /// dropped.
    pub contradicted: u64,
    /// The datum `[lat°, lon°, alt m]` of the map frame (ENU at it).
    pub datum: Option<[f64; 3]>,
    /// `config`, `first good fix` or `first consistent fix` (the first the next two
    /// agree with).
    pub datum_source: String,
    /// Fixes whose σ was raised to the floor of their status.
    pub floored: u64,
    /// Fixes with covariance type UNKNOWN (given the configured σ).
    pub unknown_covariance: u64,
    /// The antenna's lever arm `base_from_antenna` (x, y), metres, and where it came from.
    pub lever_arm: Option<[f64; 2]>,
}

/// What the estimation stage did: the estimator's own report, what became of the GNSS
/// fixes before it saw them, and how many inputs it was given (`summary.json`'s
/// `log.estimator`).
#[derive(Clone, Debug, Serialize)]
pub struct EstimationReport {
    /// The estimator's counters and what it learnt.
    pub estimator: EstimatorReport,
    /// Per GNSS topic, the fixes passed, floored or refused.
    pub gnss_input: Vec<GnssInputReport>,
    /// Inputs given to the estimator.
    pub inputs: usize,
}
