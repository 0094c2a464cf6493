//! The pose sensors' tables (wheel odometry, IMU, GNSS, pose): their noise overrides,
//! the GNSS datum, σ floors and altitude band, and the mount, checked and planned.

use super::sensor::{GnssNoise, OdometryNoise, PlannedSensor, SensorConfig};
use super::{check_mount, err, finite, FieldError};
use crate::estimator::DEFAULT_ALTITUDE_RANGE_M;

/// `v` when absent or finite and positive; the error names `field`.
fn positive_opt(field: String, v: Option<f64>) -> Result<Option<f64>, FieldError> {
    match v {
        Some(x) if finite(&field, x)? <= 0.0 => Err(err(field, format!("must be > 0, got {x}"))),
        v => Ok(v),
    }
}

/// Table `i` (`s`, enabled, of a pose-sensor kind) planned under `name`, its clock
/// `offset` checked by the caller.
pub(super) fn plan_pose_sensor(
    i: usize,
    s: &SensorConfig,
    name: String,
    offset: f64,
) -> Result<PlannedSensor, FieldError> {
    let f = |name: &str| format!("sensor[{i}].{name}");
    let pos = |k: &str, v: Option<f64>| positive_opt(f(k), v);
    let odometry = OdometryNoise {
        translation_per_sqrt_m: pos("translation_noise_per_sqrt_m", s.translation_noise_per_sqrt_m)?,
        rotation_per_sqrt_rad: pos("rotation_noise_per_sqrt_rad", s.rotation_noise_per_sqrt_rad)?,
        rotation_per_sqrt_m: pos("rotation_noise_per_sqrt_m", s.rotation_noise_per_sqrt_m)?,
    };
    let gyro = pos("gyro_noise_rad_s", s.gyro_noise_rad_s)?;
    check_datum(i, s.datum)?;
    let gnss = gnss_noise(i, s)?;
    let altitude_range_m = s.altitude_range_m.unwrap_or(DEFAULT_ALTITUDE_RANGE_M);
    let [low, high] = altitude_range_m;
    if finite(&f("altitude_range_m"), low)? >= finite(&f("altitude_range_m"), high)? {
        return Err(err(f("altitude_range_m"), format!("must be [lowest, highest], got [{low}, {high}]")));
    }
    let pose_noise =
        (pos("position_noise_m", s.position_noise_m)?, pos("yaw_noise_deg", s.yaw_noise_deg)?.map(f64::to_radians));
    if let Some(m) = &s.base_from_sensor {
        check_mount(f, m)?;
    }
    Ok(PlannedSensor {
        kind: s.kind,
        name,
        topic: s.topic.clone(),
        frame: s.frame.clone(),
        time_offset_s: offset,
        base_from_sensor: s.base_from_sensor,
        odometry,
        gyro_noise_rad_s: gyro,
        use_orientation: s.use_orientation.unwrap_or(true),
        datum: s.datum,
        gnss,
        altitude_range_m,
        pose_noise,
        explicit: true,
    })
}

/// A configured datum: finite, latitude within ±90° and longitude within ±180°.
fn check_datum(i: usize, datum: Option<[f64; 3]>) -> Result<(), FieldError> {
    let Some([lat, lon, alt]) = datum else { return Ok(()) };
    let field = format!("sensor[{i}].datum");
    for v in [lat, lon, alt] {
        finite(&field, v)?;
    }
    if lat.abs() > 90.0 || lon.abs() > 180.0 {
        return Err(err(field, format!("latitude must be within ±90° and longitude ±180°, got {lat}, {lon}")));
    }
    Ok(())
}

/// The GNSS σ floors by fix status and the σ of a fix without a covariance, each positive.
fn gnss_noise(i: usize, s: &SensorConfig) -> Result<GnssNoise, FieldError> {
    let gnss = GnssNoise {
        floor_rtk_m: s.sigma_floor_rtk_m.unwrap_or(0.02),
        floor_sbas_m: s.sigma_floor_sbas_m.unwrap_or(0.5),
        floor_fix_m: s.sigma_floor_fix_m.unwrap_or(0.5),
        unknown_m: s.sigma_unknown_m.unwrap_or(3.0),
    };
    for (k, v) in [
        ("sigma_floor_rtk_m", gnss.floor_rtk_m),
        ("sigma_floor_sbas_m", gnss.floor_sbas_m),
        ("sigma_floor_fix_m", gnss.floor_fix_m),
        ("sigma_unknown_m", gnss.unknown_m),
    ] {
        let field = format!("sensor[{i}].{k}");
        if finite(&field, v)? <= 0.0 {
            return Err(err(field, format!("must be > 0 metres, got {v}")));
        }
    }
    Ok(gnss)
}
