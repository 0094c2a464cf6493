//! The verdict of the design document's validation (§5): does fusion help, and if not,
//! is the fusion model at fault or the sensors' time sync and mounts?
//!
//! Two tests, in this order:
//! * **§5.2, leave-one-out hit rates.** Each map is built from the earlier part of the log;
//!   each sensor's observations of the later part are projected onto it with the same pose
//!   track, and its hit rate is the share that land on the map's obstacle cells. A map of
//!   every sensor (M3) that a sensor's later observations hit less often than a map built
//!   without some of the sensors (M1, M2) disagrees with that sensor: evidence was put in
//!   the wrong place, which a mount or a clock does, not the fusion rule. (A point hits
//!   a map when it lands within one cell of an obstacle cell.)
//! * **§5.1, entropy.** Otherwise fusion helps when M3's mean entropy is below the best
//!   single-sensor map's by at least `min_gain_nats` (the document's rule of thumb: 0.05
//!   nats indoors at 0.05 m with prior 0.5; entropy depends on the resolution, so the
//!   figure does not carry over to other cell sizes).
//!
//! Which sensor is the suspect. Hit rates alone cannot say: two sensors that disagree
//! disagree symmetrically, and the fused map follows the stronger one (a lidar), so the
//! weaker one's hit rate drops whichever is wrong. And SLAM bends the track to the lidar,
//! so a lidar with a wrong mount still agrees with its own map. The third witness is the
//! pose sensors: where SLAM ran, [`super::motion_agreement`] compares the lidar's direction
//! of travel with theirs, which a wrong lidar yaw turns by the error. So:
//! * a lidar whose motion disagrees with the pose sensors by more than `mount_yaw_deg`
//!   (and three standard errors) is the suspect;
//! * else, the sensor whose later observations lose the most hit rate from the map of its
//!   own kind (M1 for a lidar, M2 for a camera) to M3, as a share of that rate.

use super::MotionAgreement;
use crate::config::Thresholds;
use crate::fusion::HitRate;
use crate::measurement::SensorKind;
use serde::Serialize;

/// What a map of the validation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MapRole {
    /// M1: the lidars and the pose sensors.
    Lidar,
    /// M2: the cameras and the pose sensors.
    Camera,
    /// M3: every sensor.
    Fused,
    /// Every sensor but one (§4.3's leave-one-out, built when more than two sensors make
    /// the map); reported, not judged.
    LeftOut,
}

/// One sensor's held-out observations against one map.
#[derive(Clone, Debug, Serialize)]
pub struct SensorHits {
    /// The sensor's name.
    pub sensor: String,
    /// Its kind.
    pub kind: SensorKind,
    /// Its hit rate on the map.
    #[serde(flatten)]
    pub hit: HitRate,
}

/// One map's figures.
#[derive(Clone, Debug, Serialize)]
pub struct MapFigures {
    /// Its name (`m1`, `m2`, `m3`).
    pub name: String,
    /// What it is.
    pub role: MapRole,
    /// The sensors whose observations built it.
    pub sensors: Vec<String>,
    /// Mean binary entropy over the cells any map of the validation observed (unknown
    /// ones at the prior), nats.
    pub mean_entropy_nats: f64,
    /// Each held-out sensor's hit rate on it.
    pub hit_rates: Vec<SensorHits>,
}

/// The verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// M3 agrees with every sensor and is clearly more certain than the best single map.
    FusionHelps,
    /// M3 agrees with every sensor but is not clearly more certain (or there is one kind of
    /// map evidence only, nothing to fuse).
    NoGain,
    /// A sensor's later observations hit M3 less often than its own map: check its clock
    /// offset and its mount.
    CheckSyncAndExtrinsics,
}

/// The judgement of a validation.
#[derive(Clone, Debug, Serialize)]
pub struct Judgement {
    /// The verdict code.
    pub verdict: Verdict,
    /// The sensor the verdict names, if any.
    pub suspect: Option<String>,
    /// H(best single-sensor map) − H(M3), nats; `None` without a single-sensor map to
    /// compare with.
    pub fusion_gain_nats: Option<f64>,
    /// Each sensor's hit-rate drop from its own map to M3, as a share of its own-map rate.
    pub hit_rate_drops: Vec<(String, f64)>,
    /// The verdict in a plain sentence.
    pub sentence: String,
}

/// A sensor's rate on the map of `role`, if it has enough endpoints.
fn rate_on(maps: &[MapFigures], role: &MapRole, sensor: &str, min_endpoints: u64) -> Option<f64> {
    let m = maps.iter().find(|m| &m.role == role)?;
    let h = m.hit_rates.iter().find(|h| h.sensor == sensor)?;
    h.hit.rate.filter(|_| h.hit.endpoints >= min_endpoints)
}

/// The map built from a sensor's kind alone.
fn own_role(kind: SensorKind) -> MapRole {
    // (A map without one sensor is never a sensor's own.)
    match kind {
        SensorKind::Lidar => MapRole::Lidar,
        SensorKind::Camera => MapRole::Camera,
    }
}

/// The lidar whose direction of travel disagrees most, and significantly, with the pose
/// sensors', with the angle.
fn turned_lidar<'a>(motion: &'a [(String, MotionAgreement)], t: &Thresholds) -> Option<(&'a str, f64)> {
    motion
        .iter()
        .filter(|(_, m)| m.median_deg.abs() > t.mount_yaw_deg.max(3.0 * m.standard_error_deg))
        .max_by(|a, b| a.1.median_deg.abs().total_cmp(&b.1.median_deg.abs()))
        .map(|(n, m)| (n.as_str(), m.median_deg))
}

/// Each sensor's relative drop of its held-out hit rate from its own map to the fused one
/// (only with more than one single-sensor map to compare).
fn hit_rate_drops(maps: &[MapFigures], fused: &MapFigures, singles: usize, t: &Thresholds) -> Vec<(String, f64)> {
    let mut drops = Vec::new();
    for h in &fused.hit_rates {
        let own = rate_on(maps, &own_role(h.kind), &h.sensor, t.min_endpoints);
        let on_fused = rate_on(maps, &MapRole::Fused, &h.sensor, t.min_endpoints);
        if let (Some(own), Some(f)) = (own, on_fused) {
            if singles > 1 && own > 0.0 {
                drops.push((h.sensor.clone(), (own - f) / own));
            }
        }
    }
    drops
}

/// Judges the maps of a validation, with each SLAM lidar's motion against the pose
/// sensors' (see the module docs).
pub fn judge(maps: &[MapFigures], motion: &[(String, MotionAgreement)], t: &Thresholds) -> Judgement {
    let Some(fused) = maps.iter().find(|m| m.role == MapRole::Fused) else {
        return Judgement {
            verdict: Verdict::NoGain,
            suspect: None,
            fusion_gain_nats: None,
            hit_rate_drops: Vec::new(),
            sentence: "no fused map was built: nothing to judge".into(),
        };
    };
    let singles: Vec<&MapFigures> =
        maps.iter().filter(|m| matches!(m.role, MapRole::Lidar | MapRole::Camera)).collect();
    let drops = hit_rate_drops(maps, fused, singles.len(), t);
    let best_single = singles.iter().map(|m| m.mean_entropy_nats).min_by(f64::total_cmp);
    let gain = best_single.filter(|_| singles.len() > 1).map(|h| h - fused.mean_entropy_nats);
    let worst = drops.iter().max_by(|a, b| a.1.total_cmp(&b.1)).filter(|d| d.1 >= t.hit_rate_drop);
    if let Some((lidar, angle)) = turned_lidar(motion, t) {
        let also = worst.map_or(String::new(), |(s, d)| {
            format!("; and `{s}`'s later observations hit the fused map {:.0} % less often than its own map", 100.0 * d)
        });
        return Judgement {
            verdict: Verdict::CheckSyncAndExtrinsics,
            suspect: Some(lidar.to_string()),
            fusion_gain_nats: gain,
            sentence: format!(
                "check `{lidar}`'s mount: its direction of travel (SLAM's track) is turned {angle:+.2}° from the pose \
                 sensors' on straight steps, which a yaw mount wrong by about that much does (or odometry that \
                 crabs){also}"
            ),
            hit_rate_drops: drops,
        };
    }
    if let Some((sensor, drop)) = worst {
        return Judgement {
            verdict: Verdict::CheckSyncAndExtrinsics,
            suspect: Some(sensor.clone()),
            fusion_gain_nats: gain,
            sentence: format!(
                "check `{sensor}`'s clock offset and mount: its later observations hit the fused map {:.0} % less \
                 often than its own map, so the fused map puts evidence where `{sensor}` does not see it (§5.2: \
                 a sync or extrinsics fault, not the fusion model)",
                100.0 * drop
            ),
            hit_rate_drops: drops,
        };
    }
    let (verdict, sentence) = match gain {
        None => (
            Verdict::NoGain,
            "one kind of map evidence only: there is nothing to fuse, and no single-sensor map to compare with"
                .to_string(),
        ),
        Some(g) if g >= t.min_gain_nats => (
            Verdict::FusionHelps,
            format!(
                "fusion helps: the fused map's mean entropy is {g:.3} nats below the best single-sensor map's \
                 (at least {:.2} asked), and every sensor with enough later points agrees with it",
                t.min_gain_nats
            ),
        ),
        Some(g) => (
            Verdict::NoGain,
            format!(
                "no clear gain: the fused map's mean entropy is {g:.3} nats below the best single-sensor map's, \
                 under the {:.2} asked; the sensors with enough later points agree with it, so check what each adds before adding more \
                 (§4.3)",
                t.min_gain_nats
            ),
        ),
    };
    Judgement { verdict, suspect: None, fusion_gain_nats: gain, hit_rate_drops: drops, sentence }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hits(sensor: &str, kind: SensorKind, endpoints: u64, hit: u64) -> SensorHits {
        SensorHits {
            sensor: sensor.into(),
            kind,
            hit: HitRate { endpoints, hits: hit, rate: Some(hit as f64 / endpoints as f64) },
        }
    }

    fn map(name: &str, role: MapRole, h: f64, rates: [(u64, u64); 2]) -> MapFigures {
        MapFigures {
            name: name.into(),
            role,
            sensors: Vec::new(),
            mean_entropy_nats: h,
            hit_rates: vec![
                hits("laser", SensorKind::Lidar, rates[0].0, rates[0].1),
                hits("camera", SensorKind::Camera, rates[1].0, rates[1].1),
            ],
        }
    }

    const T: Thresholds =
        Thresholds { min_gain_nats: 0.05, hit_rate_drop: 0.1, min_endpoints: 100, mount_yaw_deg: 1.0 };

    #[test]
    fn agreement_and_lower_entropy_is_help() {
        let maps = [
            map("m1", MapRole::Lidar, 0.40, [(1000, 900), (1000, 500)]),
            map("m2", MapRole::Camera, 0.50, [(1000, 400), (1000, 800)]),
            map("m3", MapRole::Fused, 0.30, [(1000, 910), (1000, 790)]),
        ];
        let j = judge(&maps, &[], &T);
        assert_eq!(j.verdict, Verdict::FusionHelps, "{}", j.sentence);
        assert!((j.fusion_gain_nats.unwrap() - 0.10).abs() < 1e-12);
        let j = judge(
            &[maps[0].clone(), maps[1].clone(), MapFigures { mean_entropy_nats: 0.37, ..maps[2].clone() }],
            &[],
            &T,
        );
        assert_eq!(j.verdict, Verdict::NoGain, "{}", j.sentence);
    }

    #[test]
    fn a_sensor_that_disagrees_with_the_fused_map_is_named() {
        let maps = [
            map("m1", MapRole::Lidar, 0.40, [(1000, 900), (1000, 500)]),
            map("m2", MapRole::Camera, 0.50, [(1000, 400), (1000, 800)]),
            map("m3", MapRole::Fused, 0.30, [(1000, 890), (1000, 500)]),
        ];
        let j = judge(&maps, &[], &T);
        assert_eq!(j.verdict, Verdict::CheckSyncAndExtrinsics);
        assert_eq!(j.suspect.as_deref(), Some("camera"), "{}", j.sentence);
        assert!(j.sentence.contains("`camera`"), "{}", j.sentence);
        // Too few endpoints: no verdict on them.
        let few = Thresholds { min_endpoints: 2000, ..T };
        assert_ne!(judge(&maps, &[], &few).verdict, Verdict::CheckSyncAndExtrinsics);
    }

    #[test]
    fn a_lidar_turned_against_the_pose_sensors_is_named_before_hit_rates() {
        let maps = [
            map("m1", MapRole::Lidar, 0.40, [(1000, 900), (1000, 500)]),
            map("m2", MapRole::Camera, 0.50, [(1000, 400), (1000, 800)]),
            map("m3", MapRole::Fused, 0.30, [(1000, 890), (1000, 500)]),
        ];
        let turned = MotionAgreement { steps: 200, median_deg: 2.1, standard_error_deg: 0.1 };
        let j = judge(&maps, &[("laser".into(), turned)], &T);
        assert_eq!(
            (j.verdict, j.suspect.as_deref()),
            (Verdict::CheckSyncAndExtrinsics, Some("laser")),
            "{}",
            j.sentence
        );
        assert!(j.sentence.contains("+2.10°") && j.sentence.contains("`camera`"), "{}", j.sentence);
        // Within the tolerance, or within its noise: the hit rates decide.
        for m in [MotionAgreement { median_deg: 0.8, ..turned }, MotionAgreement { standard_error_deg: 0.9, ..turned }]
        {
            assert_eq!(judge(&maps, &[("laser".into(), m)], &T).suspect.as_deref(), Some("camera"));
        }
    }

    #[test]
    fn one_kind_of_evidence_has_nothing_to_fuse() {
        let m1 = MapFigures {
            hit_rates: vec![hits("laser", SensorKind::Lidar, 1000, 900)],
            ..map("m1", MapRole::Lidar, 0.4, [(1, 1); 2])
        };
        let m3 = MapFigures { role: MapRole::Fused, name: "m3".into(), ..m1.clone() };
        let j = judge(&[m1, m3], &[], &T);
        assert_eq!((j.verdict, j.fusion_gain_nats), (Verdict::NoGain, None));
        assert!(j.sentence.contains("nothing to fuse"), "{}", j.sentence);
    }
}
