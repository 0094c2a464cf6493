//! The Rauch–Tung–Striebel smoother (Rauch, Tung & Striebel, *Maximum likelihood
//! estimates of linear dynamic systems*, AIAA J. 1965; Särkkä, *Bayesian Filtering and
//! Smoothing*, §8.2 for the extended form): a backward pass over the filter's records
//! giving every state the information of the whole log. This is what an offline mapper has
//! over a filter: a fix after an RTK dropout also corrects the poses inside it.
//!
//! `C_k = P_k F_{k+1}ᵀ P̄_{k+1}⁻¹`,
//! `x̂_k = x_k + C_k (x̂_{k+1} − x̄_{k+1})`,
//! `P̂_k = P_k + C_k (P̂_{k+1} − P̄_{k+1}) C_kᵀ`.

use super::error::EstimatorError;
use super::filter::{StepRecord, N, THETA};
use super::linalg::{add, all_finite, mul, mul_vec, sandwich, spd_inverse, sub, transpose, Mat};
use super::output::StateSample;
use super::run::{RunCounts, RunOutput};
use crate::geometry::{normalize_angle, Pose2};
use crate::time::Stamp;
use std::ops::Range;

/// Steps whose records the smoother holds at once (688 bytes each: 45 MB, about 20 minutes
/// of 50 Hz odometry). A longer log is smoothed a segment of this many steps at a time,
/// from its end; see [`filter_and_smooth`].
pub(crate) const HELD_RECORDS: usize = 1 << 16;

/// The filter's and the smoother's samples of every step, in time order.
pub(crate) struct Track {
    pub filtered: Vec<StateSample>,
    pub smoothed: Vec<StateSample>,
    /// The filter's last state and covariance (what the log taught it: the gyro bias, the
    /// odometry scale); `None` without a step (never: the start is one).
    pub last: Option<([f64; N], Mat<N, N>)>,
    /// Per odometry interval: flagged as slipping.
    pub slip: Vec<bool>,
}

/// Runs the forward pass (`forward(keep, counts, whole)`: the filter over the log,
/// keeping the records of the steps in `keep`, to its end when `whole`, else up to the end
/// of `keep`) and the smoother over its records, holding at most `held` records at once.
///
/// The first pass runs whole, counts into `counts` and keeps the first `held` records. A
/// log of more steps is smoothed a segment at a time from its end, and the forward pass
/// runs again up to each segment, keeping that segment's records (and counting into a
/// scratch copy): the filter is deterministic, so they are the first
/// pass's records to the bit, and the samples are those of one pass holding them all.
/// Memory then grows with the log by a sample's 240 bytes a step instead of a record's
/// 688; time by a partial forward pass per segment (a whole one takes about 0.5 s an
/// hour of 50 Hz odometry), so quadratically in the log's length past `held` steps. This is checkpointing with
/// recomputation, as in Griewank & Walther's reverse-mode differentiation, with the start
/// of the log as the only checkpoint.
pub(crate) fn filter_and_smooth(
    forward: impl Fn(Range<usize>, &mut RunCounts, bool) -> Result<RunOutput, EstimatorError>,
    counts: &mut RunCounts,
    held: usize,
) -> Result<Track, EstimatorError> {
    let scratch = counts.clone();
    let held = held.max(1);
    let RunOutput { records: first, slip, steps } = forward(0..held, counts, true)?;
    let segments: Vec<Range<usize>> = (0..steps).step_by(held).map(|a| a..(a + held).min(steps)).collect();
    let (mut filtered, mut smoothed) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let mut last = None;
    // The first record of the segment after the current one, and its smoothed state.
    let mut after: Option<(StepRecord, [f64; N], Mat<N, N>)> = None;
    // The earliest step whose smoothed state is not finite.
    let mut bad = None;
    // Held through the whole backward pass only when it is the only segment; otherwise
    // the first segment is computed again at the end, so that one segment's records are
    // held at a time, not two (45 MB more at the default `held`).
    let mut first = (segments.len() == 1).then_some(first);
    for segment in segments.iter().rev() {
        let records = match first.take() {
            Some(records) => records,
            None => forward(segment.clone(), &mut scratch.clone(), false)?.records,
        };
        debug_assert_eq!(records.len(), segment.len());
        let Some(end) = records.last() else { continue };
        last.get_or_insert((end.x, end.p));
        let mut later = after.as_ref().map(|(r, x, p)| (r, *x, *p));
        for rec in records.iter().rev() {
            let (xs, ps) = match later {
                Some((next, xn, pn)) => rts_step(rec, next, &xn, &pn),
                None => (rec.x, rec.p),
            };
            if !xs.iter().all(|v| v.is_finite()) || !all_finite(&ps) {
                bad = Some(rec.stamp);
            }
            filtered.push(sample(rec.stamp, &rec.x, &rec.p));
            smoothed.push(sample(rec.stamp, &xs, &ps));
            later = Some((rec, xs, ps));
        }
        after = later.map(|(r, x, p)| (r.clone(), x, p));
    }
    // The smoother's gain (P Pₚ⁻¹) can overflow where a correction claimed a variance of
    // 10¹²² (found by fuzzing): an estimate never hands out a NaN pose.
    if let Some(stamp) = bad {
        return Err(EstimatorError::Numerical { stamp: stamp.0 });
    }
    filtered.reverse();
    smoothed.reverse();
    Ok(Track { filtered, smoothed, last, slip })
}

/// One backward step: the smoothed state of `rec` from the filter's record and the next
/// step's record and smoothed state.
fn rts_step(rec: &StepRecord, next: &StepRecord, xs_next: &[f64; N], ps_next: &Mat<N, N>) -> ([f64; N], Mat<N, N>) {
    let Some(pred_inv) = spd_inverse(&next.p_pred) else {
        // A singular prediction carries no information back: keep the filtered state.
        return (rec.x, rec.p);
    };
    let c = mul(&mul(&rec.p, &transpose(&next.f)), &pred_inv);
    let mut dx = [0.0; N];
    for i in 0..N {
        dx[i] = xs_next[i] - next.x_pred[i];
    }
    dx[THETA] = normalize_angle(dx[THETA]);
    let corr = mul_vec(&c, &dx);
    let mut xs = rec.x;
    for i in 0..N {
        xs[i] += corr[i];
    }
    xs[THETA] = normalize_angle(xs[THETA]);
    let ps = add(&rec.p, &sandwich(&c, &sub(ps_next, &next.p_pred)));
    (xs, ps)
}

/// Smoothed states and covariances, one per record (all records held).
#[cfg(test)]
pub(crate) fn smooth(records: &[StepRecord]) -> Vec<([f64; N], Mat<N, N>)> {
    let mut out: Vec<([f64; N], Mat<N, N>)> = Vec::with_capacity(records.len());
    for (k, rec) in records.iter().enumerate().rev() {
        let s = match out.last() {
            Some((xn, pn)) => rts_step(rec, &records[k + 1], xn, pn),
            None => (rec.x, rec.p),
        };
        out.push(s);
    }
    out.reverse();
    out
}

/// A step's state as a sample of the track.
fn sample(stamp: Stamp, x: &[f64; N], p: &Mat<N, N>) -> StateSample {
    let mut covariance = [[0.0; 3]; 3];
    for (i, row) in covariance.iter_mut().enumerate() {
        row.copy_from_slice(&p[i][..3]);
    }
    StateSample { stamp, pose: Pose2::new(x[0], x[1], x[2]), covariance, gyro_bias: x[3], odometry_scale: x[4] }
}
