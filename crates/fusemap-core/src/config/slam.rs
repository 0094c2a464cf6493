//! `[slam]`: scan matching, submaps and loop closure (Hess et al. 2016), and when they run.
//!
//! Every key maps onto [`SlamParams`]; the defaults are in [`SlamParams::default`] and the
//! reasons for them beside each field there.

use super::{err, finite, probability, FieldError};
use crate::slam::{LocalMatchParams, SlamParams, SubmapBounds};
use serde::{Deserialize, Serialize};

/// When SLAM corrects the pose track.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlamMode {
    /// On when the poses come from odometry, the estimator, TF under an `odom` frame or
    /// the raw odometry of a CARMEN log (pose = odometry on every scan line, no `NEFF`
    /// lines); off when they are already corrected (corrected CARMEN logs, TF from a `map`
    /// frame).
    #[default]
    Auto,
    /// Always (on a log with a lidar).
    On,
    /// Never: the pose track is used as it is.
    Off,
}

/// The `[slam]` table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SlamConfig {
    /// `auto`, `on` or `off`.
    pub mode: SlamMode,
    /// Submap cell size, metres.
    pub resolution_m: f64,
    /// A submap is full (the next one starts) after this much travel, metres …
    pub submap_distance_m: f64,
    /// … or this much turning, degrees …
    pub submap_rotation_deg: f64,
    /// … or this many scans.
    pub submap_max_scans: usize,
    /// Occupancy probability of one hit in a submap.
    pub hit_probability: f64,
    /// Occupancy probability of one miss in a submap.
    pub miss_probability: f64,
    /// σ of the likelihood field scans are matched against, metres.
    pub field_sigma_m: f64,
    /// Returns farther than this are not used by SLAM, metres.
    pub max_range_m: f64,
    /// Scans with fewer usable returns are not matched.
    pub min_points: usize,
    /// A scan becomes a pose-graph node after this much travel, metres …
    pub node_distance_m: f64,
    /// … or this much turn, degrees …
    pub node_angle_deg: f64,
    /// … or this much time, seconds.
    pub node_time_s: f64,
    /// Correlative search half-width in x and y, metres.
    pub search_linear_window_m: f64,
    /// Correlative search half-width in heading, degrees.
    pub search_angular_window_deg: f64,
    /// Correlative motion penalty per metre.
    pub translation_delta_cost: f64,
    /// Correlative motion penalty per radian.
    pub rotation_delta_cost: f64,
    /// Refinement pull of the translation towards the prediction, per metre.
    pub translation_weight: f64,
    /// Refinement pull of the heading towards the correlative result, per radian.
    pub rotation_weight: f64,
    /// σ of one point's residual (probability units) scaling the match information.
    pub match_residual_sigma: f64,
    /// Smallest/largest translational information below which a match is degenerate.
    pub degeneracy_ratio: f64,
    /// The constant-velocity prediction replaces the track's when its match's mean
    /// probability is higher by this much (odometry that stalls, then jumps).
    pub moving_prediction_margin: f64,
    /// A match scoring below this share of the recent matches' is searched again wider.
    pub rescue_score_ratio: f64,
    /// That wider search's half-width in x and y, metres.
    pub rescue_linear_window_m: f64,
    /// That wider search's half-width in heading, degrees.
    pub rescue_angular_window_deg: f64,
    /// Odometry edge σ per metre travelled.
    pub odometry_translation_per_m: f64,
    /// Odometry edge σ floor, metres.
    pub odometry_floor_m: f64,
    /// Odometry edge σ per radian turned.
    pub odometry_rotation_per_rad: f64,
    /// Odometry edge σ floor, degrees.
    pub odometry_floor_deg: f64,
    /// Search for loop closures.
    pub loop_closure: bool,
    /// Share of nodes searched for loop closures: the loop-closure rate.
    pub loop_closure_sampling_ratio: f64,
    /// … and at most one node per this much travel, metres.
    pub loop_closure_node_spacing_m: f64,
    /// A searched node tries at most this many nearest finished submaps.
    pub loop_closure_submaps_per_node: usize,
    /// A finished submap is tried by at most this many earlier nodes near it.
    pub loop_closure_nodes_per_submap: usize,
    /// Two submaps tied by this many accepted closures are not searched again (0: no
    /// limit).
    pub loop_closure_links_per_pair: usize,
    /// Returns farther than this are left out of the loop-closure search, metres.
    pub loop_closure_max_range_m: f64,
    /// At most this many returns (evenly spread) go into a loop-closure search.
    pub loop_closure_max_points: usize,
    /// Memory for the submaps' branch-and-bound grids, MiB (least recently used rebuilt).
    pub loop_closure_grid_cache_mib: usize,
    /// Only submaps within this distance of a node are searched, metres.
    pub loop_closure_max_distance_m: f64,
    /// Loop-closure search half-width in x and y, metres.
    pub loop_closure_linear_window_m: f64,
    /// Loop-closure search half-width in heading, degrees.
    pub loop_closure_angular_window_deg: f64,
    /// Minimum mean probability of a loop closure's points (the score threshold).
    pub loop_closure_min_score: f64,
    /// Smallest/largest translational information ratio of a loop closure below which it
    /// is refused as degenerate.
    pub loop_closure_degeneracy_ratio: f64,
    /// Huber scale of loop-closure edges, in σ (the first pass of each optimisation).
    pub loop_closure_huber: f64,
    /// Φ of the dynamic covariance scaling of loop-closure edges (the second pass).
    pub loop_closure_dcs: f64,
    /// Metres the loop-closure window grows per metre driven since the last closure.
    pub loop_closure_window_growth: f64,
    /// Degrees the loop-closure window grows per metre driven since the last closure.
    pub loop_closure_angular_growth_deg_per_m: f64,
    /// The widest loop-closure window, metres.
    pub loop_closure_max_linear_window_m: f64,
    /// A closure moving its node by at most this much (metres) …
    pub loop_closure_accept_shift_m: f64,
    /// … and this much (degrees) is accepted at once; more needs a confirmation.
    pub loop_closure_accept_shift_deg: f64,
    /// Half-width of the search that confirms a large correction, metres …
    pub loop_closure_confirm_linear_window_m: f64,
    /// … and degrees.
    pub loop_closure_confirm_angular_window_deg: f64,
    /// A large correction must be confirmed within this much travel, metres.
    pub loop_closure_confirm_within_m: f64,
    /// Travel without a closure after which global searches begin, metres.
    pub loop_closure_global_after_m: f64,
    /// Submaps searched globally per batch.
    pub loop_closure_global_submaps_per_batch: usize,
    /// Score a global match needs.
    pub loop_closure_global_min_score: f64,
    /// Searches run together every this many nodes.
    pub loop_closure_batch_nodes: usize,
    /// At most this much work a batch (millions of grid lookups).
    pub loop_closure_million_lookups_per_batch: f64,
    /// σ of a loop closure's translation, metres.
    pub loop_closure_sigma_m: f64,
    /// σ of a loop closure's rotation, degrees.
    pub loop_closure_sigma_deg: f64,
    /// Optimise the pose graph every this many nodes (and at the end).
    pub optimize_every_n_nodes: usize,
    /// … and at least this much travel, metres.
    pub optimize_every_m: f64,
    /// Levels of the branch-and-bound precomputation (2^(depth−1) cells at the top).
    pub branch_and_bound_depth: usize,
    /// GNSS fixes become position priors on the pose graph's nodes (when the track is the
    /// estimator's, whose map frame is the fixes').
    pub fixes: bool,
    /// A fix is attached to the node nearest in time if within this, seconds.
    pub fix_max_offset_s: f64,
    /// Huber scale of a fix's prior (whitened units).
    pub fix_huber: f64,
}

/// Angles are written as the literal degrees of [`SlamParams::default`]: a round trip
/// through radians would differ from a config that writes the same default in its last bit.
impl Default for SlamConfig {
    fn default() -> Self {
        let p = SlamParams::default();
        Self {
            mode: SlamMode::Auto,
            resolution_m: p.resolution,
            submap_distance_m: p.submap.distance_m,
            submap_rotation_deg: 360.0,
            submap_max_scans: p.submap.max_scans,
            hit_probability: p.hit_probability as f64,
            miss_probability: p.miss_probability as f64,
            field_sigma_m: p.field_sigma_m,
            max_range_m: p.max_range_m,
            min_points: p.min_points,
            node_distance_m: p.node_distance_m,
            node_angle_deg: 2.0,
            node_time_s: p.node_time_s,
            search_linear_window_m: p.local.linear_window_m,
            search_angular_window_deg: 6.0,
            translation_delta_cost: p.local.translation_delta_cost,
            rotation_delta_cost: p.local.rotation_delta_cost,
            translation_weight: p.local.translation_weight,
            rotation_weight: p.local.rotation_weight,
            match_residual_sigma: p.local.residual_sigma,
            degeneracy_ratio: p.local.degeneracy_ratio,
            moving_prediction_margin: p.moving_prediction_margin,
            rescue_score_ratio: p.rescue_score_ratio,
            rescue_linear_window_m: p.rescue_linear_window_m,
            rescue_angular_window_deg: 20.0,
            odometry_translation_per_m: p.odometry_translation_per_m,
            odometry_floor_m: p.odometry_floor_m,
            odometry_rotation_per_rad: p.odometry_rotation_per_rad,
            odometry_floor_deg: 1.0,
            loop_closure: p.loop_closure,
            loop_closure_sampling_ratio: p.loop_closure_sampling_ratio,
            loop_closure_node_spacing_m: p.loop_closure_node_spacing_m,
            loop_closure_submaps_per_node: p.loop_closure_submaps_per_node,
            loop_closure_nodes_per_submap: p.loop_closure_nodes_per_submap,
            loop_closure_links_per_pair: p.loop_closure_links_per_pair,
            loop_closure_max_range_m: p.loop_closure_max_range_m,
            loop_closure_max_points: p.loop_closure_max_points,
            loop_closure_grid_cache_mib: p.loop_closure_grid_cache_mib,
            loop_closure_max_distance_m: p.loop_closure_max_distance_m,
            loop_closure_linear_window_m: p.loop_closure_linear_window_m,
            loop_closure_angular_window_deg: 10.0,
            loop_closure_min_score: p.loop_closure_min_score as f64,
            loop_closure_degeneracy_ratio: p.loop_closure_degeneracy_ratio,
            loop_closure_huber: p.loop_closure_huber,
            loop_closure_dcs: p.loop_closure_dcs,
            loop_closure_window_growth: p.loop_closure_window_growth,
            loop_closure_angular_growth_deg_per_m: 0.02,
            loop_closure_accept_shift_m: p.loop_closure_accept_shift_m,
            loop_closure_accept_shift_deg: 5.0,
            loop_closure_max_linear_window_m: p.loop_closure_max_linear_window_m,
            loop_closure_confirm_linear_window_m: p.loop_closure_confirm_linear_window_m,
            loop_closure_confirm_angular_window_deg: 3.0,
            loop_closure_confirm_within_m: p.loop_closure_confirm_within_m,
            loop_closure_global_after_m: p.loop_closure_global_after_m,
            loop_closure_global_submaps_per_batch: p.loop_closure_global_submaps_per_batch,
            loop_closure_global_min_score: p.loop_closure_global_min_score as f64,
            loop_closure_batch_nodes: p.loop_closure_batch_nodes,
            loop_closure_million_lookups_per_batch: p.loop_closure_work_per_batch / 1e6,
            loop_closure_sigma_m: p.loop_closure_sigma_m,
            loop_closure_sigma_deg: 0.2,
            optimize_every_n_nodes: p.optimize_every_n_nodes,
            optimize_every_m: p.optimize_every_m,
            branch_and_bound_depth: p.branch_and_bound_depth,
            fixes: p.fixes,
            fix_max_offset_s: p.fix_max_offset_s,
            fix_huber: p.fix_huber,
        }
    }
}

fn positive(field: &str, v: f64) -> Result<f64, FieldError> {
    let v = finite(&format!("slam.{field}"), v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(err(format!("slam.{field}"), format!("must be > 0, got {v}")))
    }
}

fn non_negative(field: &str, v: f64) -> Result<f64, FieldError> {
    let v = finite(&format!("slam.{field}"), v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(err(format!("slam.{field}"), format!("must be ≥ 0, got {v}")))
    }
}

/// A ratio of the smallest to the largest information, which lies in [0, 1]: above 1 every
/// match would be refused.
fn unit_ratio(field: &str, v: f64) -> Result<f64, FieldError> {
    let v = finite(field, v)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(err(field, format!("must be within 0..=1, got {v}")))
    }
}

/// The most candidate poses one correlative search may score for a scan: 500 times the
/// local search's default (2,107) and 40 times the rescue search's (23,829). Each is scored
/// against every return, so 10⁶ candidates of a 360-beam scan are 3.6 × 10⁸ lookups.
pub const MAX_SEARCH_CANDIDATES: f64 = 1e6;

/// Checks what the correlative searches cost a scan, not only each key's sign: a window
/// of 5 m and 180° at 5 mm passes every key's range and would score 10¹¹ poses a scan.
fn check_search_cost(p: &SlamParams) -> Result<(), FieldError> {
    let windows = [
        ("search", p.local.linear_window_m, p.local.angular_window_rad),
        ("rescue", p.rescue_linear_window_m, p.rescue_angular_window_rad),
    ];
    for (name, linear, angular) in windows {
        let n = crate::slam::search_candidates(linear, angular, p.resolution);
        if n > MAX_SEARCH_CANDIDATES {
            return Err(err(
                format!("slam.{name}_linear_window_m"),
                format!(
                    "slam.{name}_linear_window_m = {linear} m and slam.{name}_angular_window_deg = {:.1}° at slam.resolution_m = {} m are {n:.3e} candidate poses a scan, over the limit of {MAX_SEARCH_CANDIDATES:.0e} (each is scored against every return); narrow the windows or coarsen slam.resolution_m",
                    angular.to_degrees(),
                    p.resolution
                ),
            ));
        }
    }
    Ok(())
}

impl SlamConfig {
    /// Checks every key and builds the parameters.
    pub fn validate(&self) -> Result<SlamParams, FieldError> {
        let hit = probability("slam.hit_probability", self.hit_probability)?;
        let miss = probability("slam.miss_probability", self.miss_probability)?;
        if hit <= 0.5 || miss >= 0.5 {
            return Err(err("slam", format!("need hit_probability > 0.5 > miss_probability, got {hit} / {miss}")));
        }
        let score = probability("slam.loop_closure_min_score", self.loop_closure_min_score)?;
        let ratio = finite("slam.loop_closure_sampling_ratio", self.loop_closure_sampling_ratio)?;
        if !(0.0..=1.0).contains(&ratio) {
            return Err(err("slam.loop_closure_sampling_ratio", format!("must be within 0..=1, got {ratio}")));
        }
        let res = positive("resolution_m", self.resolution_m)?;
        if !(0.005..=1.0).contains(&res) {
            return Err(err("slam.resolution_m", format!("must be within 0.005..=1 m, got {res}")));
        }
        for (k, v) in
            [("submap_max_scans", self.submap_max_scans), ("optimize_every_n_nodes", self.optimize_every_n_nodes)]
        {
            if v == 0 {
                return Err(err(format!("slam.{k}"), "must be at least 1"));
            }
        }
        if !(1..=12).contains(&self.branch_and_bound_depth) {
            return Err(err(
                "slam.branch_and_bound_depth",
                format!("must be within 1..=12, got {}", self.branch_and_bound_depth),
            ));
        }
        let angular = non_negative("search_angular_window_deg", self.search_angular_window_deg)?;
        let lc_angular = non_negative("loop_closure_angular_window_deg", self.loop_closure_angular_window_deg)?;
        let rescue_angular = non_negative("rescue_angular_window_deg", self.rescue_angular_window_deg)?;
        if angular > 180.0 || lc_angular > 180.0 || rescue_angular > 180.0 {
            return Err(err("slam", "angular search windows must be at most 180°"));
        }
        let params = self.matching(res, hit, miss, angular, rescue_angular)?;
        let params = self.with_loop_closure(params, ratio, lc_angular, score)?;
        check_search_cost(&params)?;
        Ok(params)
    }

    /// The scan matcher's, the submaps' and the odometry edges' parameters (every other
    /// field the default, set by [`SlamConfig::with_loop_closure`]).
    fn matching(
        &self,
        res: f64,
        hit: f64,
        miss: f64,
        angular: f64,
        rescue_angular: f64,
    ) -> Result<SlamParams, FieldError> {
        Ok(SlamParams {
            resolution: res,
            submap: SubmapBounds {
                distance_m: positive("submap_distance_m", self.submap_distance_m)?,
                rotation_rad: positive("submap_rotation_deg", self.submap_rotation_deg)?.to_radians(),
                max_scans: self.submap_max_scans,
            },
            hit_probability: hit as f32,
            miss_probability: miss as f32,
            field_sigma_m: non_negative("field_sigma_m", self.field_sigma_m)?.min(1.0),
            max_range_m: positive("max_range_m", self.max_range_m)?,
            min_points: self.min_points,
            max_track_speed_m_s: SlamParams::default().max_track_speed_m_s,
            max_track_turn_rate_rad_s: SlamParams::default().max_track_turn_rate_rad_s,
            node_distance_m: non_negative("node_distance_m", self.node_distance_m)?,
            node_angle_rad: non_negative("node_angle_deg", self.node_angle_deg)?.to_radians(),
            node_time_s: positive("node_time_s", self.node_time_s)?,
            local: LocalMatchParams {
                linear_window_m: non_negative("search_linear_window_m", self.search_linear_window_m)?.min(5.0),
                angular_window_rad: angular.to_radians(),
                translation_delta_cost: non_negative("translation_delta_cost", self.translation_delta_cost)?,
                rotation_delta_cost: non_negative("rotation_delta_cost", self.rotation_delta_cost)?,
                map_weight: 1.0,
                translation_weight: non_negative("translation_weight", self.translation_weight)?,
                rotation_weight: non_negative("rotation_weight", self.rotation_weight)?,
                residual_sigma: positive("match_residual_sigma", self.match_residual_sigma)?,
                degeneracy_ratio: unit_ratio("slam.degeneracy_ratio", self.degeneracy_ratio)?,
            },
            moving_prediction_margin: non_negative("moving_prediction_margin", self.moving_prediction_margin)?,
            rescue_score_ratio: non_negative("rescue_score_ratio", self.rescue_score_ratio)?,
            rescue_linear_window_m: non_negative("rescue_linear_window_m", self.rescue_linear_window_m)?.min(5.0),
            rescue_angular_window_rad: rescue_angular.to_radians(),
            odometry_translation_per_m: non_negative("odometry_translation_per_m", self.odometry_translation_per_m)?,
            odometry_floor_m: positive("odometry_floor_m", self.odometry_floor_m)?,
            odometry_rotation_per_rad: non_negative("odometry_rotation_per_rad", self.odometry_rotation_per_rad)?,
            odometry_floor_rad: positive("odometry_floor_deg", self.odometry_floor_deg)?.to_radians(),
            ..SlamParams::default()
        })
    }

    /// `params` with the loop closure's, the optimisation's and the fix priors' parameters.
    fn with_loop_closure(
        &self,
        params: SlamParams,
        ratio: f64,
        lc_angular: f64,
        score: f64,
    ) -> Result<SlamParams, FieldError> {
        Ok(SlamParams {
            loop_closure: self.loop_closure,
            loop_closure_sampling_ratio: ratio,
            loop_closure_node_spacing_m: non_negative("loop_closure_node_spacing_m", self.loop_closure_node_spacing_m)?,
            loop_closure_submaps_per_node: self.loop_closure_submaps_per_node,
            loop_closure_nodes_per_submap: self.loop_closure_nodes_per_submap,
            loop_closure_links_per_pair: self.loop_closure_links_per_pair,
            loop_closure_max_range_m: positive("loop_closure_max_range_m", self.loop_closure_max_range_m)?,
            loop_closure_max_points: self.loop_closure_max_points,
            loop_closure_grid_cache_mib: self.loop_closure_grid_cache_mib,
            loop_closure_max_distance_m: non_negative("loop_closure_max_distance_m", self.loop_closure_max_distance_m)?,
            loop_closure_linear_window_m: non_negative(
                "loop_closure_linear_window_m",
                self.loop_closure_linear_window_m,
            )?
            .min(100.0),
            loop_closure_angular_window_rad: lc_angular.to_radians(),
            loop_closure_min_score: score as f32,
            loop_closure_degeneracy_ratio: unit_ratio(
                "slam.loop_closure_degeneracy_ratio",
                self.loop_closure_degeneracy_ratio,
            )?,
            loop_closure_huber: positive("loop_closure_huber", self.loop_closure_huber)?,
            loop_closure_dcs: positive("loop_closure_dcs", self.loop_closure_dcs)?,
            loop_closure_window_growth: non_negative("loop_closure_window_growth", self.loop_closure_window_growth)?,
            loop_closure_angular_growth_rad_per_m: non_negative(
                "loop_closure_angular_growth_deg_per_m",
                self.loop_closure_angular_growth_deg_per_m,
            )?
            .to_radians(),
            loop_closure_max_linear_window_m: non_negative(
                "loop_closure_max_linear_window_m",
                self.loop_closure_max_linear_window_m,
            )?
            .min(100.0),
            ..self.with_closure_acceptance(params)?
        })
    }

    /// `params` with what makes a found match an edge (accepting, confirming, global
    /// searches, batches, the edges' weights), the optimisation's and the fix priors'.
    fn with_closure_acceptance(&self, params: SlamParams) -> Result<SlamParams, FieldError> {
        Ok(SlamParams {
            loop_closure_accept_shift_m: non_negative("loop_closure_accept_shift_m", self.loop_closure_accept_shift_m)?,
            loop_closure_accept_shift_rad: non_negative(
                "loop_closure_accept_shift_deg",
                self.loop_closure_accept_shift_deg,
            )?
            .min(180.0)
            .to_radians(),
            loop_closure_confirm_linear_window_m: non_negative(
                "loop_closure_confirm_linear_window_m",
                self.loop_closure_confirm_linear_window_m,
            )?
            .min(100.0),
            loop_closure_confirm_angular_window_rad: non_negative(
                "loop_closure_confirm_angular_window_deg",
                self.loop_closure_confirm_angular_window_deg,
            )?
            .min(180.0)
            .to_radians(),
            loop_closure_confirm_within_m: non_negative(
                "loop_closure_confirm_within_m",
                self.loop_closure_confirm_within_m,
            )?,
            loop_closure_global_after_m: non_negative("loop_closure_global_after_m", self.loop_closure_global_after_m)?,
            loop_closure_global_submaps_per_batch: self.loop_closure_global_submaps_per_batch,
            loop_closure_global_min_score: probability(
                "slam.loop_closure_global_min_score",
                self.loop_closure_global_min_score,
            )? as f32,
            loop_closure_batch_nodes: self.loop_closure_batch_nodes.max(1),
            loop_closure_work_per_batch: positive(
                "loop_closure_million_lookups_per_batch",
                self.loop_closure_million_lookups_per_batch,
            )? * 1e6,
            loop_closure_sigma_m: positive("loop_closure_sigma_m", self.loop_closure_sigma_m)?,
            loop_closure_sigma_rad: positive("loop_closure_sigma_deg", self.loop_closure_sigma_deg)?.to_radians(),
            optimize_every_n_nodes: self.optimize_every_n_nodes,
            optimize_every_m: non_negative("optimize_every_m", self.optimize_every_m)?,
            branch_and_bound_depth: self.branch_and_bound_depth,
            fixes: self.fixes,
            fix_max_offset_s: non_negative("fix_max_offset_s", self.fix_max_offset_s)?.min(60.0),
            fix_huber: positive("fix_huber", self.fix_huber)?,
            ..params
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_to_the_parameters() {
        let p = SlamConfig::default().validate().unwrap();
        let d = SlamParams::default();
        assert_eq!(p.submap.max_scans, d.submap.max_scans);
        assert!((p.submap.rotation_rad - d.submap.rotation_rad).abs() < 1e-12);
        assert!((p.node_angle_rad - d.node_angle_rad).abs() < 1e-12);
        assert!((p.loop_closure_angular_window_rad - d.loop_closure_angular_window_rad).abs() < 1e-12);
        assert_eq!(p.local.linear_window_m, d.local.linear_window_m);
    }

    #[test]
    fn bad_keys_are_named() {
        let c = SlamConfig { resolution_m: 1e-9, ..Default::default() };
        assert!(c.validate().unwrap_err().to_string().contains("slam.resolution_m"));
        let c = SlamConfig { hit_probability: 0.4, ..Default::default() };
        assert!(c.validate().unwrap_err().to_string().contains("hit_probability"));
        let c = SlamConfig { loop_closure_sampling_ratio: 2.0, ..Default::default() };
        assert!(c.validate().unwrap_err().to_string().contains("slam.loop_closure_sampling_ratio"));
        let c = SlamConfig { loop_closure_degeneracy_ratio: 1.5, ..Default::default() };
        assert!(c.validate().unwrap_err().to_string().contains("slam.loop_closure_degeneracy_ratio"));
        let c = SlamConfig { submap_max_scans: 0, ..Default::default() };
        assert!(c.validate().unwrap_err().to_string().contains("slam.submap_max_scans"));
    }

    #[test]
    fn a_search_window_is_judged_by_what_it_costs_a_scan() {
        let p = SlamConfig::default().validate().unwrap();
        let cost = |lin: f64, ang: f64| crate::slam::search_candidates(lin, ang, p.resolution);
        assert_eq!(cost(p.local.linear_window_m, p.local.angular_window_rad), 2107.0);
        assert_eq!(cost(p.rescue_linear_window_m, p.rescue_angular_window_rad), 23829.0);
        // A wide window a user may want for poor odometry passes …
        let wide = SlamConfig { search_linear_window_m: 1.0, search_angular_window_deg: 30.0, ..Default::default() };
        assert!(wide.validate().is_ok());
        // … every key of this one is in range, and it would score 10¹¹ poses a scan.
        for (name, c) in [
            (
                "slam.search_linear_window_m",
                SlamConfig {
                    resolution_m: 0.005,
                    search_linear_window_m: 5.0,
                    search_angular_window_deg: 180.0,
                    ..Default::default()
                },
            ),
            ("slam.rescue_linear_window_m", SlamConfig { rescue_linear_window_m: 3.0, ..Default::default() }),
        ] {
            let e = c.validate().unwrap_err();
            assert_eq!(e.field, name, "{e}");
            assert!(e.message.contains("candidate poses a scan, over the limit of 1e6"), "{e}");
        }
    }
}
