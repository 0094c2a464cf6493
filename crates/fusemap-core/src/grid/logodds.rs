//! Log-odds occupancy arithmetic (Thrun et al., *Probabilistic Robotics*, §9.2, Table 9.1;
//! Moravec & Elfes 1985).
//!
//! A cell stores `l = ln(p / (1 - p))`. A measurement with inverse-model probability
//! `p_meas` updates it by `l ← l + ln(p_meas / (1 - p_meas)) - l_0`, where `l_0` is the
//! prior's log-odds: without the `- l_0` the prior would be counted again at every
//! update. Sums stay finite where products of probabilities would underflow.
//!
//! **Clamping.** After each update `l` is clamped to `[l_min, l_max]` (defaults: p = 0.12
//! and 0.97, OctoMap's values, Hornung et al. 2013 §III-C). Unclamped, a cell seen free
//! ten thousand times needs ten thousand hits to turn occupied: the map could never
//! follow a door that closes or a chair that moves, and float32 loses the small steps
//! against a huge accumulated value. Clamping bounds the evidence a cell can hold so it
//! can always be revised in a bounded number of updates.

use serde::{Deserialize, Serialize};

/// `ln(p / (1 - p))`.
#[inline]
pub fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// `1 - 1 / (1 + e^l)`: the inverse of [`logit`], written as the design document writes
/// it. Saturates to exactly 0 or 1 for |l| beyond ~745 without producing NaN.
#[inline]
pub fn probability(l: f64) -> f64 {
    1.0 - 1.0 / (1.0 + l.exp())
}

/// What a map knows about a cell, by thresholds on its probability.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Ternary {
    /// Probability below the free threshold.
    Free,
    /// Probability above the occupied threshold.
    Occupied,
    /// Never observed, or observed without enough evidence either way.
    Unknown,
}

/// The probabilistic parameters of an occupancy layer, all in probability form.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OccupancyParams {
    /// Prior occupancy of an unobserved cell.
    pub prior: f64,
    /// Lower clamp on a cell's probability.
    pub clamp_min: f64,
    /// Upper clamp on a cell's probability.
    pub clamp_max: f64,
    /// A cell is occupied when its probability is above this.
    pub occupied_threshold: f64,
    /// A cell is free when its probability is below this.
    pub free_threshold: f64,
    /// How free evidence behind a confidently occupied cell is weighed. Off in
    /// `OccupancyParams::default()` (the plain model of Thrun et al.); the configuration's
    /// `[map.pass_through]` turns it on by default (see [`PassThroughParams`](super::PassThroughParams)).
    #[serde(default = "pass_through_off")]
    pub pass_through: super::PassThroughParams,
}

impl Default for OccupancyParams {
    fn default() -> Self {
        Self {
            prior: 0.5,
            clamp_min: 0.12,
            clamp_max: 0.97,
            occupied_threshold: 0.65,
            free_threshold: 0.25,
            pass_through: super::PassThroughParams::OFF,
        }
    }
}

fn pass_through_off() -> super::PassThroughParams {
    super::PassThroughParams::OFF
}

/// The same parameters in log-odds form, precomputed once for the update loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogOddsTable {
    /// `l_0`, the prior's log-odds.
    pub prior: f32,
    /// `l_min`.
    pub min: f32,
    /// `l_max`.
    pub max: f32,
    occupied_threshold: f64,
    free_threshold: f64,
}

impl LogOddsTable {
    /// Precomputes the log-odds of `params`. Callers validate `params` first (see the
    /// config module); this only converts.
    pub fn new(params: &OccupancyParams) -> Self {
        Self {
            prior: logit(params.prior) as f32,
            min: logit(params.clamp_min) as f32,
            max: logit(params.clamp_max) as f32,
            occupied_threshold: params.occupied_threshold,
            free_threshold: params.free_threshold,
        }
    }

    /// The increment a measurement with inverse-model probability `p_meas` adds:
    /// `ln(p_meas / (1 - p_meas)) - l_0`.
    pub fn increment(&self, p_meas: f64) -> f32 {
        (logit(p_meas) - self.prior as f64) as f32
    }

    /// One Bayesian update of a stored value: `clamp(l + delta)`.
    #[inline(always)]
    pub fn update(&self, l: f32, delta: f32) -> f32 {
        (l + delta).clamp(self.min, self.max)
    }

    /// Classifies a probability.
    pub fn classify(&self, p: f64) -> Ternary {
        if p > self.occupied_threshold {
            Ternary::Occupied
        } else if p < self.free_threshold {
            Ternary::Free
        } else {
            Ternary::Unknown
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn document_values() {
        assert!((logit(0.9) - 2.1972245773).abs() < 1e-9);
        assert!((logit(0.4) + 0.4054651081).abs() < 1e-9);
        assert_eq!(logit(0.5), 0.0);
        assert_eq!(probability(0.0), 0.5);
        assert_eq!(probability(1e4), 1.0);
        assert_eq!(probability(-1e4), 0.0);
    }

    #[test]
    fn prior_is_not_injected_twice() {
        // With prior 0.7, a measurement that says exactly "0.7" must leave the cell alone.
        let t = LogOddsTable::new(&OccupancyParams { prior: 0.7, ..Default::default() });
        assert!(t.increment(0.7).abs() < 1e-6);
    }

    #[test]
    fn clamping_keeps_a_cell_revisable() {
        let t = LogOddsTable::new(&OccupancyParams::default());
        let free = t.increment(0.4);
        let occ = t.increment(0.9);
        let mut l = t.prior;
        for _ in 0..10_000 {
            l = t.update(l, free);
        }
        assert_eq!(l, t.min);
        // Two hits bring it back above 0.5: (l_min = -1.99) + 2 × 2.197 > 0.
        l = t.update(t.update(l, occ), occ);
        assert!(probability(l as f64) > 0.5);
    }

    #[test]
    fn classification_uses_strict_thresholds() {
        let t = LogOddsTable::new(&OccupancyParams::default());
        assert_eq!(t.classify(0.9), Ternary::Occupied);
        assert_eq!(t.classify(0.65), Ternary::Unknown);
        assert_eq!(t.classify(0.5), Ternary::Unknown);
        assert_eq!(t.classify(0.25), Ternary::Unknown);
        assert_eq!(t.classify(0.1), Ternary::Free);
    }

    proptest! {
        #[test]
        fn logit_and_probability_are_inverse(p in 1e-6..(1.0 - 1e-6f64)) {
            prop_assert!((probability(logit(p)) - p).abs() < 1e-9);
        }

        #[test]
        fn updates_commute_without_clamping(a in -3.0..3.0f64, b in -3.0..3.0f64, c in -3.0..3.0f64) {
            // Bayes with independent evidence: order does not matter.
            let x = (a + b) + c;
            let y = (c + a) + b;
            prop_assert!((x - y).abs() < 1e-12);
        }

        #[test]
        fn update_stays_in_the_clamp(l in -2.0f32..3.5, d in -50.0f32..50.0) {
            let t = LogOddsTable::new(&OccupancyParams::default());
            let l = l.clamp(t.min, t.max);
            let u = t.update(l, d);
            prop_assert!(u >= t.min && u <= t.max);
            if d >= 0.0 { prop_assert!(u >= l); } else { prop_assert!(u <= l); }
        }

        #[test]
        fn probability_is_monotone(a in -30.0..30.0f64, b in -30.0..30.0f64) {
            if a < b { prop_assert!(probability(a) <= probability(b)); }
        }
    }
}
