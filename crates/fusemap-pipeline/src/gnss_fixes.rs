//! GNSS fixes as the estimator is given them: checked against the message definition and
//! the Earth, converted exactly (WGS84 → ECEF → ENU) into one local map frame around a
//! datum chosen robustly, with covariances floored per fix status and the antenna's lever
//! arm. What is not used is counted by reason.

use crate::estimation_report::GnssInputReport;
use crate::extrinsics::frame_tree;
use crate::recording::Inventory;
use crate::sensors::{Bound, BoundSensor};
use crate::{PipelineError, Stage};
use fusemap_core::config::{LogConfig, Plan, SensorKind};
use fusemap_core::estimator::{check_fix, EstimatorInput, FixProblem, FixQuality, GnssCovarianceKind, Repeated};
use fusemap_core::frames::FrameTree;
use fusemap_core::geometry::{geodetic::Datum, Point2};
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::sensor_msgs::{NavSatFix, NavSatStatus};
use fusemap_io::log::GnssMessage;

/// The datum of the map frame `[lat°, lon°, alt m]`, where it came from, and how many
/// early fixes were passed over because the fixes after them disagreed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ChosenDatum {
    /// Latitude, longitude, altitude.
    pub lla: (f64, f64, f64),
    /// `config`, `first good fix` or `first consistent fix`.
    pub source: &'static str,
    /// Good fixes before it that the fixes after them contradicted.
    pub passed_over: usize,
    /// The fix it was taken from (`None` when configured).
    pub fix: Option<(Stamp, [f64; 2])>,
}

impl ChosenDatum {
    /// True for a fix from before the datum's own fix that disagrees with it: a receiver
    /// fault the fixes after it contradicted, never given to the estimator (whose start
    /// it would otherwise set).
    fn contradicts(&self, f: &GnssMessage) -> bool {
        self.fix.is_some_and(|(t, at)| {
            f.stamp < t && ground_distance_m(at, lat_lon(f)) > agreement_m(t.secs_since(f.stamp))
        })
    }
}

/// The GNSS fixes as the estimator is given them: antenna positions in its map frame
/// (the shared local ENU frame), covariances floored per fix quality, lever arms.
pub fn gnss_positions(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<Vec<EstimatorInput>, PipelineError> {
    let (tree, _) = frame_tree(&plan.log, &inv.tf_static, &inv.tf_dynamic);
    let datum = shared_datum(inv, bound);
    let mut out = Vec::new();
    for s in bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::Gnss) {
        out.extend(gnss_inputs(s, inv, &tree, &plan.log, datum)?.0);
    }
    Ok(out)
}

/// What is wrong with fix `f` for a receiver whose altitudes lie in `band`.
fn problem(f: &GnssMessage, band: [f64; 2]) -> Result<(), FixProblem> {
    check_fix(f.status, f.position_covariance_type, [f.latitude, f.longitude, f.altitude], band)
}

/// A fix with a position, within the altitude band `band` (the doctor's rule, the same
/// checks as a run's).
pub fn usable_fix(f: &GnssMessage, band: [f64; 2]) -> bool {
    problem(f, band).is_ok()
}

/// How far apart two fixes can be and still agree, metres: a generous receiver error plus
/// a fast robot's travel between them.
fn agreement_m(dt_s: f64) -> f64 {
    const RECEIVER_M: f64 = 100.0;
    const SPEED_MPS: f64 = 20.0;
    RECEIVER_M + SPEED_MPS * dt_s.abs()
}

/// Distance between two fixes on the ground, metres (equirectangular: ample for telling
/// 100 m from a teleport).
fn ground_distance_m([lat_a, lon_a]: [f64; 2], [lat_b, lon_b]: [f64; 2]) -> f64 {
    const M_PER_DEG: f64 = 111_320.0;
    let north = (lat_b - lat_a) * M_PER_DEG;
    let east = (lon_b - lon_a) * M_PER_DEG * lat_a.to_radians().cos();
    north.hypot(east)
}

/// Latitude and longitude of a fix.
fn lat_lon(f: &GnssMessage) -> [f64; 2] {
    [f.latitude, f.longitude]
}

/// One map frame for every GNSS sensor: the first configured datum, else the earliest good
/// fix of any GNSS topic (two receivers must not get two ENU frames metres apart) that the
/// next two good fixes agree with. A lone first fix a thousand kilometres off is a
/// receiver fault and is passed over; with fewer than three good fixes, the first is taken.
pub(crate) fn shared_datum(inv: &Inventory, bound: &Bound) -> Option<ChosenDatum> {
    let gnss = bound.sensors.iter().filter(|s| s.sensor.kind == SensorKind::Gnss);
    if let Some([lat, lon, alt]) = gnss.clone().find_map(|s| s.sensor.datum) {
        return Some(ChosenDatum { lla: (lat, lon, alt), source: "config", passed_over: 0, fix: None });
    }
    let mut good: Vec<&GnssMessage> = gnss
        .flat_map(|s| inv.gnss[&s.topic].iter().filter(|f| problem(f, s.sensor.altitude_range_m).is_ok()))
        .collect();
    good.sort_by_key(|f| f.stamp);
    let agrees = |a: &GnssMessage, b: &GnssMessage| {
        ground_distance_m(lat_lon(a), lat_lon(b)) <= agreement_m(b.stamp.secs_since(a.stamp))
    };
    let consistent = (0..good.len().saturating_sub(2))
        .find(|&i| good[i + 1..=i + 2].iter().all(|later| agrees(good[i], later)))
        .unwrap_or(0);
    let f = good.get(consistent)?;
    let source = if consistent == 0 { "first good fix" } else { "first consistent fix" };
    Some(ChosenDatum {
        lla: (f.latitude, f.longitude, f.altitude),
        source,
        passed_over: consistent,
        fix: Some((f.stamp, [f.latitude, f.longitude])),
    })
}

/// The quality of a fix, for the report and the floor.
fn quality(f: &GnssMessage) -> FixQuality {
    match f.status {
        NavSatStatus::STATUS_GBAS_FIX => FixQuality::RtkFixed,
        NavSatStatus::STATUS_SBAS_FIX => FixQuality::Sbas,
        NavSatStatus::STATUS_FIX => FixQuality::Fix,
        _ => FixQuality::Unknown,
    }
}

/// Counts a fix that gives no position under its reason.
fn count(r: &mut GnssInputReport, why: FixProblem) {
    match why {
        FixProblem::InvalidField => r.invalid_field += 1,
        FixProblem::NoFix => r.no_fix += 1,
        FixProblem::NotFinite => r.not_finite += 1,
        FixProblem::OutOfRange => r.out_of_range += 1,
    }
}

/// The notes for the fixes a GNSS sensor's stream lost to faults.
fn fault_notes(topic: &str, r: &GnssInputReport, datum: Option<ChosenDatum>, notes: &mut Vec<String>) {
    if r.out_of_range > 0 || r.invalid_field > 0 {
        notes.push(format!(
            "GNSS `{topic}`: {} fixes outside the Earth's ranges (latitude ±90°, longitude ±180°, \
             altitude_range_m) and {} with a status or covariance type NavSatFix does not define \
             were dropped as receiver faults",
            r.out_of_range, r.invalid_field
        ));
    }
    if let Some(d) = datum.filter(|d| d.passed_over > 0) {
        notes.push(format!(
            "GNSS `{topic}`: the first {} good fixes disagree with the fixes after them, so the datum \
             is the first fix the next two agree with; {} fixes before it that disagree with it were \
             dropped",
            d.passed_over, r.contradicted
        ));
    }
}

/// One GNSS sensor's fixes as estimator inputs, with its report and notes.
pub(crate) fn gnss_inputs(
    s: &BoundSensor,
    inv: &Inventory,
    tree: &FrameTree,
    cfg: &LogConfig,
    datum: Option<ChosenDatum>,
) -> Result<(Vec<EstimatorInput>, GnssInputReport, Vec<String>), PipelineError> {
    let msgs = &inv.gnss[&s.topic];
    let band = s.sensor.altitude_range_m;
    let mut r = GnssInputReport { read: msgs.len() as u64, ..Default::default() };
    let mut notes = Vec::new();
    let Some(chosen) = datum else {
        notes.push(format!(
            "GNSS `{}`: {} messages but no usable fix and no datum configured: the fixes are not used",
            s.topic,
            msgs.len()
        ));
        for f in msgs {
            if let Err(why) = problem(f, band) {
                count(&mut r, why);
            }
        }
        fault_notes(&s.topic, &r, None, &mut notes);
        return Ok((Vec::new(), r, notes));
    };
    r.datum_source = chosen.source.to_string();
    let (lat0, lon0, alt0) = chosen.lla;
    let datum = Datum::new(lat0, lon0, alt0)
        .map_err(|e| PipelineError::refused(Stage::Poses, format!("GNSS `{}`: datum: {e}", s.topic)))?;
    r.datum = Some([lat0, lon0, alt0]);
    let frame = s.sensor.frame.clone().or_else(|| msgs.first().map(|m| m.frame_id.clone())).unwrap_or_default();
    let lever = crate::extrinsics::sensor_mount(s, cfg, tree, &frame, msgs.first().map(|m| m.stamp), &mut notes)?;
    r.lever_arm = Some([lever.x, lever.y]);
    let floors = s.sensor.gnss;
    let mut out = Vec::new();
    let mut repeated = Repeated::new();
    for f in msgs {
        if let Err(why) = problem(f, band) {
            count(&mut r, why);
            continue;
        }
        if chosen.contradicts(f) {
            r.contradicted += 1;
            continue;
        }
        let enu = datum.to_enu(f.latitude, f.longitude, f.altitude);
        let q = quality(f);
        // NavSatFix's covariance is ENU (east, north, up), m².
        let kind = match f.position_covariance_type {
            NavSatFix::COVARIANCE_TYPE_UNKNOWN => GnssCovarianceKind::Unknown,
            NavSatFix::COVARIANCE_TYPE_KNOWN => GnssCovarianceKind::Known,
            _ => GnssCovarianceKind::Diagonal,
        };
        let cov = floors.covariance(&f.position_covariance, kind, q);
        r.unknown_covariance += u64::from(cov.unknown);
        r.floored += u64::from(cov.floored);
        r.passed += 1;
        let covariance = repeated.share(cov.enu);
        out.push(EstimatorInput::Position {
            stamp: s.stamp(f.stamp),
            enu: [enu[0], enu[1]],
            covariance,
            antenna: Point2::new(lever.x, lever.y),
            quality: q,
        });
    }
    fault_notes(&s.topic, &r, Some(chosen), &mut notes);
    Ok((out, r, notes))
}
