//! The number checks every part of a scenario uses, each naming the field it refuses
//! ([`FieldError`]). A leaf: the scenario and the sensors' settings both use it.

use fusemap_core::field_error::FieldError;

/// `Ok` when `v` is finite and > 0.
pub(crate) fn positive(field: &str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be a finite number > 0, got {v}")))
    }
}

/// `Ok` when `v` is finite and ≥ 0.
pub(crate) fn non_negative(field: &str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be a finite number >= 0, got {v}")))
    }
}

/// `Ok` when `v` is a probability.
pub(crate) fn probability(field: &str, v: f64) -> Result<(), FieldError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must lie in [0, 1], got {v}")))
    }
}

/// `Ok` when `v` is finite.
pub(crate) fn finite(field: &str, v: f64) -> Result<(), FieldError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be finite, got {v}")))
    }
}
