//! The layers a fusion map carries beside occupancy, and the per-cell updates that write
//! them.
//!
//! * **Semantic** ([`semantic`](super::semantic)): per cell, Dirichlet evidence counts
//!   over the configured classes, written by the semantic sensor only (design document
//!   §2.2: semantic evidence from the semantic sensor).
//! * **Dynamic** ([`dynamic`](super::dynamic)): log-odds of "a moving object is here",
//!   decaying back to unknown with a half-life, with each cell's last-update stamp
//!   (§2.4: dynamic objects in their own layer).
//! * **Correlation group** ([`correlated`](super::correlated)): scratch state that merges
//!   the occupancy evidence of correlated observations into one equivalent observation
//!   (§2.4: correlated observations must not be counted as independent).
//!
//! Each block is allocated on a tile's first write of that layer, so a lidar-only map
//! pays three pointers per tile.

use super::correlated::GroupBlock;
use super::dynamic::DynamicBlock;
use super::{ExtraLayers, LayeredGrid, TILE_CELLS};

/// The extra layers of a fusion map (see the module docs).
#[derive(Default)]
pub struct FusionLayers {
    /// Semantic evidence counts, `TILE_CELLS × classes`, cell-major (`offset · k + class`).
    pub(crate) semantic: Option<Box<[f32]>>,
    /// The dynamic-object layer.
    pub(crate) dynamic: Option<Box<DynamicBlock>>,
    /// Correlation-group scratch state.
    pub(crate) group: Option<Box<GroupBlock>>,
}

impl ExtraLayers for FusionLayers {
    #[inline(always)]
    fn empty() -> Self {
        Self { semantic: None, dynamic: None, group: None }
    }
}

impl FusionLayers {
    /// The semantic counts of the cell at `offset` for a table of `k` classes, `None` when
    /// the tile holds no semantic evidence.
    #[inline]
    pub fn semantic_counts(&self, offset: usize, k: usize) -> Option<&[f32]> {
        let b = self.semantic.as_deref()?;
        (b.len() == TILE_CELLS * k).then(|| &b[offset * k..(offset + 1) * k])
    }

    /// Adds `votes` (one per class) to the semantic counts of the cell at `offset`.
    #[inline]
    pub fn add_semantic(&mut self, offset: usize, votes: &[f32]) {
        let k = votes.len();
        let b = self.semantic.get_or_insert_with(|| vec![0.0; TILE_CELLS * k].into_boxed_slice());
        debug_assert_eq!(b.len(), TILE_CELLS * k, "one class table per map");
        if b.len() != TILE_CELLS * k {
            return;
        }
        for (c, v) in b[offset * k..(offset + 1) * k].iter_mut().zip(votes) {
            *c += v;
        }
    }

    /// The dynamic layer's block, if written.
    pub fn dynamic(&self) -> Option<&DynamicBlock> {
        self.dynamic.as_deref()
    }
}

/// A map with occupancy and the fusion layers: what the fusion engine writes.
pub type FusionGrid = LayeredGrid<FusionLayers>;
