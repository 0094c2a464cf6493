//! The semantic layer: per cell, a distribution over the configured classes.
//!
//! Each cell holds Dirichlet evidence counts `n_c`, one per class. With a symmetric
//! Dirichlet prior `α` over the classes that are not ignored, the posterior predictive
//! probability of class `c` is `(α + n_c) / Σ_j (α + n_j)` (the Dirichlet–categorical
//! conjugate update; Murphy, *Machine Learning: a Probabilistic Perspective*, §3.4). A
//! camera frame adds to a cell the mean weight of its pixels there (depth, class rate,
//! agreement of label and geometry; at most one unit while class weights are at most 1),
//! split over the classes they report: many pixels of one frame landing in one cell are
//! one look, not many (the design document's "do not count correlated evidence twice",
//! §2.4).
//!
//! Counts are never decayed: the static semantic layer takes only static classes; moving
//! objects go to the dynamic layer.

/// The prior pseudo-count of each class (Jeffreys' prior for a categorical: ½).
pub const DIRICHLET_PRIOR: f32 = 0.5;

/// The posterior class distribution of a cell with counts `counts`, written to `out`;
/// classes with `eligible[c] == false` (ignored classes) get probability 0. Returns the
/// most likely class and its probability, `None` when the cell has no evidence.
pub fn distribution(counts: &[f32], eligible: &[bool], out: &mut [f32]) -> Option<(usize, f32)> {
    let total: f32 = counts.iter().zip(eligible).filter(|(_, &e)| e).map(|(n, _)| n).sum();
    if total <= 0.0 {
        out.iter_mut().for_each(|o| *o = 0.0);
        return None;
    }
    let k = eligible.iter().filter(|&&e| e).count() as f32;
    let norm = total + DIRICHLET_PRIOR * k;
    let mut best: Option<(usize, f32)> = None;
    for (c, ((o, n), e)) in out.iter_mut().zip(counts).zip(eligible).enumerate() {
        *o = if *e { (n + DIRICHLET_PRIOR) / norm } else { 0.0 };
        if *e && best.is_none_or(|(_, p)| *o > p) {
            best = Some((c, *o));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_posterior_sums_to_one_and_follows_the_counts() {
        let eligible = [false, true, true, true];
        let mut out = [0.0; 4];
        assert_eq!(distribution(&[0.0; 4], &eligible, &mut out), None);
        let (best, p) = distribution(&[5.0, 3.0, 1.0, 0.0], &eligible, &mut out).unwrap();
        assert_eq!(best, 1);
        assert!((out.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert_eq!(out[0], 0.0);
        assert!((p - 3.5 / 5.5).abs() < 1e-6);
        // More evidence, more confidence in the same class.
        let (_, p2) = distribution(&[0.0, 30.0, 10.0, 0.0], &eligible, &mut out).unwrap();
        assert!(p2 > 0.7 && p2 > p - 0.1);
    }
}
