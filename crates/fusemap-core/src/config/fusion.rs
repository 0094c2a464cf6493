//! `[fusion]`: how the sensors' evidence is combined — which sensors are correlated and
//! how their evidence is merged (design document §2.4), and the dynamic-object layer.

use super::{err, finite, probability, FieldError};
use crate::grid::{DynamicParams, MergeRule};
use serde::{Deserialize, Serialize};

/// The `[fusion]` table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FusionConfig {
    /// Groups of sensor names whose observations within `correlation_window_s` of each
    /// other are one look at the world (a lidar and the camera triggered with it), merged
    /// per cell into one equivalent observation instead of summed. Default: none.
    pub correlated: Vec<Vec<String>>,
    /// The window, seconds.
    pub correlation_window_s: f64,
    /// `max` (the evidence of largest magnitude: never more confident than the most
    /// confident member) or `mean`.
    pub merge: MergeRule,
    /// Half-life of the dynamic layer's evidence, seconds.
    pub dynamic_half_life_s: f64,
    /// Probability a dynamic detection gives its cell in the dynamic layer.
    pub dynamic_p_hit: f64,
    /// Probability a cell seen empty gives in the dynamic layer.
    pub dynamic_p_miss: f64,
    /// Upper clamp of the dynamic layer (bounds how long a trail lasts: a saturated cell
    /// falls below the occupied threshold within log2(logit(clamp) / logit(threshold))
    /// half-lives).
    pub dynamic_clamp_max: f64,
    /// Lidar hits on cells the dynamic layer holds as occupied (a person the camera
    /// labelled) go to the dynamic layer instead of the static map.
    pub route_lidar_hits_to_dynamic: bool,
}

impl Default for FusionConfig {
    fn default() -> Self {
        let d = DynamicParams::default();
        Self {
            correlated: Vec::new(),
            correlation_window_s: 0.05,
            merge: MergeRule::Max,
            dynamic_half_life_s: d.half_life_s,
            dynamic_p_hit: d.p_hit,
            dynamic_p_miss: d.p_miss,
            dynamic_clamp_max: d.clamp_max,
            route_lidar_hits_to_dynamic: true,
        }
    }
}

impl FusionConfig {
    /// Checks the numbers (sensor names are checked against the planned sensors by the
    /// caller) and returns the dynamic layer's parameters for a map whose occupied
    /// threshold is `occupied_threshold`.
    pub fn validate(&self, occupied_threshold: f64) -> Result<DynamicParams, FieldError> {
        let w = finite("fusion.correlation_window_s", self.correlation_window_s)?;
        if !(0.0..=1.0).contains(&w) {
            return Err(err("fusion.correlation_window_s", format!("must be within 0..=1 s, got {w}")));
        }
        let h = finite("fusion.dynamic_half_life_s", self.dynamic_half_life_s)?;
        if h <= 0.0 {
            return Err(err("fusion.dynamic_half_life_s", format!("must be > 0, got {h}")));
        }
        let p_hit = probability("fusion.dynamic_p_hit", self.dynamic_p_hit)?;
        let p_miss = probability("fusion.dynamic_p_miss", self.dynamic_p_miss)?;
        let clamp = probability("fusion.dynamic_clamp_max", self.dynamic_clamp_max)?;
        if p_hit <= 0.5 || p_miss >= 0.5 {
            return Err(err("fusion", format!("need dynamic_p_hit > 0.5 > dynamic_p_miss, got {p_hit} / {p_miss}")));
        }
        if clamp <= occupied_threshold {
            return Err(err(
                "fusion.dynamic_clamp_max",
                format!("must be above map.occupied_threshold ({occupied_threshold}), got {clamp}"),
            ));
        }
        for (i, g) in self.correlated.iter().enumerate() {
            if g.len() < 2 {
                return Err(err(format!("fusion.correlated[{i}]"), "a group needs at least two sensor names"));
            }
        }
        Ok(DynamicParams { half_life_s: h, p_hit, p_miss, clamp_max: clamp, occupied_threshold })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        let d = FusionConfig::default().validate(0.65).unwrap();
        assert_eq!(d, DynamicParams::default());
        let bad = FusionConfig { dynamic_half_life_s: 0.0, ..Default::default() };
        assert_eq!(bad.validate(0.65).unwrap_err().field, "fusion.dynamic_half_life_s");
        let bad = FusionConfig { dynamic_clamp_max: 0.6, ..Default::default() };
        assert_eq!(bad.validate(0.65).unwrap_err().field, "fusion.dynamic_clamp_max");
        let bad = FusionConfig { correlated: vec![vec!["laser".into()]], ..Default::default() };
        assert_eq!(bad.validate(0.65).unwrap_err().field, "fusion.correlated[0]");
    }
}
