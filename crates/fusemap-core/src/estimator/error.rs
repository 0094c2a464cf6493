//! Why no estimate could be made.

/// Why [`estimate`](super::estimate) refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// The configuration is invalid (the message names the field).
    #[error("invalid estimator configuration: {0}")]
    Config(String),
    /// No inputs at all.
    #[error("the estimator received no inputs")]
    NoInputs,
    /// Translation needs wheel odometry; a gyro and fixes alone are refused rather than
    /// guessed with a constant-velocity model.
    #[error(
        "no usable wheel odometry ({odometry} messages, {gyro} gyro samples, {fixes} fixes): \
         the estimator predicts translation from odometry"
    )]
    NoOdometry {
        /// Odometry messages received (all unusable).
        odometry: usize,
        /// Gyro samples received.
        gyro: usize,
        /// Position fixes received.
        fixes: usize,
    },
    /// Absolute positions exist but the heading could never be initialised: no absolute
    /// heading or pose, and the robot never drove far enough between good fixes.
    #[error(
        "the heading never became observable: no absolute heading, and the good fixes span \
         {travelled_m:.2} m (heading_init_distance_m = {needed_m:.2} m)"
    )]
    HeadingNotObservable {
        /// Largest distance between good fixes, metres.
        travelled_m: f64,
        /// The configured distance, metres.
        needed_m: f64,
    },
    /// The filter's covariance stopped being finite (a bug or absurd inputs).
    #[error("numerical failure of the filter at stamp {stamp} ns")]
    Numerical {
        /// The step's stamp, nanoseconds.
        stamp: i64,
    },
}
