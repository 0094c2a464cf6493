//! Correlated observations merged into one equivalent observation before the Bayesian
//! update.
//!
//! The log-odds update `l ← l + l_meas − l₀` assumes each measurement is independent
//! given the map (Thrun et al., *Probabilistic Robotics*, §9.2). A camera frame and a
//! lidar scan taken within a few milliseconds of each other, or two outputs of one
//! pre-processing step, are not: adding both counts one look at the world twice and
//! inflates confidence (design document §2.4). Observations of one *correlation group*
//! (an id the engine assigns) are therefore merged per cell: every member's evidence for
//! the cell is combined by the [`MergeRule`], and the cell carries the merged evidence
//! once — each member changes it by the difference between the merged evidence and what
//! the group has already applied there, so evidence another sensor wrote in between is
//! kept.
//!
//! Limit: the scratch entry of a cell belongs to one group at a time; two configured
//! groups whose members interleave on the same cell within their windows restart each
//! other's merge there.
//!
//! * [`MergeRule::Max`] (the default) keeps the evidence of largest magnitude: the merged
//!   observation is as informative as the most informative member, never more. It is
//!   the choice of covariance intersection (Julier & Uhlmann 1997) at its extreme weight,
//!   which is consistent whatever the unknown correlation is, and it lets the sensor that
//!   is confident about a cell (the lidar's hit on a wall, the camera's obstacle on a glass
//!   pane the lidar sees through) speak for the group instead of being diluted.
//! * [`MergeRule::Mean`] averages the members' evidence: the fully correlated case, for
//!   sensors that are two readings of the same measurement.
//!
//! The members' evidence is still computed and counted per member; only the stored value
//! is the merged one. The scratch block is allocated on a tile's first grouped update.

use super::{LogOddsTable, TILE_CELLS};

/// How the evidence of correlated observations for one cell is combined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MergeRule {
    /// The evidence of largest magnitude (see the module docs).
    #[default]
    Max,
    /// The mean of the members' evidence.
    Mean,
}

/// Per-cell scratch state of the current correlation group: one 16-byte entry per cell,
/// so a grouped update touches one cache line.
#[derive(Clone, Debug)]
pub struct GroupBlock {
    cells: [GroupCell; TILE_CELLS],
}

#[derive(Clone, Copy, Debug)]
struct GroupCell {
    /// The low 32 bits of the group that last touched the cell (0: none; groups start at
    /// 1). Two groups 2³² apart (13 years of 10 Hz groups) would share a tag.
    tag: u32,
    /// Members that reached the cell.
    count: u32,
    /// The change the group has made to the cell so far (after clamping).
    applied: f32,
    /// The combined evidence so far (the max, or the sum for the mean).
    acc: f32,
}

impl GroupBlock {
    fn empty() -> Self {
        Self { cells: [GroupCell { tag: 0, count: 0, applied: 0.0, acc: 0.0 }; TILE_CELLS] }
    }
}

/// One observation's membership of a correlation group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    /// The group's number (never 0).
    pub id: u64,
    /// How its members' evidence is combined.
    pub rule: MergeRule,
}

impl Group {
    /// Applies `delta` to `log_odds` (one cell's stored value, NaN if never observed) as
    /// this group's member: the cell ends up changed by the merged evidence once.
    #[inline]
    pub fn update(
        &self,
        block: &mut Option<Box<GroupBlock>>,
        log_odds: &mut f32,
        offset: usize,
        delta: f32,
        table: &LogOddsTable,
    ) {
        let b = block.get_or_insert_with(|| Box::new(GroupBlock::empty()));
        let c = &mut b.cells[offset];
        let tag = self.id as u32;
        let merged = if c.tag != tag {
            *c = GroupCell { tag, count: 1, applied: 0.0, acc: delta };
            delta
        } else {
            c.count = c.count.saturating_add(1);
            match self.rule {
                MergeRule::Max => {
                    if delta.abs() > c.acc.abs() {
                        c.acc = delta;
                    }
                    c.acc
                }
                MergeRule::Mean => {
                    c.acc += delta;
                    c.acc / c.count as f32
                }
            }
        };
        let before = if log_odds.is_nan() { table.prior } else { *log_odds };
        let after = table.update(before, merged - c.applied);
        c.applied += after - before;
        *log_odds = after;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::OccupancyParams;
    use proptest::prelude::*;

    fn table() -> LogOddsTable {
        LogOddsTable::new(&OccupancyParams::default())
    }

    #[test]
    fn max_keeps_the_strongest_member_and_mean_averages() {
        let t = table();
        let mut block = None;
        let mut l = f32::NAN;
        let g = Group { id: 1, rule: MergeRule::Max };
        g.update(&mut block, &mut l, 0, 2.0, &t);
        g.update(&mut block, &mut l, 0, 0.5, &t);
        assert_eq!(l, 2.0);
        g.update(&mut block, &mut l, 0, -2.5, &t);
        assert_eq!(l, (-2.5f32).max(t.min));
        // A new group starts from the merged value.
        let g2 = Group { id: 2, rule: MergeRule::Mean };
        let before = l;
        g2.update(&mut block, &mut l, 0, 1.0, &t);
        g2.update(&mut block, &mut l, 0, 0.0, &t);
        assert!((l - t.update(before, 0.5)).abs() < 1e-6);
    }

    #[test]
    fn evidence_written_between_two_members_is_kept() {
        let t = table();
        let mut block = None;
        let mut l = 0.0f32;
        let g = Group { id: 3, rule: MergeRule::Max };
        g.update(&mut block, &mut l, 0, 0.5, &t);
        // Another, ungrouped sensor writes the cell.
        l = t.update(l, -0.4);
        g.update(&mut block, &mut l, 0, 0.8, &t);
        assert!((l - (0.8 - 0.4)).abs() < 1e-6, "{l}");
    }

    proptest! {
        /// Merged evidence is never stronger than its strongest member, whatever the
        /// order: a group of n copies of one observation is that observation once.
        #[test]
        fn a_group_is_never_more_confident_than_its_strongest_member(
            start in -3.0f32..3.0, deltas in prop::collection::vec(-2.5f32..2.5, 1..6), mean in any::<bool>()
        ) {
            let t = table();
            let rule = if mean { MergeRule::Mean } else { MergeRule::Max };
            let g = Group { id: 9, rule };
            let mut block = None;
            let mut l = t.update(start, 0.0);
            let base = l;
            for &d in &deltas {
                g.update(&mut block, &mut l, 5, d, &t);
            }
            let strongest = deltas.iter().fold(0.0f32, |m, d| if d.abs() > m.abs() { *d } else { m });
            prop_assert!((l - base).abs() <= strongest.abs() + 1e-5);
            let copies = vec![deltas[0]; deltas.len()];
            let mut l2 = base;
            let mut block2 = None;
            for &d in &copies {
                g.update(&mut block2, &mut l2, 5, d, &t);
            }
            prop_assert!((l2 - t.update(base, deltas[0])).abs() < 1e-6);
        }
    }
}
