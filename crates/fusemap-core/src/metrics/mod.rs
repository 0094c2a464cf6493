//! Map quality: entropy (the design document's §5.1 fusion gain) and agreement with
//! ground truth; trajectory accuracy by the SLAM benchmark's relations.

mod entropy;
mod motion_agreement;
mod relations;
mod scores;
mod semantic;
mod trajectory;
mod validation;

pub use entropy::{binary_entropy, entropy_where, map_entropy, sparse_entropy, EntropyReport};
pub(crate) use motion_agreement::median_of_sorted;
pub use motion_agreement::{motion_agreement, MotionAgreement};
pub use relations::{
    at_relation_stamps, parse_relations, relation_errors, score_relations, score_trajectory, Relation,
    RelationMatching, RelationScore, RelationsError, PLANAR_TOLERANCE,
};
pub use scores::{Confusion, TolerantScore};
pub use semantic::{ClassAccuracy, SemanticAccuracy};
pub use trajectory::{
    absolute_trajectory_error, consecutive_relations, revisit_relations, score_index_relations, IndexRelation,
    RevisitRule,
};
pub use validation::{judge, Judgement, MapFigures, MapRole, SensorHits, Verdict};
