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
use super::run::{Pass, RunCounts, RunOutput};
use crate::geometry::{normalize_angle, Pose2};
use crate::time::Stamp;
use std::ops::Range;

/// Steps whose records the smoother holds at once (688 bytes each: 5.6 MB, about 2.7
/// minutes of 50 Hz odometry). A longer log is smoothed a segment of this many steps at a
/// time, from its end; see [`filter_and_smooth`].
pub(crate) const HELD_RECORDS: usize = 1 << 13;

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

/// Runs the forward pass (`forward(pass, counts)`: the filter over the log, see
/// [`Pass`]) and the smoother over its records, holding at most `held` records at once.
///
/// The first pass runs whole, counts into `counts`, keeps the first `held` records and a
/// checkpoint of the filter's state before every further `held` steps. A log of more steps
/// is smoothed a segment at a time from its end: the forward pass runs again from the
/// checkpoint before each segment to its end, keeping that segment's records (and
/// counting into a scratch copy). The filter is deterministic and a checkpoint holds all
/// of its state, so they are the first pass's records to the bit, and the samples are
/// those of one pass holding them all. Memory then grows with the log by a sample's 240
/// bytes a step instead of a record's 688, and time by a second forward pass. This is
/// checkpointing with recomputation, as in Griewank & Walther's reverse-mode
/// differentiation, with a checkpoint per segment.
pub(crate) fn filter_and_smooth(
    forward: impl Fn(Pass, &mut RunCounts) -> Result<RunOutput, EstimatorError>,
    counts: &mut RunCounts,
    held: usize,
) -> Result<Track, EstimatorError> {
    let scratch = counts.clone();
    let held = held.max(1);
    let pass = Pass { keep: 0..held, whole: true, resume: None, checkpoint_every: held };
    let RunOutput { records: first, slip, steps, checkpoints } = forward(pass, counts)?;
    let segments: Vec<Range<usize>> = (0..steps).step_by(held).map(|a| a..(a + held).min(steps)).collect();
    let (mut filtered, mut smoothed) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let mut last = None;
    // The first record of the segment after the current one, and its smoothed state.
    let mut after: Option<(StepRecord, [f64; N], Mat<N, N>)> = None;
    // The earliest step whose smoothed state is not finite.
    let mut bad = None;
    // Held through the whole backward pass only when it is the only segment; otherwise
    // the first segment is computed again at the end, so that one segment's records are
    // held at a time, not two.
    let mut first = (segments.len() == 1).then_some(first);
    for (k, segment) in segments.iter().enumerate().rev() {
        let records = match first.take() {
            Some(records) => records,
            None => {
                let resume = k.checked_sub(1).and_then(|c| checkpoints.get(c));
                let pass = Pass { keep: segment.clone(), whole: false, resume, checkpoint_every: 0 };
                forward(pass, &mut scratch.clone())?.records
            }
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
