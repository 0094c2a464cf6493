//! The frame tree and how transforms enter it.

use super::check;
use super::report::Tally;
use super::samples::{self, GapRule, Inserted, Samples};
use super::{AddOutcome, EdgeKind, FrameError};
use crate::geometry::Pose3;
use crate::time::Stamp;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// The tolerances a [`FrameTree`] applies.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrameTreeLimits {
    /// Longest interval between two samples of a dynamic edge that a lookup interpolates
    /// across, seconds (infinite: any). Interpolating over a long silence invents a
    /// straight-line motion the robot may not have made; the default matches the
    /// configuration's `log.max_pose_gap_s`. Zero, negative or NaN: only stamps that
    /// fall exactly on a sample are answered (unless bridged, below).
    pub max_gap_s: f64,
    /// Also interpolate across a longer gap when its two samples' translations are at most
    /// this far apart, metres (negative: never). A robot standing still makes long silent
    /// gaps with nothing to invent in them; default as `log.gap_bridge_motion_m`.
    pub bridge_motion_m: f64,
    /// … and their rotations at most this far apart, degrees (default as
    /// `log.gap_bridge_motion_deg`).
    pub bridge_motion_deg: f64,
    /// Largest accepted `|x² + y² + z² + w² − 1|` of an incoming quaternion (tf2 uses
    /// 0.01). Accepted quaternions are normalised; others are refused.
    pub quaternion_norm_tolerance: f64,
}

impl Default for FrameTreeLimits {
    fn default() -> Self {
        Self { max_gap_s: 0.5, bridge_motion_m: 0.05, bridge_motion_deg: 2.0, quaternion_norm_tolerance: 0.01 }
    }
}

/// The transform an edge holds.
#[derive(Clone, Debug)]
pub(super) enum EdgeData {
    /// `parent_from_child`, valid at all stamps.
    Static(Pose3),
    /// `parent_from_child` samples.
    Dynamic(Samples),
}

/// One parent → child edge with the counts of what happened to it.
#[derive(Clone, Debug)]
pub(super) struct Edge {
    pub(super) parent: usize,
    pub(super) child: usize,
    pub(super) data: EdgeData,
    pub(super) out_of_order: u64,
    pub(super) identical_duplicates: u64,
    pub(super) conflicts: u64,
}

impl Edge {
    pub(super) fn kind(&self) -> EdgeKind {
        match self.data {
            EdgeData::Static(_) => EdgeKind::Static,
            EdgeData::Dynamic(_) => EdgeKind::Dynamic,
        }
    }
}

/// A TF tree (REP 105: `map → odom → base_link → sensor`), built from static
/// transforms (`/tf_static`, valid at all stamps) and stamped dynamic ones (`/tf`).
///
/// Each edge holds `parent_from_child` (a `geometry_msgs/TransformStamped` with
/// `header.frame_id` = parent maps points from `child_frame_id` into the parent).
/// As in tf2, every frame has at most one parent, so the frames form a forest and the
/// transform between two frames is the chain through their lowest common ancestor.
/// Unlike tf2 nothing is dropped silently: every refused transform is a typed
/// [`FrameError`] and is counted in [`FrameTree::report`].
///
/// ```
/// use fusemap_core::frames::FrameTree;
/// use fusemap_core::geometry::Pose3;
/// use fusemap_core::time::Stamp;
/// let mut tf = FrameTree::default();
/// let level = [0.0, 0.0, 0.0, 1.0];
/// tf.add_static("base_link", "laser", Pose3::new([0.2, 0.0, 0.3], level)).unwrap();
/// tf.add_dynamic(Stamp(0), "odom", "base_link", Pose3::new([0.0, 0.0, 0.0], level)).unwrap();
/// tf.add_dynamic(Stamp(100_000_000), "odom", "base_link", Pose3::new([1.0, 0.0, 0.0], level)).unwrap();
/// let odom_from_laser = tf.lookup("odom", "laser", Stamp(50_000_000)).unwrap();
/// assert!((odom_from_laser.translation[0] - 0.7).abs() < 1e-12);
/// assert!(tf.lookup("odom", "laser", Stamp(200_000_000)).is_err()); // no extrapolation
/// ```
#[derive(Clone, Debug)]
pub struct FrameTree {
    pub(super) limits: FrameTreeLimits,
    /// The limits' gap rule in the units the samples use.
    pub(super) gaps: GapRule,
    /// Frame names by id.
    pub(super) names: Vec<String>,
    /// Frame ids by name.
    index: HashMap<String, usize>,
    /// For each frame id, the edge to its parent.
    pub(super) parent_edge: Vec<Option<usize>>,
    pub(super) edges: Vec<Edge>,
    pub(super) tally: Tally,
}

impl Default for FrameTree {
    fn default() -> Self {
        Self::new(FrameTreeLimits::default())
    }
}

impl FrameTree {
    /// An empty tree applying `limits`.
    pub fn new(limits: FrameTreeLimits) -> Self {
        let max_gap_ns = if limits.max_gap_s.is_nan() {
            0
        } else {
            // Saturating float → integer conversion: +inf becomes i128::MAX.
            (limits.max_gap_s * 1e9).max(0.0) as i128
        };
        // A NaN bridge compares false: never bridges.
        let gaps =
            GapRule { max_gap_ns, bridge_m: limits.bridge_motion_m, bridge_rad: limits.bridge_motion_deg.to_radians() };
        Self {
            limits,
            gaps,
            names: Vec::new(),
            index: HashMap::new(),
            parent_edge: Vec::new(),
            edges: Vec::new(),
            tally: Tally::default(),
        }
    }

    /// The limits in force.
    pub fn limits(&self) -> FrameTreeLimits {
        self.limits
    }

    /// Adds a static transform `parent_from_child` (from `/tf_static`).
    pub fn add_static(
        &mut self,
        parent: &str,
        child: &str,
        parent_from_child: Pose3,
    ) -> Result<AddOutcome, FrameError> {
        let result = self.add(EdgeKind::Static, Stamp::ZERO, parent, child, parent_from_child);
        self.tally.record(EdgeKind::Static, &result);
        result
    }

    /// Adds a sample of a dynamic transform `parent_from_child` at `stamp` (from `/tf`).
    /// Samples may come in any order; they are kept in stamp order.
    pub fn add_dynamic(
        &mut self,
        stamp: Stamp,
        parent: &str,
        child: &str,
        parent_from_child: Pose3,
    ) -> Result<AddOutcome, FrameError> {
        let result = self.add(EdgeKind::Dynamic, stamp, parent, child, parent_from_child);
        self.tally.record(EdgeKind::Dynamic, &result);
        result
    }

    /// True when a transform named this frame (one leading `/` ignored).
    pub fn contains(&self, frame: &str) -> bool {
        self.id(frame).is_some()
    }

    /// The frame's parent, `None` for a root or an unknown frame.
    pub fn parent(&self, frame: &str) -> Option<&str> {
        let e = self.parent_edge[self.id(frame)?]?;
        Some(&self.names[self.edges[e].parent])
    }

    /// The kind of the edge `parent → child`, if there is one.
    pub fn edge_kind(&self, parent: &str, child: &str) -> Option<EdgeKind> {
        let edge = &self.edges[self.parent_edge[self.id(child)?]?];
        (edge.parent == self.id(parent)?).then(|| edge.kind())
    }

    /// All frame names, in the order they first appeared.
    pub fn frames(&self) -> impl Iterator<Item = &str> + '_ {
        self.names.iter().map(String::as_str)
    }

    /// The id of a frame, with one leading `/` ignored.
    pub(super) fn id(&self, frame: &str) -> Option<usize> {
        self.index.get(frame.strip_prefix('/').unwrap_or(frame)).copied()
    }

    fn intern(&mut self, name: &str) -> usize {
        if let Some(&id) = self.index.get(name) {
            return id;
        }
        let id = self.names.len();
        self.names.push(name.to_owned());
        self.index.insert(name.to_owned(), id);
        self.parent_edge.push(None);
        id
    }

    fn add(
        &mut self,
        kind: EdgeKind,
        stamp: Stamp,
        parent: &str,
        child: &str,
        pose: Pose3,
    ) -> Result<AddOutcome, FrameError> {
        let parent = check::frame_name(parent)?;
        let child = check::frame_name(child)?;
        let pose = check::rigid_transform(parent, child, pose, self.limits.quaternion_norm_tolerance)?;
        let names = || (parent.to_owned(), child.to_owned());
        if parent == child {
            let (parent, child) = names();
            return Err(FrameError::Loop { cycle: vec![child.clone(), child.clone()], parent, child });
        }
        // Already cleaned: look up as they are (a second `/` stays part of the name).
        let (p, c) = (self.index.get(parent).copied(), self.index.get(child).copied());
        if let Some(e) = c.and_then(|c| self.parent_edge[c]) {
            if Some(self.edges[e].parent) != p {
                return Err(FrameError::TwoParents {
                    child: child.to_owned(),
                    parent: self.names[self.edges[e].parent].clone(),
                    rejected_parent: parent.to_owned(),
                });
            }
            return self.add_to_edge(e, kind, stamp, pose, parent, child);
        }
        if let (Some(p), Some(c)) = (p, c) {
            if let Some(cycle) = self.cycle_through(p, c) {
                let (parent, child) = names();
                return Err(FrameError::Loop { parent, child, cycle });
            }
        }
        let p = self.intern(parent);
        let c = self.intern(child);
        let data = match kind {
            EdgeKind::Static => EdgeData::Static(pose),
            EdgeKind::Dynamic => EdgeData::Dynamic(Samples::new(stamp, pose)),
        };
        self.parent_edge[c] = Some(self.edges.len());
        self.edges.push(Edge { parent: p, child: c, data, out_of_order: 0, identical_duplicates: 0, conflicts: 0 });
        Ok(AddOutcome::NewEdge)
    }

    /// A transform for an edge that already exists between these two frames.
    fn add_to_edge(
        &mut self,
        e: usize,
        kind: EdgeKind,
        stamp: Stamp,
        pose: Pose3,
        parent: &str,
        child: &str,
    ) -> Result<AddOutcome, FrameError> {
        let edge = &mut self.edges[e];
        let names = || (parent.to_owned(), child.to_owned());
        match (&mut edge.data, kind) {
            (EdgeData::Static(held), EdgeKind::Static) => {
                if samples::same(held, &pose) {
                    edge.identical_duplicates += 1;
                    return Ok(AddOutcome::IdenticalDuplicate);
                }
                let (translation_m, rotation) = samples::difference(held, &pose);
                edge.conflicts += 1;
                let (parent, child) = names();
                Err(FrameError::ConflictingStatic { parent, child, translation_m, rotation_deg: rotation.to_degrees() })
            }
            (EdgeData::Dynamic(held), EdgeKind::Dynamic) => match held.insert(stamp, pose) {
                Inserted::Appended => Ok(AddOutcome::Appended),
                Inserted::OutOfOrder => {
                    edge.out_of_order += 1;
                    Ok(AddOutcome::InsertedOutOfOrder)
                }
                Inserted::Identical => {
                    edge.identical_duplicates += 1;
                    Ok(AddOutcome::IdenticalDuplicate)
                }
                Inserted::Conflict(translation_m, rotation) => {
                    edge.conflicts += 1;
                    let (parent, child) = names();
                    let rotation_deg = rotation.to_degrees();
                    Err(FrameError::ConflictingSample { parent, child, stamp, translation_m, rotation_deg })
                }
            },
            (data, attempted) => {
                let existing = match data {
                    EdgeData::Static(_) => EdgeKind::Static,
                    EdgeData::Dynamic(_) => EdgeKind::Dynamic,
                };
                let (parent, child) = names();
                Err(FrameError::KindClash { parent, child, existing, attempted })
            }
        }
    }

    /// When `c` is `p` or one of its ancestors, the loop an edge `p → c` would close:
    /// `c → … → p → c`.
    fn cycle_through(&self, p: usize, c: usize) -> Option<Vec<String>> {
        let mut up = vec![p];
        let mut f = p;
        while f != c {
            f = self.edges[self.parent_edge[f]?].parent;
            up.push(f);
        }
        let mut cycle: Vec<String> = up.iter().rev().map(|&f| self.names[f].clone()).collect();
        cycle.push(self.names[c].clone());
        Some(cycle)
    }
}
