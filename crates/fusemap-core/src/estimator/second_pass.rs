//! A second look at the fixes with hindsight: the offline advantage over a filter.
//!
//! A forward filter gates each fix against its prediction. Where the prediction is
//! uncertain (after a dropout, through a stretch of wheel slip) an outlier of a few metres
//! can pass that gate and pull the track. The smoothed track knows the whole log: each
//! accepted fix is tested again against it, with the same χ² gate and the innovation
//! covariance `H P_s Hᵀ + R` of the smoothed state (conservative: the fix's own
//! information is still inside `P_s`, which only lowers the NIS). Fixes that fail are
//! removed and the filter and smoother run once more — the robust re-weighting an offline
//! batch estimator does (cf. the iterative outlier removal of bundle adjustment), limited
//! to one extra pass so the cost stays bounded. The removed fixes are reported with the
//! reason `smoothed_gate` and their NIS.

use super::chi2::chi_square_quantile;
use super::linalg::spd_inverse;
use super::models;
use super::output::Estimate;
use super::{EstimatorInput, FixRejection, RejectedFix};
use crate::time::Stamp;
use std::collections::HashSet;

/// The accepted fixes of `first` that fail the gate against its smoothed track: their index
/// in `inputs`, stamp and NIS.
pub(crate) fn flagged_fixes(
    inputs: &[EstimatorInput],
    first: &Estimate,
    gate_probability: f64,
) -> Vec<(usize, Stamp, f64)> {
    let Some(gate) = chi_square_quantile(2, gate_probability) else { return Vec::new() };
    let rejected: HashSet<Stamp> = first.report.rejected_fixes.iter().map(|r| r.stamp).collect();
    let mut out = Vec::new();
    for (index, i) in inputs.iter().enumerate() {
        let &EstimatorInput::Position { stamp, enu, ref covariance, antenna, .. } = i else { continue };
        if rejected.contains(&stamp) {
            continue;
        }
        let Ok((pose, p)) = first.pose_at(stamp) else { continue };
        let x = [pose.x, pose.y, pose.theta, 0.0, 1.0];
        let (nu, h) = models::position(&x, enu, antenna);
        // S = H P Hᵀ + R over the pose block.
        let mut s = **covariance;
        for (r, s_row) in s.iter_mut().enumerate() {
            for (c, v) in s_row.iter_mut().enumerate() {
                for a in 0..3 {
                    for b in 0..3 {
                        *v += h[r][a] * p[a][b] * h[c][b];
                    }
                }
            }
        }
        let Some(si) = spd_inverse(&s) else { continue };
        let nis = (0..2).map(|a| (0..2).map(|b| nu[a] * si[a][b] * nu[b]).sum::<f64>()).sum::<f64>();
        if nis > gate {
            out.push((index, stamp, nis));
        }
    }
    out
}

/// Runs the estimator, then once more without the fixes its smoothed track rejects.
pub(crate) fn estimate_with_hindsight(
    inputs: &[EstimatorInput],
    cfg: &super::EstimatorConfig,
) -> Result<Estimate, super::EstimatorError> {
    let first = super::estimate_once(inputs, &HashSet::new(), cfg)?;
    if !cfg.smoothed_fix_gate {
        return Ok(first);
    }
    let flagged = flagged_fixes(inputs, &first, cfg.gate_probability);
    if flagged.is_empty() {
        return Ok(first);
    }
    // The first estimate is not needed any more: free it before the second is built.
    drop(first);
    let drop: HashSet<usize> = flagged.iter().map(|f| f.0).collect();
    let mut second = super::estimate_once(inputs, &drop, cfg)?;
    let r = &mut second.report;
    r.fixes.received += flagged.len();
    r.fixes.rejected_smoothed_gate += flagged.len();
    for &(index, stamp, nis) in &flagged {
        if let EstimatorInput::Position { quality, .. } = inputs[index] {
            if let Some(q) = r.fixes_by_quality.iter_mut().find(|q| q.quality == quality) {
                q.received += 1;
            }
        }
        r.rejected_fixes.push(RejectedFix { stamp, reason: FixRejection::SmoothedGate, nis });
    }
    r.rejected_fixes.sort_by_key(|f| f.stamp);
    Ok(second)
}
