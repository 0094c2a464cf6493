//! The Rauch–Tung–Striebel smoother (Rauch, Tung & Striebel, *Maximum likelihood
//! estimates of linear dynamic systems*, AIAA J. 1965; Särkkä, *Bayesian Filtering and
//! Smoothing*, §8.2 for the extended form): a backward pass over the filter's records
//! giving every state the information of the whole log. This is what an offline mapper has
//! over a filter: a fix after an RTK dropout also corrects the poses inside it.
//!
//! `C_k = P_k F_{k+1}ᵀ P̄_{k+1}⁻¹`,
//! `x̂_k = x_k + C_k (x̂_{k+1} − x̄_{k+1})`,
//! `P̂_k = P_k + C_k (P̂_{k+1} − P̄_{k+1}) C_kᵀ`.

use super::filter::{StepRecord, N, THETA};
use super::linalg::{add, mul, mul_vec, sandwich, spd_inverse, sub, transpose, Mat};
use crate::geometry::normalize_angle;

/// Smoothed states and covariances, one per record.
pub(crate) fn smooth(records: &[StepRecord]) -> Vec<([f64; N], Mat<N, N>)> {
    let n = records.len();
    let mut out = vec![([0.0; N], [[0.0; N]; N]); n];
    let Some(last) = records.last() else {
        return out;
    };
    out[n - 1] = (last.x, last.p);
    for k in (0..n - 1).rev() {
        let (rec, next) = (&records[k], &records[k + 1]);
        let Some(pred_inv) = spd_inverse(&next.p_pred) else {
            // A singular prediction carries no information back: keep the filtered state.
            out[k] = (rec.x, rec.p);
            continue;
        };
        let c = mul(&mul(&rec.p, &transpose(&next.f)), &pred_inv);
        let (xs_next, ps_next) = &out[k + 1];
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
        out[k] = (xs, ps);
    }
    out
}
