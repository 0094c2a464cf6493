//! One error type for every check of parameters a user writes: a config file, a scenario
//! file, a sensor's filter table, the estimator's settings. It names the field as its
//! TOML path (`map.prior`, `sensor[2].filters.shadow.window`, `gnss.rate_hz`) apart from
//! what is wrong with it, so the file readers in `fusemap-io` can point at the line the
//! field is written on without parsing the message.

/// A parameter that is not allowed, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct FieldError {
    /// The field, as a TOML path (`map.prior`, `lidar[0].mount`).
    pub field: String,
    /// What is wrong with it.
    pub message: String,
}

impl FieldError {
    /// `field` is wrong: `message`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self { field: field.into(), message: message.into() }
    }

    /// The same error for a field that sits below `table` (`filters` + `shadow.window`
    /// gives `filters.shadow.window`).
    pub fn within(self, table: &str) -> Self {
        Self { field: format!("{table}.{}", self.field), message: self.message }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_error_names_its_path() {
        let e = FieldError::new("shadow.window", "must be at least 1 beam").within("sensor[2].filters");
        assert_eq!(e.field, "sensor[2].filters.shadow.window");
        assert_eq!(e.to_string(), "sensor[2].filters.shadow.window: must be at least 1 beam");
    }
}
