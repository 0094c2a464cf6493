//! Transforms between any two frames of the tree, at a stamp.
//!
//! `target_from_source = (ancestor_from_target)⁻¹ ∘ ancestor_from_source`, where the
//! ancestor is the lowest frame above both and each `ancestor_from_x` composes the edges
//! from `x` up to it (the walk tf2's `BufferCore::walkToTopParent` makes).

use super::samples::Miss;
use super::tree::{Edge, EdgeData};
use super::{FrameTree, LookupError};
use crate::geometry::Pose3;
use crate::time::Stamp;

/// The edges from two frames up to their lowest common ancestor.
struct Chain {
    /// Edges from the source upwards.
    source_up: Vec<usize>,
    /// Edges from the target upwards.
    target_up: Vec<usize>,
}

fn seconds(ns: i128) -> f64 {
    ns as f64 * 1e-9
}

impl FrameTree {
    /// `target_from_source` at `stamp`: maps points in `source` into `target`. Dynamic
    /// edges are interpolated between the samples around the stamp (linear translation,
    /// slerp rotation), static edges hold at every stamp. A stamp outside an edge's
    /// samples, or inside a gap longer than [`super::FrameTreeLimits::max_gap_s`] (and
    /// not bridged), is an error: never an extrapolation.
    pub fn lookup(&self, target: &str, source: &str, stamp: Stamp) -> Result<Pose3, LookupError> {
        self.resolve(target, source, |edge| self.edge_at(edge, stamp))
    }

    /// `target_from_source` through static edges only: the mounting of one sensor on
    /// another, known before any `/tf` arrives. A dynamic edge on the way is an error.
    pub fn lookup_static(&self, target: &str, source: &str) -> Result<Pose3, LookupError> {
        self.resolve(target, source, |edge| match &edge.data {
            EdgeData::Static(pose) => Ok(*pose),
            EdgeData::Dynamic(_) => {
                Err(self.edge_error(edge, |parent, child| LookupError::DynamicEdge { parent, child }))
            }
        })
    }

    /// The latest stamp at which every dynamic edge between the two frames has data
    /// (tf2's `getLatestCommonTime`): the earliest of their last samples. `None` when the
    /// chain is all static, so any stamp will do. Interpolation at this stamp can still
    /// meet a gap.
    pub fn latest_common_stamp(&self, target: &str, source: &str) -> Result<Option<Stamp>, LookupError> {
        let chain = self.chain(target, source)?;
        let mut window: Option<(Stamp, Stamp)> = None;
        for &e in chain.source_up.iter().chain(&chain.target_up) {
            if let EdgeData::Dynamic(samples) = &self.edges[e].data {
                let (first, last) = samples.span();
                window = Some(window.map_or((first, last), |(lo, hi)| (lo.max(first), hi.min(last))));
            }
        }
        match window {
            Some((lo, hi)) if lo > hi => {
                Err(LookupError::NoCommonTime { target_frame: target.to_owned(), source_frame: source.to_owned() })
            }
            w => Ok(w.map(|(_, hi)| hi)),
        }
    }

    /// Composes the chain between two frames with `edge_pose` giving each edge's
    /// `parent_from_child`.
    fn resolve(
        &self,
        target: &str,
        source: &str,
        edge_pose: impl Fn(&Edge) -> Result<Pose3, LookupError>,
    ) -> Result<Pose3, LookupError> {
        let chain = self.chain(target, source)?;
        let up = |edges: &[usize]| -> Result<Pose3, LookupError> {
            let mut ancestor_from_x = Pose3::IDENTITY;
            for &e in edges {
                ancestor_from_x = edge_pose(&self.edges[e])?.compose(&ancestor_from_x);
            }
            Ok(ancestor_from_x)
        };
        let ancestor_from_source = up(&chain.source_up)?;
        let ancestor_from_target = up(&chain.target_up)?;
        Ok(ancestor_from_target.inverse().compose(&ancestor_from_source))
    }

    /// The edges from each frame up to the lowest common ancestor.
    fn chain(&self, target: &str, source: &str) -> Result<Chain, LookupError> {
        let known = |frame: &str| self.id(frame).ok_or_else(|| LookupError::UnknownFrame { frame: frame.to_owned() });
        let (t, s) = (known(target)?, known(source)?);
        // Frames from the source up to its root (trees are shallow: a linear scan is fine).
        let mut source_frames = vec![s];
        while let Some(e) = self.parent_edge[source_frames[source_frames.len() - 1]] {
            source_frames.push(self.edges[e].parent);
        }
        let mut target_up = Vec::new();
        let mut f = t;
        loop {
            if let Some(k) = source_frames.iter().position(|&x| x == f) {
                let source_up = source_frames[..k].iter().filter_map(|&x| self.parent_edge[x]).collect();
                return Ok(Chain { source_up, target_up });
            }
            match self.parent_edge[f] {
                Some(e) => {
                    target_up.push(e);
                    f = self.edges[e].parent;
                }
                None => {
                    return Err(LookupError::NotConnected {
                        target_frame: target.to_owned(),
                        source_frame: source.to_owned(),
                        target_root: self.names[f].clone(),
                        source_root: self.names[source_frames[source_frames.len() - 1]].clone(),
                    })
                }
            }
        }
    }

    /// `parent_from_child` of one edge at a stamp.
    fn edge_at(&self, edge: &Edge, stamp: Stamp) -> Result<Pose3, LookupError> {
        match &edge.data {
            EdgeData::Static(pose) => Ok(*pose),
            EdgeData::Dynamic(samples) => samples.at(stamp, &self.gaps).map_err(|miss| {
                self.edge_error(edge, |parent, child| match miss {
                    Miss::Before(ns) => LookupError::BeforeSamples { parent, child, by_s: seconds(ns) },
                    Miss::After(ns) => LookupError::AfterSamples { parent, child, by_s: seconds(ns) },
                    Miss::Gap(ns) => {
                        LookupError::Gap { parent, child, gap_s: seconds(ns), limit_s: self.limits.max_gap_s }
                    }
                })
            }),
        }
    }

    fn edge_error(&self, edge: &Edge, make: impl FnOnce(String, String) -> LookupError) -> LookupError {
        make(self.names[edge.parent].clone(), self.names[edge.child].clone())
    }
}
