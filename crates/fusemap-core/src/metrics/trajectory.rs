//! Trajectory accuracy against a reference trajectory sampled at the same scans: the
//! relation metric of Kümmerle et al. 2009 with relations chosen automatically (by scan
//! index, not by stamp), and the absolute trajectory error after a rigid alignment.
//!
//! The SLAM benchmark's relations were picked by hand; a test bench built from corrected
//! logs needs them picked by rule, in two sets that answer different questions:
//!
//! - **local** relations join consecutive scans: does the track follow the motion?
//! - **revisit** relations join a scan to an earlier one at the same place, reached again
//!   after a long detour: did SLAM close the loop? Without a loop closure their error is
//!   the drift accumulated over the detour.
//!
//! Indices, not stamps: some logs print every stamp as the same number (`%g`), and the
//! scans must still be told apart.

use super::relations::{score_errors, RelationScore};
use crate::geometry::Pose2;

/// A reference motion between scans `i` and `j` of a trajectory (`x_i⁻¹ ∘ x_j`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexRelation {
    /// The first scan (the frame the motion is expressed in).
    pub i: usize,
    /// The second scan.
    pub j: usize,
    /// The reference motion δ*.
    pub motion: Pose2,
}

/// When two scans count as a revisit of one place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RevisitRule {
    /// The two scans lie at most this far apart in the reference, metres.
    pub max_distance_m: f64,
    /// … and at least this far apart in time, seconds (when the stamps tell scans apart),
    pub min_interval_s: f64,
    /// … or at least this far apart along the path, metres (when they do not).
    pub min_path_m: f64,
}

impl Default for RevisitRule {
    /// 5 m, 60 s or 30 m of path: far enough apart that odometry alone has drifted, near
    /// enough that the two scans see the same walls.
    fn default() -> Self {
        Self { max_distance_m: 5.0, min_interval_s: 60.0, min_path_m: 30.0 }
    }
}

/// The motion between every pair of consecutive scans of `truth`.
pub fn consecutive_relations(truth: &[Pose2]) -> Vec<IndexRelation> {
    truth
        .windows(2)
        .enumerate()
        .map(|(i, w)| IndexRelation { i, j: i + 1, motion: w[0].inverse().compose(w[1]).normalized() })
        .collect()
}

/// For every scan of `truth`, a revisit relation to the nearest earlier scan that `rule`
/// calls the same place (none when there is no such scan). `seconds`: each scan's time
/// when the stamps tell the scans apart (strictly increasing), else `None` and the rule's
/// path length is used. At most one relation per scan, so a long stay at one place does
/// not outweigh the rest.
pub fn revisit_relations(truth: &[Pose2], seconds: Option<&[f64]>, rule: &RevisitRule) -> Vec<IndexRelation> {
    let mut path = Vec::with_capacity(truth.len());
    let mut along = 0.0;
    for (k, p) in truth.iter().enumerate() {
        if k > 0 {
            along += p.translation().distance(truth[k - 1].translation());
        }
        path.push(along);
    }
    let far_apart = |i: usize, j: usize| match seconds {
        Some(t) => t[j] - t[i] >= rule.min_interval_s,
        None => path[j] - path[i] >= rule.min_path_m,
    };
    let r2 = rule.max_distance_m * rule.max_distance_m;
    let mut out = Vec::new();
    for j in 0..truth.len() {
        let best = (0..j)
            .filter(|&i| far_apart(i, j))
            .map(|i| {
                let (dx, dy) = (truth[j].x - truth[i].x, truth[j].y - truth[i].y);
                (dx * dx + dy * dy, i)
            })
            .filter(|(d2, _)| *d2 <= r2)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, i)) = best {
            out.push(IndexRelation { i, j, motion: truth[i].inverse().compose(truth[j]).normalized() });
        }
    }
    out
}

/// `estimate` scored against `relations` (see [`RelationScore`]); a relation naming a scan
/// beyond `estimate` or with a non-finite pose is unmatched.
pub fn score_index_relations(relations: &[IndexRelation], estimate: &[Pose2]) -> RelationScore {
    let errors: Vec<Pose2> = relations
        .iter()
        .filter_map(|r| {
            let (a, b) = (estimate.get(r.i)?, estimate.get(r.j)?);
            (a.is_finite() && b.is_finite()).then(|| r.motion.inverse().compose(a.inverse().compose(*b)))
        })
        .collect();
    score_errors(relations.len(), &errors)
}

/// The absolute trajectory error: the RMS distance between `estimate` and `truth` (the
/// same scans, in the same order) after the rigid motion that best aligns the first onto
/// the second in least squares (the planar case of Umeyama 1991, without scale). NaN when
/// the two differ in length or are empty.
pub fn absolute_trajectory_error(estimate: &[Pose2], truth: &[Pose2]) -> f64 {
    if estimate.len() != truth.len() || estimate.is_empty() {
        return f64::NAN;
    }
    let n = estimate.len() as f64;
    let mean = |v: &[Pose2]| {
        let (sx, sy) = v.iter().fold((0.0, 0.0), |(a, b), p| (a + p.x, b + p.y));
        (sx / n, sy / n)
    };
    let ((ex, ey), (tx, ty)) = (mean(estimate), mean(truth));
    // The rotation maximising Σ ⟨R e_k, t_k⟩ over centred points: atan2 of the summed
    // cross and dot products.
    let (mut dot, mut cross) = (0.0, 0.0);
    for (e, t) in estimate.iter().zip(truth) {
        let (ax, ay, bx, by) = (e.x - ex, e.y - ey, t.x - tx, t.y - ty);
        dot += ax * bx + ay * by;
        cross += ax * by - ay * bx;
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    let sum: f64 = estimate
        .iter()
        .zip(truth)
        .map(|(e, t)| {
            let (ax, ay) = (e.x - ex, e.y - ey);
            let (rx, ry) = (c * ax - s * ay, s * ax + c * ay);
            (rx - (t.x - tx)).powi(2) + (ry - (t.y - ty)).powi(2)
        })
        .sum();
    (sum / n).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn square_loop(laps: usize) -> Vec<Pose2> {
        // 10 m squares, a scan every metre.
        let mut v = Vec::new();
        for _ in 0..laps {
            for side in 0..4 {
                for k in 0..10 {
                    let th = side as f64 * std::f64::consts::FRAC_PI_2;
                    let (x0, y0) = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)][side];
                    v.push(Pose2::new(x0 + k as f64 * th.cos(), y0 + k as f64 * th.sin(), th));
                }
            }
        }
        v
    }

    #[test]
    fn revisits_need_distance_in_space_and_apart_in_path_or_time() {
        let truth = square_loop(2);
        let rule = RevisitRule::default();
        let r = revisit_relations(&truth, None, &rule);
        // The second lap revisits the first; 30 m of path rules out most of lap one.
        assert!(r.iter().all(|r| r.j >= 30 && r.j > r.i));
        assert!(r.iter().all(|r| truth[r.i].translation().distance(truth[r.j].translation()) <= 5.0));
        let lap2 = r.iter().filter(|r| r.j >= 40).count();
        assert_eq!(lap2, 40, "every scan of lap two finds its twin");
        assert!(r.iter().filter(|r| r.j >= 40).all(|r| r.i == r.j - 40));
        // With times one second a scan, 60 s apart rules out everything before scan 60.
        let t: Vec<f64> = (0..truth.len()).map(|k| k as f64).collect();
        let r = revisit_relations(&truth, Some(&t), &rule);
        assert!(r.iter().all(|r| r.j - r.i >= 60));
        assert!(!r.is_empty());
    }

    #[test]
    fn a_drifted_trajectory_fails_the_revisits_not_the_local_relations() {
        let truth = square_loop(2);
        // A heading error of 0.5° per scan, integrated.
        let mut est = vec![truth[0]];
        for w in truth.windows(2) {
            let d = w[0].inverse().compose(w[1]);
            let last = *est.last().unwrap();
            est.push(last.compose(Pose2::new(d.x, d.y, d.theta + 0.5f64.to_radians())));
        }
        let local = score_index_relations(&consecutive_relations(&truth), &est);
        let revisit = score_index_relations(&revisit_relations(&truth, None, &RevisitRule::default()), &est);
        assert!(local.translation_mean_m < 0.01, "{local:?}");
        assert!(revisit.translation_mean_m > 1.0, "{revisit:?}");
        assert!(score_index_relations(&consecutive_relations(&truth), &truth).translation_max_m < 1e-12);
        // Too short an estimate leaves relations unmatched, never silently dropped.
        let short = score_index_relations(&consecutive_relations(&truth), &est[..10]);
        assert_eq!((short.scored, short.unmatched), (9, truth.len() - 10));
    }

    proptest! {
        #[test]
        fn ate_ignores_a_rigid_motion_and_sees_noise(x in -50.0..50.0f64, y in -50.0..50.0f64, th in -3.1..3.1f64, e in 0.0..0.5f64) {
            let truth = square_loop(1);
            let g = Pose2::new(x, y, th);
            let moved: Vec<Pose2> = truth.iter().map(|p| g.compose(*p)).collect();
            prop_assert!(absolute_trajectory_error(&moved, &truth) < 1e-9);
            // Alternate ±e along x in the truth's frame: RMS after alignment at most e.
            let noisy: Vec<Pose2> = moved
                .iter()
                .enumerate()
                .map(|(k, p)| p.compose(Pose2::new(if k % 2 == 0 { e } else { -e }, 0.0, 0.0)))
                .collect();
            let ate = absolute_trajectory_error(&noisy, &truth);
            prop_assert!(ate <= e + 1e-9 && ate >= 0.5 * e - 1e-9, "{ate} {e}");
        }
    }
}
