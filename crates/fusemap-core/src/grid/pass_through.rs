//! Free evidence behind a confidently occupied cell: the pass-through rule.
//!
//! A lidar beam that meets polished steel can come back by a mirror path and report an
//! echo far *behind* the pillar (a specular ghost, a "flying point"); a beam that meets
//! glass often goes through it and returns from whatever lies beyond. In both cases the
//! ray from the sensor to the reported point crosses an object the map has seen many
//! times, and the plain inverse model (Thrun et al., *Probabilistic Robotics* §9.2) then
//! applies its full free update to every crossed cell: the pillar, the glass pane and the
//! machine body behind them are carved open by their own artefacts. The mapping
//! literature treats such returns as a known failure of the independent-beam model:
//! specular and transparent surfaces produce reflections and pass-throughs that must be
//! detected or down-weighted (Foster, Sun, Park & Kuipers, "VisAGGE: Visible angle grid
//! for glass environments", ICRA 2013; Koch, May, Nüchter et al., "Detection of specular
//! reflections in range measurements for faultless robotic SLAM", 2015/2017).
//!
//! **The rule.** While walking a ray, the first time it crosses a cell whose stored
//! probability is at least `threshold` *and* the ray still goes on for more than
//! `margin_cells` cells after it, the ray is judged a probable pass-through: that cell,
//! and every later cell of the ray the map has observed, receive only `weight` × the
//! miss update (in log-odds) instead of the full one, until the ray reaches a cell the map
//! holds as free (below the free threshold): it has come out into known free space (the
//! room beyond a corner it clipped, beyond a door that opened), and from there it is a
//! plain ray again. The cells before the confident one, and every ray that ends within the
//! margin (a beam that grazes a wall and ends, with range noise, a cell or two behind an
//! occupied cell of that same wall), are updated exactly as before.
//!
//! Cells behind the confident cell that the map has **never observed** get no evidence
//! from such a ray at all: whatever lies behind a known obstacle was reached only through
//! it, so the ray says nothing credible about space no other ray has seen. This keeps the
//! inside of a steel pillar or a machine body, which no beam can see, from being carved
//! open by the ghosts that cross it, and stops ghost rays from drawing free space outside
//! the hall's walls. Hits are applied as before; one whose ray is still behind a confident
//! cell at its end is counted (`InsertStats::ghost_hits`): dropping them would also drop
//! real walls seen past a clipped corner into unexplored space (3–8 % of the walls of the
//! corrected CARMEN logs, measured).
//!
//! **Why it keeps the map updatable.** The rule only slows free evidence down; it never
//! stops it. A cell held at the upper clamp (OctoMap's clamping, Hornung et al. 2013
//! §III-C, is the general mechanism that bounds how much evidence a cell can hold) that
//! is crossed by misses only — a door that really opened — first loses
//! `weight · |l_miss|` per observation until it drops below `threshold`, then the full
//! `|l_miss|`: it leaves the occupied state after
//! `⌈(l_max − l_threshold) / (weight·|l_miss|)⌉ + ⌈(l_threshold − l_occupied) / |l_miss|⌉`
//! observations at most (12 with the defaults, against 8 without the rule). A pillar is
//! different: some beams keep hitting it, each hit puts it back at the clamp, and with
//! the rule the few ghost rays between two hits no longer wear it down below the
//! occupied threshold.
//!
//! **Measured** (docs/BENCHMARKS.md): on the simulated production line with true poses the
//! rule halves the pillar and machine cells left free (2.75 % → 1.35 %; machines 1.55 % →
//! 0.20 %), keeps the glass fence (68 % → 86 % of its cells occupied) and raises the F1 of
//! occupied cells (0.402 → 0.415); on the Intel and Freiburg 079 logs every cell OctoMap
//! holds occupied stays occupied. Its cost is one comparison per crossed cell.
//!
//! **Where it lives.** In the map's [`OccupancyParams`](super::OccupancyParams)
//! (`[map.pass_through]`), not in a sensor's evidence: it is a rule about how the map
//! weighs new evidence against what it already holds, like clamping, and needs the
//! map's thresholds; the engine hands the grid only [`RangeData`](crate::measurement::RangeData).
//! It is off in `OccupancyParams::default()` (the plain model) and on in a configured map.
//!
//! **Defaults** (`threshold` 0.95, `weight` 0.25, `margin_cells` 3). 0.95 needs more than
//! one hit from the prior (one hit with `p_occ = 0.9` gives 0.9, two reach the 0.97
//! clamp), so a single stray return never shields anything. 0.25 keeps a quarter of the
//! evidence, so an opened door still clears in about 1.5 times the scans. Three cells
//! (15 cm at 5 cm) cover range noise and a wall's thickness. `weight = 1` switches the
//! rule off, and the map is then bit for bit the map without it.

use serde::{Deserialize, Serialize};

/// Parameters of the pass-through rule (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PassThroughParams {
    /// A crossed cell with at least this probability is confidently occupied.
    pub threshold: f64,
    /// Share of the miss update (in log-odds) applied from such a cell to the ray's end;
    /// within `[0, 1]`, `1` switches the rule off.
    pub weight: f64,
    /// The rule applies only when the ray goes on for more than this many cells after
    /// the confidently occupied cell.
    pub margin_cells: u32,
}

impl PassThroughParams {
    /// The rule switched off: every miss at full weight.
    pub const OFF: PassThroughParams = PassThroughParams { threshold: 0.95, weight: 1.0, margin_cells: 3 };

    /// Whether the rule changes nothing (`weight >= 1`).
    pub fn is_off(&self) -> bool {
        self.weight >= 1.0
    }
}

impl Default for PassThroughParams {
    fn default() -> Self {
        Self { threshold: 0.95, weight: 0.25, margin_cells: 3 }
    }
}

#[cfg(test)]
mod tests;
