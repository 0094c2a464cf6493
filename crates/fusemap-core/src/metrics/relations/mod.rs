//! The relation-based accuracy metric of the SLAM benchmark (Kümmerle et al. 2009, "On
//! measuring the accuracy of SLAM algorithms", *Autonomous Robots* 27(4)), as reported by
//! Hess et al. 2016 ("Real-Time Loop Closure in 2D LIDAR SLAM", Table II).
//!
//! Why relations and not absolute poses: a trajectory's error in a global frame mixes
//! an early heading error with every later position, so one bad turn dominates the
//! score. Kümmerle et al. instead compare *relative* motions between pairs of poses
//! (the relations, chosen and checked by a human from aligned scans):
//!
//! - the estimated relation is δ_ij = x_j ⊖ x_i = x_i⁻¹ ∘ x_j, the pose at t2 in the
//!   frame of the pose at t1;
//! - its error against the reference δ*_ij is ε_ij = δ_ij ⊖ δ*_ij = δ*_ij⁻¹ ∘ δ_ij
//!   (their eq. 1, with ⊖ the inverse of the motion composition ⊕);
//! - the translational error is ‖trans(ε_ij)‖ (metres), the rotational error
//!   |rot(ε_ij)| wrapped to [0, π] (reported in degrees).
//!
//! The paper's ε(δ) sums the squared forms; its tables (and Hess et al.'s) give the mean
//! and standard deviation of the absolute errors, and also of the squared ones.
//! [`RelationScore`] carries both.

use crate::geometry::{normalize_angle, Pose2};
use crate::time::Stamp;
use serde::Serialize;
use std::borrow::Cow;

#[cfg(test)]
mod tests;

/// The largest |roll|, |pitch| (radians) and |z| (metres) a relation may carry and still
/// be read as planar. The benchmark's 2D files write them as `0.000000`; anything larger
/// is a 3D relation this planar metric would silently misjudge.
pub const PLANAR_TOLERANCE: f64 = 1e-3;

/// One reference relation of a SLAM-benchmark relations file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relation {
    /// The 1-based line of the file it came from (for messages about it).
    pub line: usize,
    /// Stamp of the first pose (the frame the motion is expressed in).
    pub t1: Stamp,
    /// Stamp of the second pose.
    pub t2: Stamp,
    /// The true motion δ*: the pose at `t2` in the frame of the pose at `t1`
    /// (`x_t1⁻¹ ∘ x_t2`), rotation wrapped to (-π, π].
    pub motion: Pose2,
}

/// A relations file that does not follow the format, at a 1-based line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct RelationsError {
    /// The 1-based line.
    pub line: usize,
    /// What is wrong, in plain words.
    pub message: String,
}

/// The names of the eight fields, for error messages.
const FIELDS: [&str; 8] = ["t1", "t2", "x", "y", "z", "roll", "pitch", "yaw"];

/// Parses a relations file of the SLAM benchmark: one relation a line,
/// `t1 t2 x y z roll pitch yaw` (stamps in decimal seconds, metres, radians), blank lines
/// and `#` comments skipped.
///
/// Stamps are parsed exactly from their decimal text ([`Stamp::parse_decimal`]): going
/// through `f64` would lose up to ~120 ns at Unix-epoch magnitudes, enough to miss an
/// exact match against scan stamps. Exactly eight fields are accepted, every number must
/// be finite, and z, roll and pitch must be zero within [`PLANAR_TOLERANCE`]: the metric
/// is planar.
pub fn parse_relations(text: &str) -> Result<Vec<Relation>, RelationsError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let bad = |message: String| RelationsError { line, message };
        let f: Vec<&str> = trimmed.split_whitespace().collect();
        if f.len() != FIELDS.len() {
            return Err(bad(format!("expected 8 fields (t1 t2 x y z roll pitch yaw), got {}", f.len())));
        }
        let stamp = |k: usize| {
            Stamp::parse_decimal(f[k]).ok_or_else(|| {
                bad(format!("field {} ({}) is not a decimal number of seconds: `{}`", k + 1, FIELDS[k], f[k]))
            })
        };
        let (t1, t2) = (stamp(0)?, stamp(1)?);
        let mut v = [0.0f64; 6];
        for (k, slot) in v.iter_mut().enumerate() {
            let (name, s) = (FIELDS[k + 2], f[k + 2]);
            let x: f64 = s.parse().map_err(|_| bad(format!("field {} ({name}) is not a number: `{s}`", k + 3)))?;
            if !x.is_finite() {
                return Err(bad(format!("field {} ({name}) is not finite: `{s}`", k + 3)));
            }
            *slot = x;
        }
        let [x, y, z, roll, pitch, yaw] = v;
        for (name, value, unit) in [("z", z, "m"), ("roll", roll, "rad"), ("pitch", pitch, "rad")] {
            if value.abs() > PLANAR_TOLERANCE {
                return Err(bad(format!(
                    "{name} is {value} {unit}: the relation is not planar (|{name}| must be at most {PLANAR_TOLERANCE})"
                )));
            }
        }
        out.push(Relation { line, t1, t2, motion: Pose2::new(x, y, yaw).normalized() });
    }
    Ok(out)
}

/// The pose of `trajectory` (sorted by stamp) nearest in time to `t`, when it lies within
/// `tolerance_ns`. Binary search; on a tie the earlier sample wins, and of samples with
/// equal stamps the first.
fn nearest(trajectory: &[(Stamp, Pose2)], t: Stamp, tolerance_ns: i64) -> Option<Pose2> {
    let i = trajectory.partition_point(|(s, _)| *s < t);
    let mut best: Option<(u128, Pose2)> = None;
    for j in [i.checked_sub(1), Some(i)].into_iter().flatten() {
        if let Some(&(s, p)) = trajectory.get(j) {
            // i128: the difference of two i64 stamps cannot overflow it.
            let d = (s.0 as i128 - t.0 as i128).unsigned_abs();
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, p));
            }
        }
    }
    let tolerance = tolerance_ns.max(0) as u128;
    best.filter(|(d, _)| *d <= tolerance).map(|(_, p)| p)
}

/// `trajectory` in stamp order: itself when already sorted, else a stably sorted copy.
fn in_stamp_order(trajectory: &[(Stamp, Pose2)]) -> Cow<'_, [(Stamp, Pose2)]> {
    if trajectory.windows(2).all(|w| w[0].0 <= w[1].0) {
        Cow::Borrowed(trajectory)
    } else {
        let mut v = trajectory.to_vec();
        v.sort_by_key(|(s, _)| *s);
        Cow::Owned(v)
    }
}

/// `trajectory` at the stamps the relations name, for a trajectory not sampled at the
/// scans (a `trajectory.tum` written at the odometry's rate): at each stamp the nearest
/// pose within `tolerance_ns`, else the pose interpolated between the two around it
/// (linear in translation, shortest arc in heading, as tf2 does) when they are at most
/// `max_gap_ns` apart; a stamp in a longer gap or outside the trajectory gets no pose and
/// its relations stay unmatched.
pub fn at_relation_stamps(
    relations: &[Relation],
    trajectory: &[(Stamp, Pose2)],
    tolerance_ns: i64,
    max_gap_ns: i64,
) -> Vec<(Stamp, Pose2)> {
    let trajectory = in_stamp_order(trajectory);
    let mut stamps: Vec<Stamp> = relations.iter().flat_map(|r| [r.t1, r.t2]).collect();
    stamps.sort();
    stamps.dedup();
    stamps
        .into_iter()
        .filter_map(|t| {
            if let Some(p) = nearest(&trajectory, t, tolerance_ns) {
                return Some((t, p));
            }
            let i = trajectory.partition_point(|s| s.0 < t);
            let ((ta, a), (tb, b)) = (*trajectory.get(i.checked_sub(1)?)?, *trajectory.get(i)?);
            let gap = tb.0 as i128 - ta.0 as i128;
            (gap > 0 && gap <= max_gap_ns as i128)
                .then(|| (t, a.interpolate(b, (t.0 as i128 - ta.0 as i128) as f64 / gap as f64)))
        })
        .collect()
}

/// How a trajectory's poses are found at the stamps the relations name: the one rule of
/// `fusemap relations` and of the SLAM-benchmark tests, so that the figure a user
/// reproduces is the figure the tests assert.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelationMatching {
    /// The nearest pose counts when it lies at most this far from the stamp, ns.
    pub tolerance_ns: i64,
    /// Else the pose interpolated between the two around the stamp, when they are at
    /// most this far apart, ns.
    pub max_gap_ns: i64,
    /// The pose of the sensor the relations are between, in the trajectory's frame (the
    /// benchmark's relations are laser poses; fusemap writes the base frame's).
    pub sensor_in_base: Pose2,
}

impl RelationMatching {
    /// The default tolerance, ms: relation stamps are written with microseconds and a
    /// trajectory holding a pose at every scan has the stamp itself.
    pub const TOLERANCE_MS: f64 = 1.0;
    /// The default largest gap interpolated across, ms: a few odometry periods, never a
    /// pause in which the robot may have turned.
    pub const MAX_GAP_MS: f64 = 500.0;
}

impl Default for RelationMatching {
    fn default() -> Self {
        Self {
            tolerance_ns: (Self::TOLERANCE_MS * 1e6) as i64,
            max_gap_ns: (Self::MAX_GAP_MS * 1e6) as i64,
            sensor_in_base: Pose2::IDENTITY,
        }
    }
}

/// `trajectory` (`map_from_base`, any order) scored against `relations` by `matching`:
/// the sensor's pose at each relation stamp ([`at_relation_stamps`]), then
/// [`score_relations`] on exactly those stamps.
pub fn score_trajectory(
    relations: &[Relation],
    trajectory: &[(Stamp, Pose2)],
    matching: &RelationMatching,
) -> RelationScore {
    let sensor: Vec<(Stamp, Pose2)> =
        trajectory.iter().map(|&(t, p)| (t, p.compose(matching.sensor_in_base))).collect();
    let at_stamps = at_relation_stamps(relations, &sensor, matching.tolerance_ns, matching.max_gap_ns);
    score_relations(relations, &at_stamps, 0)
}

/// The error transform ε = δ*⁻¹ ∘ δ of each relation (Kümmerle et al. 2009, eq. 1), in the
/// order of `relations`; `None` for a relation whose `t1` or `t2` has no trajectory sample
/// within `tolerance_ns` (a negative tolerance counts as 0: exact stamps only).
///
/// δ = P(t1)⁻¹ ∘ P(t2) with P the nearest sample of `trajectory` (`map_from_base` poses;
/// any order: an unsorted trajectory is sorted by stamp first). No interpolation: the
/// benchmark's relations name scan stamps, and a trajectory of scan poses has them.
pub fn relation_errors(relations: &[Relation], trajectory: &[(Stamp, Pose2)], tolerance_ns: i64) -> Vec<Option<Pose2>> {
    let trajectory = in_stamp_order(trajectory);
    relations
        .iter()
        .map(|r| {
            let p1 = nearest(&trajectory, r.t1, tolerance_ns)?;
            let p2 = nearest(&trajectory, r.t2, tolerance_ns)?;
            let estimated = p1.inverse().compose(p2);
            Some(r.motion.inverse().compose(estimated))
        })
        .collect()
}

/// A trajectory scored against reference relations (Kümmerle et al. 2009; the figures of
/// Hess et al. 2016, Table II, are `translation_mean_m` ± `translation_std_m` and
/// `rotation_mean_deg` ± `rotation_std_deg`).
///
/// Standard deviations are population ones (divided by `scored`). Every statistic is NaN
/// (JSON `null`) when nothing was scored.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RelationScore {
    /// Relations given.
    pub relations: usize,
    /// Relations whose two stamps were both found in the trajectory.
    pub scored: usize,
    /// Relations with a stamp not in the trajectory (within the tolerance): never
    /// silently dropped, `relations == scored + unmatched`.
    pub unmatched: usize,
    /// Mean of ‖trans(ε)‖, metres.
    pub translation_mean_m: f64,
    /// Standard deviation of ‖trans(ε)‖, metres.
    pub translation_std_m: f64,
    /// Largest ‖trans(ε)‖, metres.
    pub translation_max_m: f64,
    /// Mean of |rot(ε)|, degrees.
    pub rotation_mean_deg: f64,
    /// Standard deviation of |rot(ε)|, degrees.
    pub rotation_std_deg: f64,
    /// Largest |rot(ε)|, degrees.
    pub rotation_max_deg: f64,
    /// Mean of ‖trans(ε)‖², m² (the paper's squared translational error).
    pub translation_sq_mean_m2: f64,
    /// Standard deviation of ‖trans(ε)‖², m².
    pub translation_sq_std_m2: f64,
    /// Mean of |rot(ε)|², deg² (the paper's squared rotational error).
    pub rotation_sq_mean_deg2: f64,
    /// Standard deviation of |rot(ε)|², deg².
    pub rotation_sq_std_deg2: f64,
}

/// Mean, population standard deviation and maximum of `v`; NaN for an empty slice.
fn stats(v: &[f64]) -> (f64, f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    // Two passes: the one-pass E[x²] − E[x]² cancels badly when errors are tiny and alike.
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (mean, var.sqrt(), v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
}

/// Scores `trajectory` against `relations` (see [`relation_errors`] for the matching of
/// stamps and [`RelationScore`] for the figures).
pub fn score_relations(relations: &[Relation], trajectory: &[(Stamp, Pose2)], tolerance_ns: i64) -> RelationScore {
    let errors: Vec<Pose2> = relation_errors(relations, trajectory, tolerance_ns).into_iter().flatten().collect();
    score_errors(relations.len(), &errors)
}

/// The figures of [`RelationScore`] from the error transforms of the relations that could
/// be scored, out of `relations` given.
pub(crate) fn score_errors(relations: usize, errors: &[Pose2]) -> RelationScore {
    let trans: Vec<f64> = errors.iter().map(|e| e.x.hypot(e.y)).collect();
    let rot: Vec<f64> = errors.iter().map(|e| normalize_angle(e.theta).abs().to_degrees()).collect();
    let square = |v: &[f64]| v.iter().map(|x| x * x).collect::<Vec<f64>>();
    let (translation_mean_m, translation_std_m, translation_max_m) = stats(&trans);
    let (rotation_mean_deg, rotation_std_deg, rotation_max_deg) = stats(&rot);
    let (translation_sq_mean_m2, translation_sq_std_m2, _) = stats(&square(&trans));
    let (rotation_sq_mean_deg2, rotation_sq_std_deg2, _) = stats(&square(&rot));
    RelationScore {
        relations,
        scored: errors.len(),
        unmatched: relations - errors.len(),
        translation_mean_m,
        translation_std_m,
        translation_max_m,
        rotation_mean_deg,
        rotation_std_deg,
        rotation_max_deg,
        translation_sq_mean_m2,
        translation_sq_std_m2,
        rotation_sq_mean_deg2,
        rotation_sq_std_deg2,
    }
}
