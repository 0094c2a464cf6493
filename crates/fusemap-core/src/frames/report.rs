//! What a frame tree holds and what it refused, as a serialisable report: the counts a
//! `fusemap doctor` run needs to say "your bag publishes base_link → laser twice with
//! different values" instead of mapping with whichever came first.

use super::tree::{EdgeData, FrameTreeLimits};
use super::{AddOutcome, EdgeKind, FrameError, FrameTree};
use crate::time::Stamp;
use serde::Serialize;
use std::collections::BTreeMap;

/// Accepted transforms, by what they did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Acceptances {
    /// Transforms that created an edge.
    pub new_edges: u64,
    /// Dynamic samples appended after an edge's latest.
    pub appended: u64,
    /// Dynamic samples older than an edge's latest, inserted in order.
    pub inserted_out_of_order: u64,
    /// Static transforms repeating the held value.
    pub identical_static_duplicates: u64,
    /// Dynamic samples repeating the held value at their stamp.
    pub identical_dynamic_duplicates: u64,
}

/// Refused transforms, one counter per [`FrameError`] variant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Rejections {
    /// [`FrameError::InvalidName`].
    pub invalid_name: u64,
    /// [`FrameError::NotFinite`].
    pub not_finite: u64,
    /// [`FrameError::ZeroQuaternion`].
    pub zero_quaternion: u64,
    /// [`FrameError::NotUnitQuaternion`].
    pub not_unit_quaternion: u64,
    /// [`FrameError::TwoParents`].
    pub two_parents: u64,
    /// [`FrameError::Loop`].
    pub loops: u64,
    /// [`FrameError::KindClash`].
    pub kind_clash: u64,
    /// [`FrameError::ConflictingStatic`].
    pub conflicting_static: u64,
    /// [`FrameError::ConflictingSample`].
    pub conflicting_sample: u64,
}

impl Rejections {
    /// All refusals.
    pub fn total(&self) -> u64 {
        self.invalid_name
            + self.not_finite
            + self.zero_quaternion
            + self.not_unit_quaternion
            + self.two_parents
            + self.loops
            + self.kind_clash
            + self.conflicting_static
            + self.conflicting_sample
    }
}

/// Conflicting duplicates of one edge (the first value was kept).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConflictEntry {
    /// Parent frame.
    pub parent: String,
    /// Child frame.
    pub child: String,
    /// The edge's kind.
    pub kind: EdgeKind,
    /// Refused values.
    pub count: u64,
    /// Largest distance between a refused translation and the kept one, metres.
    pub max_translation_m: f64,
    /// Largest angle between a refused rotation and the kept one, degrees.
    pub max_rotation_deg: f64,
}

/// Edges refused because they would close a loop.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LoopEntry {
    /// Parent frame of the refused edge.
    pub parent: String,
    /// Child frame of the refused edge.
    pub child: String,
    /// The loop it would close, the first time it was refused.
    pub cycle: Vec<String>,
    /// Times refused.
    pub count: u64,
}

/// Edges refused because the child already had another parent.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SecondParentEntry {
    /// The child frame.
    pub child: String,
    /// Its parent, kept.
    pub parent: String,
    /// The parent refused.
    pub rejected_parent: String,
    /// Times refused.
    pub count: u64,
}

/// Transforms refused because their edge exists with the other kind.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KindClashEntry {
    /// Parent frame.
    pub parent: String,
    /// Child frame.
    pub child: String,
    /// The kind the edge has.
    pub existing: EdgeKind,
    /// Times refused.
    pub count: u64,
}

/// One frame of the tree.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameEntry {
    /// Its name.
    pub name: String,
    /// Its parent, `None` for a root.
    pub parent: Option<String>,
    /// Edges between it and its root.
    pub depth: usize,
}

/// One edge of the tree.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EdgeEntry {
    /// Parent frame.
    pub parent: String,
    /// Child frame.
    pub child: String,
    /// Static or dynamic.
    pub kind: EdgeKind,
    /// Samples held (1 for a static edge).
    pub samples: usize,
    /// First and last sample stamp of a dynamic edge.
    pub span: Option<(Stamp, Stamp)>,
    /// Longest interval between consecutive samples of a dynamic edge, seconds.
    pub longest_gap_s: Option<f64>,
    /// Samples that arrived older than the edge's latest.
    pub out_of_order: u64,
    /// Repeats of a held value.
    pub identical_duplicates: u64,
    /// Different values refused for a held stamp (or, static, at all).
    pub conflicts: u64,
}

/// Everything a [`FrameTree`] holds and refused, for humans and JSON.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameReport {
    /// The limits applied.
    pub limits: FrameTreeLimits,
    /// Frames, depth-first from each root, children by name.
    pub frames: Vec<FrameEntry>,
    /// Frames without a parent (one for a connected tree).
    pub roots: Vec<String>,
    /// Edges, in the order of [`FrameReport::frames`] (by child).
    pub edges: Vec<EdgeEntry>,
    /// Accepted transforms by outcome.
    pub accepted: Acceptances,
    /// Refused transforms by reason.
    pub rejected: Rejections,
    /// Conflicting duplicates by edge.
    pub conflicts: Vec<ConflictEntry>,
    /// Refused loops by edge.
    pub loops: Vec<LoopEntry>,
    /// Refused second parents by edge.
    pub second_parents: Vec<SecondParentEntry>,
    /// Refused kind changes by edge.
    pub kind_clashes: Vec<KindClashEntry>,
}

type Pair = (String, String);

/// Running counts, kept as transforms arrive; grouped by edge so a bag repeating one
/// fault a million times gives one line with a count.
#[derive(Clone, Debug, Default)]
pub(super) struct Tally {
    accepted: Acceptances,
    rejected: Rejections,
    conflicts: BTreeMap<(Pair, EdgeKind), ConflictEntry>,
    loops: BTreeMap<Pair, LoopEntry>,
    second_parents: BTreeMap<(Pair, String), SecondParentEntry>,
    kind_clashes: BTreeMap<Pair, KindClashEntry>,
}

impl Tally {
    pub(super) fn record(&mut self, kind: EdgeKind, result: &Result<AddOutcome, FrameError>) {
        let a = &mut self.accepted;
        let r = &mut self.rejected;
        match result {
            Ok(AddOutcome::NewEdge) => a.new_edges += 1,
            Ok(AddOutcome::Appended) => a.appended += 1,
            Ok(AddOutcome::InsertedOutOfOrder) => a.inserted_out_of_order += 1,
            Ok(AddOutcome::IdenticalDuplicate) => match kind {
                EdgeKind::Static => a.identical_static_duplicates += 1,
                EdgeKind::Dynamic => a.identical_dynamic_duplicates += 1,
            },
            Err(FrameError::InvalidName { .. }) => r.invalid_name += 1,
            Err(FrameError::NotFinite { .. }) => r.not_finite += 1,
            Err(FrameError::ZeroQuaternion { .. }) => r.zero_quaternion += 1,
            Err(FrameError::NotUnitQuaternion { .. }) => r.not_unit_quaternion += 1,
            Err(FrameError::TwoParents { child, parent, rejected_parent }) => {
                r.two_parents += 1;
                let key = ((child.clone(), parent.clone()), rejected_parent.clone());
                self.second_parents
                    .entry(key)
                    .or_insert_with(|| SecondParentEntry {
                        child: child.clone(),
                        parent: parent.clone(),
                        rejected_parent: rejected_parent.clone(),
                        count: 0,
                    })
                    .count += 1;
            }
            Err(FrameError::Loop { parent, child, cycle }) => {
                r.loops += 1;
                self.loops
                    .entry((parent.clone(), child.clone()))
                    .or_insert_with(|| LoopEntry {
                        parent: parent.clone(),
                        child: child.clone(),
                        cycle: cycle.clone(),
                        count: 0,
                    })
                    .count += 1;
            }
            Err(FrameError::KindClash { parent, child, existing, .. }) => {
                r.kind_clash += 1;
                self.kind_clashes
                    .entry((parent.clone(), child.clone()))
                    .or_insert_with(|| KindClashEntry {
                        parent: parent.clone(),
                        child: child.clone(),
                        existing: *existing,
                        count: 0,
                    })
                    .count += 1;
            }
            Err(FrameError::ConflictingStatic { parent, child, translation_m, rotation_deg }) => {
                r.conflicting_static += 1;
                self.conflict(parent, child, EdgeKind::Static, *translation_m, *rotation_deg);
            }
            Err(FrameError::ConflictingSample { parent, child, translation_m, rotation_deg, .. }) => {
                r.conflicting_sample += 1;
                self.conflict(parent, child, EdgeKind::Dynamic, *translation_m, *rotation_deg);
            }
        }
    }

    fn conflict(&mut self, parent: &str, child: &str, kind: EdgeKind, translation_m: f64, rotation_deg: f64) {
        let entry =
            self.conflicts.entry(((parent.to_owned(), child.to_owned()), kind)).or_insert_with(|| ConflictEntry {
                parent: parent.to_owned(),
                child: child.to_owned(),
                kind,
                count: 0,
                max_translation_m: 0.0,
                max_rotation_deg: 0.0,
            });
        entry.count += 1;
        entry.max_translation_m = entry.max_translation_m.max(translation_m);
        entry.max_rotation_deg = entry.max_rotation_deg.max(rotation_deg);
    }
}

impl FrameTree {
    /// Accepted transforms so far, by outcome.
    pub fn accepted(&self) -> Acceptances {
        self.tally.accepted
    }

    /// Refused transforms so far, by reason.
    pub fn rejected(&self) -> Rejections {
        self.tally.rejected
    }

    /// The tree, its edges and every refusal, ready to print or serialise.
    pub fn report(&self) -> FrameReport {
        let n = self.names.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut roots = Vec::new();
        for f in 0..n {
            match self.parent_edge[f] {
                Some(e) => children[self.edges[e].parent].push(f),
                None => roots.push(f),
            }
        }
        for list in children.iter_mut().chain(std::iter::once(&mut roots)) {
            list.sort_by(|&a, &b| self.names[a].cmp(&self.names[b]));
        }
        let mut frames = Vec::with_capacity(n);
        let mut edges = Vec::with_capacity(self.edges.len());
        // Depth-first, iterative: (frame, depth), children pushed in reverse to pop in order.
        let mut stack: Vec<(usize, usize)> = roots.iter().rev().map(|&r| (r, 0)).collect();
        while let Some((f, depth)) = stack.pop() {
            let parent = self.parent_edge[f].map(|e| self.names[self.edges[e].parent].clone());
            frames.push(FrameEntry { name: self.names[f].clone(), parent, depth });
            if let Some(e) = self.parent_edge[f] {
                edges.push(self.edge_entry(e));
            }
            stack.extend(children[f].iter().rev().map(|&c| (c, depth + 1)));
        }
        let t = &self.tally;
        FrameReport {
            limits: self.limits,
            frames,
            roots: roots.iter().map(|&r| self.names[r].clone()).collect(),
            edges,
            accepted: t.accepted,
            rejected: t.rejected,
            conflicts: t.conflicts.values().cloned().collect(),
            loops: t.loops.values().cloned().collect(),
            second_parents: t.second_parents.values().cloned().collect(),
            kind_clashes: t.kind_clashes.values().cloned().collect(),
        }
    }

    fn edge_entry(&self, e: usize) -> EdgeEntry {
        let edge = &self.edges[e];
        let (samples, span, longest_gap_s) = match &edge.data {
            EdgeData::Static(_) => (1, None, None),
            EdgeData::Dynamic(s) => (s.len(), Some(s.span()), Some(s.longest_gap_ns() as f64 * 1e-9)),
        };
        EdgeEntry {
            parent: self.names[edge.parent].clone(),
            child: self.names[edge.child].clone(),
            kind: edge.kind(),
            samples,
            span,
            longest_gap_s,
            out_of_order: edge.out_of_order,
            identical_duplicates: edge.identical_duplicates,
            conflicts: edge.conflicts,
        }
    }
}
