//! What a SLAM run did, for the run report.

use super::pose_graph::OptimizeReport;
use serde::Serialize;

/// Counts and timings of a SLAM run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SlamReport {
    /// Scans given.
    pub scans: u64,
    /// Scans matched against a submap.
    pub matched: u64,
    /// Scans whose match was degenerate (refined again from the prediction, pulled to it ten times harder).
    pub degenerate: u64,
    /// Scans not matched (too few returns, or no submap yet): predicted pose kept.
    pub predicted: u64,
    /// Scans inside a gap of the pose track (matched from the previous scan's pose).
    pub without_track: u64,
    /// Scans refused (a non-finite track pose; a sensor origin not finite or farther from
    /// the base than `max_range_m`).
    pub refused: u64,
    /// Graph edges (match, odometry, loop closure) left out because their measurement or
    /// information was not finite (a match far out, found by fuzzing).
    pub edges_refused: u64,
    /// Scans whose track moved faster than a robot can since the previous scan (an
    /// odometry reset, a teleported pose): matched from the previous scan's pose instead,
    /// as in a gap of the track.
    pub track_jumps: u64,
    /// Scans also matched from the constant-velocity prediction, because it lay outside
    /// half the search window of the track's prediction.
    pub moving_prediction_searched: u64,
    /// Scans matched from the constant-velocity prediction because it matched better than
    /// the track's (stalled or jumping odometry).
    pub moving_prediction_used: u64,
    /// Scans whose match scored far below the recent matches', searched again in the wide
    /// window (`[slam] rescue_*`).
    pub rescue_searched: u64,
    /// … and taken from that wider search, clearly better.
    pub rescued: u64,
    /// Scans whose track reading repeated the previous scan's bit for bit (a held reading:
    /// no motion information, not made a node).
    pub held_readings: u64,
    /// Matched scans the track's motion was judged by (`odometry.rs`).
    pub odometry_samples: u64,
    /// What they made of the odometry model's σ at the end: the factors of its
    /// translation and rotation (below 1: the track was better than the model).
    pub odometry_scale: [f64; 2],
    /// Odometry edges left out: the odometry disagreed with the matched motion by > 5 σ.
    pub odometry_edges_rejected: u64,
    /// GNSS fixes given.
    pub fixes: u64,
    /// Fixes made position priors on nodes.
    pub fix_priors: u64,
    /// Fixes left out: too far from the pose track for both covariances (χ², 99.9 %).
    pub fixes_gated: u64,
    /// Fixes left out: no node with a track pose within `fix_max_offset_s`, no track pose at
    /// the fix, a covariance that is not positive definite, or a graph not in the fixes'
    /// frame (its first node had no track pose).
    pub fixes_unplaced: u64,
    /// Pose-graph nodes (scans that moved far enough).
    pub nodes: u64,
    /// Submaps built.
    pub submaps: usize,
    /// Loop-closure searches run.
    pub loop_searches: u64,
    /// Loop closures accepted.
    pub loop_accepted: u64,
    /// Travel of the trajectory's nodes, metres.
    pub travel_m: f64,
    /// The longest loop closed: the travel between the node of an accepted closure and
    /// the nearest scan of its submap, metres. A log that never comes back to a place closes
    /// only short ones (a submap seen again from a few metres on).
    pub longest_loop_m: f64,
    /// Loop-closure searches that added no edge: nothing above the score threshold, only a
    /// degenerate match, a large correction no later node confirmed, or a confirming search
    /// that disagreed.
    pub loop_rejected: u64,
    /// … of which degenerate: a match that fits anywhere along one direction (a corridor).
    pub loop_degenerate: u64,
    /// … of which large corrections no later node confirmed.
    pub loop_unconfirmed: u64,
    /// … of which confirming searches that found nothing where the hypothesis put the node.
    pub loop_disagreeing: u64,
    /// Large corrections (a widened window or the global search) held as hypotheses.
    pub loop_hypotheses: u64,
    /// … confirmed by a second, agreeing match (both become edges).
    pub loop_confirmed: u64,
    /// … of which found by the global search.
    pub loop_global_accepted: u64,
    /// Searches left out because a batch was over its budget.
    pub loop_over_budget: u64,
    /// Branch-and-bound grids built for finished submaps (first builds and rebuilds after
    /// the memory budget dropped them).
    pub grids_built: u64,
    /// The most bytes of branch-and-bound grids (and their unpacked fields) held at once.
    pub grids_peak_bytes: usize,
    /// The most bytes the submaps' grids held at once.
    pub submap_peak_bytes: usize,
    /// Pose-graph optimisations run.
    pub optimisations: u64,
    /// … of which taken some nodes after they started (run beside the matching when the
    /// pool has more than one thread).
    pub optimisations_deferred: u64,
    /// Optimisations that failed (the previous poses were kept), with the reason.
    pub optimisation_failures: Vec<String>,
    /// The last optimisation.
    pub last_optimisation: Option<OptimizeReport>,
    /// Wall time in local matching, seconds.
    pub matching_s: f64,
    /// Wall time in loop-closure search (precomputation included), seconds.
    pub loop_search_s: f64,
    /// Time the optimiser ran, seconds (periodic optimisations run beside the matching, so
    /// this is not all waited for).
    pub optimisation_s: f64,
    /// Wall time the scans waited for optimisations (taking their results included), seconds.
    pub optimisation_wait_s: f64,
}

/// A share of the scans above which degenerate matches are worth a finding.
const DEGENERATE_SHARE: f64 = 0.2;
/// A share of the scans above which unmatched ones are worth a finding.
const PREDICTED_SHARE: f64 = 0.05;

impl SlamReport {
    /// What a user should know about this run, in plain words: why no loop closed, that
    /// a corridor left the odometry in charge along it, scans that were not matched,
    /// searches the budget left out, failed optimisations. Empty when nothing stands out.
    ///
    /// `loop_closure`: whether loop closure ran (`[slam] loop_closure`); `loop_m`: the
    /// travel that makes a closure a loop (`[slam] loop_closure_global_after_m`); closures
    /// over less only tie neighbouring submaps. A run shorter than that is not told it
    /// closed no loop.
    pub fn findings(&self, loop_closure: bool, loop_m: f64) -> Vec<String> {
        let mut out = Vec::new();
        let share = |n: u64| n as f64 / self.scans.max(1) as f64;
        if loop_closure && self.travel_m > loop_m && self.longest_loop_m < loop_m {
            let other = self.loop_rejected.saturating_sub(self.loop_unconfirmed + self.loop_disagreeing);
            out.push(format!(
                "no loop closed (none over {loop_m:.0} m of travel; the longest {:.1} m): {} searches, {} accepted, {} below the score threshold or degenerate ({} degenerate), {} large corrections no later scan confirmed. If the robot did come back to a place, summary.json's open_loops give each search's best score; if it never did, the trajectory keeps the drift of scan matching",
                self.longest_loop_m,
                self.loop_searches,
                self.loop_accepted,
                other,
                self.loop_degenerate,
                self.loop_unconfirmed
            ));
        }
        if share(self.degenerate) > DEGENERATE_SHARE {
            out.push(format!(
                "{:.0} % of the scans matched only across a corridor (degenerate matches): along it the pose track's odometry decides the distance",
                100.0 * share(self.degenerate)
            ));
        }
        if share(self.predicted) > PREDICTED_SHARE {
            out.push(format!(
                "{} scans were not matched (too few returns, or no submap yet) and keep their predicted pose",
                self.predicted
            ));
        }
        if self.refused > 0 {
            out.push(format!("{} scans refused: a non-finite track pose, or a sensor origin not finite or farther from the base than slam.max_range_m", self.refused));
        }
        if self.edges_refused > 0 {
            out.push(format!(
                "{} pose-graph edges left out: their measurement or information was not finite",
                self.edges_refused
            ));
        }
        if self.track_jumps > 0 {
            out.push(format!(
                "{} times the pose track moved faster than log.max_speed_m_s or log.max_turn_rate_deg_s allow between two scans (an odometry reset, a teleported pose): those scans were matched from the previous scan's pose, not moved with the track",
                self.track_jumps
            ));
        }
        if self.loop_over_budget > 0 {
            out.push(format!(
                "{} loop-closure searches left out by the per-batch work budget ([slam] loop_closure_work_per_batch)",
                self.loop_over_budget
            ));
        }
        if let Some(first) = self.optimisation_failures.first() {
            out.push(format!(
                "{} pose-graph optimisations failed and kept the previous poses; the first: {first}",
                self.optimisation_failures.len()
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clean_run_has_no_findings_and_each_problem_one() {
        let clean = SlamReport {
            scans: 100,
            matched: 100,
            nodes: 50,
            travel_m: 300.0,
            loop_searches: 20,
            loop_accepted: 5,
            loop_rejected: 15,
            loop_unconfirmed: 2,
            loop_disagreeing: 3,
            longest_loop_m: 80.0,
            ..Default::default()
        };
        let f = |r: &SlamReport| r.findings(true, 50.0);
        assert!(f(&clean).is_empty(), "{:?}", f(&clean));
        let open = SlamReport { longest_loop_m: 12.0, ..clean.clone() };
        assert!(f(&open)[0].contains("the longest 12.0 m): 20 searches, 5 accepted, 10 below"), "{:?}", f(&open));
        // Not when loop closure is off, nor on a run too short for a loop.
        assert!(open.findings(false, 50.0).is_empty());
        assert!(f(&SlamReport { travel_m: 40.0, ..open.clone() }).is_empty());
        assert!(f(&SlamReport::default()).is_empty());
        let corridor = SlamReport { degenerate: 30, matched: 70, ..clean.clone() };
        assert!(f(&corridor)[0].contains("30 % of the scans"), "{:?}", f(&corridor));
        let unmatched = SlamReport { predicted: 10, matched: 90, ..clean.clone() };
        assert!(f(&unmatched)[0].contains("10 scans were not matched"), "{:?}", f(&unmatched));
        let failed = SlamReport { optimisation_failures: vec!["singular".into()], ..clean.clone() };
        assert!(f(&failed)[0].contains("1 pose-graph optimisations failed"), "{:?}", f(&failed));
        let budget = SlamReport { loop_over_budget: 3, refused: 1, ..clean.clone() };
        assert_eq!(f(&budget).len(), 2, "{:?}", f(&budget));
        let jumps = SlamReport { track_jumps: 2, ..clean };
        assert!(f(&jumps)[0].starts_with("2 times the pose track moved faster"), "{:?}", f(&jumps));
    }
}
