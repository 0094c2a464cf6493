//! What adding a transform did, and why a transform or a lookup was refused.
//!
//! Every refusal is a distinct variant so that a reader of a log can count each kind
//! (see [`super::Rejections`]); none of them is a panic.

use crate::time::Stamp;
use serde::Serialize;

/// Whether an edge holds one transform valid at all times (`/tf_static`) or stamped
/// samples (`/tf`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EdgeKind {
    /// One transform, valid at every stamp.
    Static,
    /// Stamped samples, interpolated between.
    Dynamic,
}

impl std::fmt::Display for EdgeKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            EdgeKind::Static => "static",
            EdgeKind::Dynamic => "dynamic",
        })
    }
}

/// What [`super::FrameTree::add_static`] or [`super::FrameTree::add_dynamic`] did with an
/// accepted transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AddOutcome {
    /// The first transform between this parent and child: a new edge.
    NewEdge,
    /// A dynamic sample later than every sample the edge held.
    Appended,
    /// A dynamic sample older than the edge's latest one: kept, inserted in stamp order
    /// (bags interleave `/tf` from several publishers, so this is common and harmless).
    InsertedOutOfOrder,
    /// The same value was already held (a static transform given again, as every
    /// latched `/tf_static` re-publication does, or a dynamic sample repeated at its
    /// stamp): nothing changed.
    IdenticalDuplicate,
}

/// Why a transform was refused. Nothing in the tree changed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// A frame name is empty (also after stripping one leading `/`).
    #[error("frame name {name:?} is empty")]
    InvalidName {
        /// The name as given.
        name: String,
    },
    /// A translation or rotation component is NaN or infinite.
    #[error("transform {parent} → {child} has a non-finite translation or rotation")]
    NotFinite {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
    },
    /// The quaternion is zero: it is no rotation at all.
    #[error("transform {parent} → {child} has a zero quaternion")]
    ZeroQuaternion {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
    },
    /// The quaternion is too far from unit length to be a rotation written with rounding
    /// errors (tf2 refuses these as well rather than guess what was meant).
    #[error(
        "transform {parent} → {child}: quaternion has squared norm {norm_squared:.6}, not within {tolerance} of 1"
    )]
    NotUnitQuaternion {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
        /// `x² + y² + z² + w²` as given.
        norm_squared: f64,
        /// The accepted `|‖q‖² − 1|`.
        tolerance: f64,
    },
    /// The child already hangs below another parent: a TF tree gives each frame one parent.
    #[error("frame {child} already has parent {parent}; refused a second parent {rejected_parent}")]
    TwoParents {
        /// The child frame.
        child: String,
        /// Its parent, kept.
        parent: String,
        /// The parent refused.
        rejected_parent: String,
    },
    /// The edge would close a loop: the child is the parent itself or one of its ancestors.
    #[error("edge {parent} → {child} would close the loop {}", cycle.join(" → "))]
    Loop {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
        /// The loop, from the child down to the parent and back to the child.
        cycle: Vec<String>,
    },
    /// The edge exists with the other kind (a `/tf` edge that is also on `/tf_static`, or
    /// the reverse): its transform would depend on which topic came first.
    #[error("edge {parent} → {child} is {existing}; refused as {attempted}")]
    KindClash {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
        /// The kind the edge has, kept.
        existing: EdgeKind,
        /// The kind refused.
        attempted: EdgeKind,
    },
    /// A static transform given again with a different value; the first is kept.
    #[error("static {parent} → {child} given again {translation_m:.6} m / {rotation_deg:.4}° away from the first; first kept")]
    ConflictingStatic {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
        /// Distance between the two translations, metres.
        translation_m: f64,
        /// Angle between the two rotations, degrees.
        rotation_deg: f64,
    },
    /// Two different dynamic samples of one edge at the same stamp; the first is kept.
    #[error("two samples of {parent} → {child} at stamp {} ns differ by {translation_m:.6} m / {rotation_deg:.4}°; first kept", stamp.0)]
    ConflictingSample {
        /// Parent frame.
        parent: String,
        /// Child frame.
        child: String,
        /// The shared stamp.
        stamp: Stamp,
        /// Distance between the two translations, metres.
        translation_m: f64,
        /// Angle between the two rotations, degrees.
        rotation_deg: f64,
    },
}

/// Why a transform between two frames cannot be given at a stamp. Like tf2's
/// `ExtrapolationException`, a stamp outside an edge's samples is an error, never a guess.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LookupError {
    /// No transform mentions this frame.
    #[error("unknown frame {frame:?}")]
    UnknownFrame {
        /// The name asked for.
        frame: String,
    },
    /// The two frames are in different trees.
    #[error("frames {target_frame} and {source_frame} are not connected (roots {target_root} and {source_root})")]
    NotConnected {
        /// Target frame.
        target_frame: String,
        /// Source frame (not `source`: thiserror reserves that name for a cause).
        source_frame: String,
        /// The root above the target.
        target_root: String,
        /// The root above the source.
        source_root: String,
    },
    /// The stamp is before the first sample of a dynamic edge on the path.
    #[error("{by_s:.6} s before the first sample of {parent} → {child}")]
    BeforeSamples {
        /// Parent frame of the edge.
        parent: String,
        /// Child frame of the edge.
        child: String,
        /// How far before, seconds.
        by_s: f64,
    },
    /// The stamp is after the last sample of a dynamic edge on the path.
    #[error("{by_s:.6} s after the last sample of {parent} → {child}")]
    AfterSamples {
        /// Parent frame of the edge.
        parent: String,
        /// Child frame of the edge.
        child: String,
        /// How far after, seconds.
        by_s: f64,
    },
    /// The stamp falls between two samples of a dynamic edge further apart than allowed.
    #[error("inside a {gap_s:.6} s gap of {parent} → {child} (limit {limit_s:.6} s)")]
    Gap {
        /// Parent frame of the edge.
        parent: String,
        /// Child frame of the edge.
        child: String,
        /// The gap's length, seconds.
        gap_s: f64,
        /// The allowed gap, seconds.
        limit_s: f64,
    },
    /// A static-only lookup met a dynamic edge.
    #[error("{parent} → {child} is dynamic; a static lookup needs a static chain")]
    DynamicEdge {
        /// Parent frame of the edge.
        parent: String,
        /// Child frame of the edge.
        child: String,
    },
    /// No stamp lies inside the samples of every dynamic edge on the path.
    #[error("the dynamic edges between {target_frame} and {source_frame} share no stamp")]
    NoCommonTime {
        /// Target frame.
        target_frame: String,
        /// Source frame.
        source_frame: String,
    },
}
