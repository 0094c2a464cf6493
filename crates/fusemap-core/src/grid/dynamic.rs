//! The dynamic-object layer: where moving things (people, forklifts) were seen recently.
//!
//! Dynamic objects must not enter the static map (design document §2.4: put dynamic
//! detections in a separate layer). Their evidence is log-odds of "a dynamic object is
//! here", like occupancy, but it *decays back to unknown* with a half-life `h`: a value
//! `l` written at `t₀` reads `l · 2^(−(t − t₀)/h)` at `t`. Decay is applied lazily, when
//! the cell is next read or written, from its last-update stamp, so an idle map costs
//! nothing.
//!
//! The layer's upper clamp bounds how long a trail lasts: a saturated cell falls below the
//! occupied threshold `l_occ` after `log2(l_max / l_occ)` half-lives (with `p_max = 0.9`
//! and a threshold of 0.65, 1.8 half-lives): a person's trail is gone within two
//! half-lives of the last sighting, whatever the evidence piled up before.

use super::logodds::logit;
use super::TILE_CELLS;
use crate::time::Stamp;

/// Parameters of the dynamic layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicParams {
    /// Half-life of the evidence, seconds.
    pub half_life_s: f64,
    /// Probability a dynamic detection (or a lidar hit routed here) gives its cell.
    pub p_hit: f64,
    /// Probability a cell seen empty (a ray through it, floor seen there) gives.
    pub p_miss: f64,
    /// Upper clamp (see the module docs for why it bounds the trail).
    pub clamp_max: f64,
    /// Probability above which a cell counts as holding a dynamic object now (lidar hits
    /// there are routed to this layer).
    pub occupied_threshold: f64,
}

impl Default for DynamicParams {
    fn default() -> Self {
        Self { half_life_s: 2.0, p_hit: 0.8, p_miss: 0.35, clamp_max: 0.9, occupied_threshold: 0.65 }
    }
}

/// The dynamic layer's parameters in log-odds form, with the clock of the observation
/// being inserted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicUpdate {
    d_hit: f32,
    d_miss: f32,
    max: f32,
    threshold: f32,
    /// `ln 2 / h`, per nanosecond.
    rate: f64,
    now: i64,
}

impl DynamicUpdate {
    /// The update for observations at `now`.
    pub fn new(p: &DynamicParams, now: Stamp) -> Self {
        Self {
            d_hit: logit(p.p_hit) as f32,
            d_miss: logit(p.p_miss) as f32,
            max: logit(p.clamp_max) as f32,
            threshold: logit(p.occupied_threshold) as f32,
            rate: std::f64::consts::LN_2 / (p.half_life_s * 1e9),
            now: now.0,
        }
    }

    /// The hit increment.
    pub fn d_hit(&self) -> f32 {
        self.d_hit
    }

    /// The miss increment.
    pub fn d_miss(&self) -> f32 {
        self.d_miss
    }

    /// Whether the cell at `offset` holds a dynamic object now.
    #[inline]
    pub fn is_dynamic(&self, block: Option<&DynamicBlock>, offset: usize) -> bool {
        block.is_some_and(|b| b.value_at(offset, self.now, self.rate) > self.threshold)
    }

    /// Adds `delta` to the cell at `offset` (after decaying it to now), allocating the block.
    #[inline]
    pub fn apply(&self, block: &mut Option<Box<DynamicBlock>>, offset: usize, delta: f32) {
        let b = block.get_or_insert_with(|| Box::new(DynamicBlock::empty()));
        let l = b.value_at(offset, self.now, self.rate);
        // The unknown state is 0 (prior 0.5); the lower clamp is the upper one mirrored,
        // so a cell seen empty recovers as fast as one seen occupied.
        b.log_odds[offset] = (l + delta).clamp(-self.max, self.max);
        b.stamp[offset] = b.stamp[offset].max(self.now);
    }

    /// Adds `delta` only to a cell the layer already holds (clearing evidence: a ray
    /// through empty space says nothing about a cell no moving object ever visited).
    #[inline]
    pub fn clear(&self, block: &mut Option<Box<DynamicBlock>>, offset: usize) {
        if let Some(b) = block.as_deref_mut() {
            if !b.log_odds[offset].is_nan() {
                let l = b.value_at(offset, self.now, self.rate);
                b.log_odds[offset] = (l + self.d_miss).clamp(-self.max, self.max);
                b.stamp[offset] = b.stamp[offset].max(self.now);
            }
        }
    }
}

/// One tile of the dynamic layer.
#[derive(Clone, Debug)]
pub struct DynamicBlock {
    /// Log-odds at the last update, NaN for a cell never written.
    log_odds: [f32; TILE_CELLS],
    /// Stamp of the last update, nanoseconds.
    stamp: [i64; TILE_CELLS],
}

impl DynamicBlock {
    fn empty() -> Self {
        Self { log_odds: [f32::NAN; TILE_CELLS], stamp: [i64::MIN; TILE_CELLS] }
    }

    #[inline]
    fn value_at(&self, offset: usize, now: i64, rate: f64) -> f32 {
        let l = self.log_odds[offset];
        if l.is_nan() {
            return 0.0;
        }
        let dt = now.saturating_sub(self.stamp[offset]).max(0) as f64;
        (l as f64 * (-rate * dt).exp()) as f32
    }

    /// The cell's log-odds decayed to `now` with half-life `half_life_s`, `None` if the
    /// layer never wrote it.
    pub fn log_odds_at(&self, offset: usize, now: Stamp, half_life_s: f64) -> Option<f32> {
        (!self.log_odds[offset].is_nan())
            .then(|| self.value_at(offset, now.0, std::f64::consts::LN_2 / (half_life_s * 1e9)))
    }

    /// The stamp of the cell's last update, `None` if never written.
    pub fn last_update(&self, offset: usize) -> Option<Stamp> {
        (!self.log_odds[offset].is_nan()).then_some(Stamp(self.stamp[offset]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::logodds::probability;

    const S: i64 = 1_000_000_000;

    #[test]
    fn evidence_halves_every_half_life() {
        let p = DynamicParams::default();
        let mut block = None;
        DynamicUpdate::new(&p, Stamp(0)).apply(&mut block, 7, 1.0);
        let b = block.as_deref().unwrap();
        let h = p.half_life_s;
        assert!((b.log_odds_at(7, Stamp(0), h).unwrap() - 1.0).abs() < 1e-6);
        assert!((b.log_odds_at(7, Stamp(2 * S), h).unwrap() - 0.5).abs() < 1e-6);
        assert!((b.log_odds_at(7, Stamp(4 * S), h).unwrap() - 0.25).abs() < 1e-6);
        assert_eq!(b.log_odds_at(8, Stamp(0), h), None);
        assert_eq!(b.last_update(7), Some(Stamp(0)));
    }

    #[test]
    fn a_saturated_trail_is_gone_within_two_half_lives() {
        let p = DynamicParams::default();
        let mut block = None;
        for k in 0..50 {
            let u = DynamicUpdate::new(&p, Stamp(k * S / 10));
            u.apply(&mut block, 0, u.d_hit());
            assert!(u.is_dynamic(block.as_deref(), 0));
        }
        let left = 49 * S / 10;
        let b = block.as_deref().unwrap();
        let l = b.log_odds_at(0, Stamp(left + (2.0 * p.half_life_s * 1e9) as i64), p.half_life_s).unwrap();
        assert!(probability(l as f64) < p.occupied_threshold, "{}", probability(l as f64));
        let later = DynamicUpdate::new(&p, Stamp(left + 4 * S));
        assert!(!later.is_dynamic(block.as_deref(), 0));
    }

    #[test]
    fn clearing_touches_only_cells_already_held() {
        let p = DynamicParams::default();
        let u = DynamicUpdate::new(&p, Stamp(0));
        let mut block = None;
        u.clear(&mut block, 3);
        assert!(block.is_none());
        u.apply(&mut block, 3, u.d_hit());
        u.clear(&mut block, 3);
        u.clear(&mut block, 4);
        let b = block.as_deref().unwrap();
        assert!((b.log_odds_at(3, Stamp(0), 2.0).unwrap() - (u.d_hit() + u.d_miss())).abs() < 1e-6);
        assert_eq!(b.log_odds_at(4, Stamp(0), 2.0), None);
    }
}
