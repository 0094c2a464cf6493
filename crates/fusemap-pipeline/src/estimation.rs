//! The estimator's inputs from log messages.

use crate::recording::Inventory;
use crate::sensors::Bound;
use crate::track::ChosenTrack;
use crate::PipelineError;
use fusemap_core::config::Plan;

/// Builds the estimator's track.
pub fn estimator_track(_plan: &Plan, _inv: &Inventory, _bound: &Bound) -> Result<ChosenTrack, PipelineError> {
    Err(PipelineError::Refused("the estimator is not available".into()))
}
