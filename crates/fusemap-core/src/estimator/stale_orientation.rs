//! An IMU orientation that stopped changing while the same IMU's gyro says it turns: a
//! frozen attitude filter, a driver republishing its last quaternion. Its covariance is
//! whatever the driver last wrote (often a few millidegrees), so the filter would hold the
//! heading at that value against the gyro and the odometry; the readings are stale, not
//! measurements, and are left out.
//!
//! An orientation is judged stale once it has repeated, bit for bit, while the gyro's own
//! rates integrate to a turn of more than [`STALE_TURN_RAD`] either way. A real attitude
//! filter's output changes with every gyro sample it integrates (its quaternion does not
//! repeat to the bit for seconds), so a good IMU is never touched; a frozen one is caught
//! in a sharp turn within a fraction of a second, along a gentle curve once it has turned
//! 5°, and at rest only after its gyro bias has integrated to 5° (a minute at 0.1°/s),
//! where leaving its heading out costs nothing.

use crate::time::Stamp;

/// Gyro turning (the integral of the yaw rate) over which an unchanged orientation is
/// stale, radians: 5°.
pub const STALE_TURN_RAD: f64 = 0.087;

/// The longest step between two samples the turning is integrated over, seconds: across a
/// longer gap the rate is unknown, and nothing is counted.
const MAX_STEP_S: f64 = 0.5;

/// Tracks one IMU's orientation readings (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct StaleOrientation {
    /// The last orientation, as bits, and the stamp of the last sample.
    last: Option<([u64; 4], Stamp)>,
    /// Gyro turning since the orientation last changed, radians (signed).
    turned_rad: f64,
}

impl StaleOrientation {
    /// Feeds one sample: its stamp, its orientation quaternion and the gyro's yaw rate
    /// (rad/s; NaN when the message has none). True when its orientation is stale.
    pub fn is_stale(&mut self, stamp: Stamp, orientation: [f64; 4], yaw_rate: f64) -> bool {
        let bits = orientation.map(f64::to_bits);
        match self.last {
            Some((b, t)) if b == bits => {
                let dt = stamp.secs_since(t);
                if yaw_rate.is_finite() && (0.0..=MAX_STEP_S).contains(&dt) {
                    self.turned_rad += yaw_rate * dt;
                }
            }
            _ => self.turned_rad = 0.0,
        }
        self.last = Some((bits, stamp));
        self.turned_rad.abs() > STALE_TURN_RAD
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orientation_that_stays_while_the_gyro_turns_is_stale_until_it_moves_again() {
        let mut s = StaleOrientation::default();
        let q = [0.0, 0.0, 0.0, 1.0];
        let at = |k: i64| Stamp(k * 10_000_000);
        // Still: the same quaternion for 10 s at rest is a still robot, not a fault.
        assert!((0..1000).all(|k| !s.is_stale(at(k), q, 0.0)));
        // … nor rocking back and forth at 0.3 rad/s (a noisy gyro at rest).
        assert!((1000..7000).all(|k| !s.is_stale(at(k), q, if k % 2 == 0 { 0.3 } else { -0.3 })));
        // Turning at 0.5 rad/s with the quaternion frozen: stale after 5° (0.17 s).
        let stale: Vec<bool> = (7000..7100).map(|k| s.is_stale(at(k), q, -0.5)).collect();
        assert!(!stale[..17].iter().any(|&x| x) && stale[19..].iter().all(|&x| x), "{stale:?}");
        // The orientation moves again: fresh at once.
        assert!(!s.is_stale(at(7100), [0.0, 0.0, 0.1, 0.995], 0.55));
        // A gap of an hour does not count as an hour of turning.
        assert!(!s.is_stale(at(7100 + 360_000), [0.0, 0.0, 0.1, 0.995], 0.55));
        // No rate in the message: nothing to judge by.
        assert!(!s.is_stale(at(7100 + 360_001), [0.0, 0.0, 0.1, 0.995], f64::NAN));
    }
}
