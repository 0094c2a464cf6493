//! `validate` again with the calibration pasted in: a calibration must not make the map
//! worse, and when it does the report says so (issue: "Running validate with the
//! calibrated config must not get worse. If it does, say so.").
//!
//! Both validations run over the log already read, one with the configuration as given,
//! one with `calibration.toml`'s tables applied to it (each named sensor's mount and clock
//! offset), so they differ only by what the calibration changed.

use crate::recording::Inventory;
use crate::validate::{validated, Validation};
use crate::{PipelineError, Progress};
use fusemap_core::config::{ExtrinsicsSource, Plan, SensorKind};
use fusemap_core::metrics::Verdict;
use serde::Serialize;

/// A sensor's hit rate on the fused map may fall by this much before the calibration
/// counts as worse (the held-out points differ a little when a clock offset moves them
/// across the training period's end).
const HIT_RATE_SLACK: f64 = 0.02;

/// One validation's figures.
#[derive(Clone, Debug, Serialize)]
pub struct Figures {
    /// Its verdict.
    pub verdict: Verdict,
    /// The sensor it names, if any.
    pub suspect: Option<String>,
    /// The fused map's mean entropy, nats.
    pub fused_entropy_nats: f64,
    /// Each sensor's hit rate on the fused map.
    pub fused_hit_rates: Vec<(String, Option<f64>)>,
}

impl Figures {
    fn of(v: &Validation) -> Self {
        let m3 = v.maps.iter().find(|m| m.name == "m3");
        Self {
            verdict: v.judgement.verdict,
            suspect: v.judgement.suspect.clone(),
            fused_entropy_nats: m3.map_or(f64::NAN, |m| m.mean_entropy_nats),
            fused_hit_rates: m3
                .map(|m| m.hit_rates.iter().map(|h| (h.sensor.clone(), h.hit.rate)).collect())
                .unwrap_or_default(),
        }
    }
}

/// The validation before and after, and whether the calibration made it worse.
#[derive(Clone, Debug, Serialize)]
pub struct Revalidation {
    /// With the configuration as given.
    pub before: Figures,
    /// With `calibration.toml` applied.
    pub after: Figures,
    /// The calibrated configuration validates worse: it is judged a sync or extrinsics
    /// fault where the given one was not, or a sensor's hit rate on the fused map fell.
    pub worse: bool,
    /// In words.
    pub sentence: String,
}

/// `plan` with the tables of `calibration_toml` applied (mount and clock of each lidar and
/// camera it names); `Err` says why it cannot be.
fn applied(plan: &Plan, calibration_toml: &str) -> Result<Plan, String> {
    let pasted = fusemap_io::config_file::parse_config_str(calibration_toml, std::path::Path::new("calibration.toml"))
        .map_err(|e| e.to_string())?;
    let mut out = plan.clone();
    for t in &pasted.sensor {
        let Some(name) = &t.name else { continue };
        match t.kind {
            SensorKind::Lidar => {
                if let Some(l) = out.lidars.iter_mut().find(|l| &l.name == name) {
                    l.mount = t.base_from_sensor.unwrap_or(l.mount);
                    l.mount_given = true;
                    l.time_offset_s = t.time_offset_s;
                }
            }
            SensorKind::Camera => {
                if let Some(c) = out.cameras.iter_mut().find(|c| &c.name == name) {
                    c.mount = t.base_from_sensor.unwrap_or(c.mount);
                    c.mount_given = true;
                    c.time_offset_s = t.time_offset_s;
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Validates with the plan as given and with the calibration applied. `Ok(None)` with a
/// reason when it cannot tell: the mounts come from the log's TF, not the configuration.
pub(super) fn revalidate(
    plan: &Plan,
    inv: &Inventory,
    calibration_toml: &str,
    progress: &mut dyn FnMut(Progress),
) -> Result<Result<Revalidation, String>, PipelineError> {
    if plan.log.extrinsics != ExtrinsicsSource::Config {
        return Ok(Err("not re-validated with the calibration: the mounts come from the log's TF where it has them \
                       (`[log] extrinsics = \"config\"` makes the configured mounts count)"
            .into()));
    }
    let calibrated = match applied(plan, calibration_toml) {
        Ok(p) => p,
        Err(e) => return Ok(Err(format!("not re-validated: calibration.toml does not read back: {e}"))),
    };
    let before = Figures::of(&validated(plan, inv, progress)?.1);
    let after = Figures::of(&validated(&calibrated, inv, progress)?.1);
    let judged = |f: &Figures| f.verdict == Verdict::CheckSyncAndExtrinsics;
    let code =
        |v: Verdict| serde_json::to_value(v).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
    let fell: Vec<String> = after
        .fused_hit_rates
        .iter()
        .filter_map(|(s, a)| {
            let b = before.fused_hit_rates.iter().find(|(t, _)| t == s)?.1?;
            // A sensor with no held-out point left after the calibration fell too.
            (a.is_none_or(|a| a < b - HIT_RATE_SLACK)).then(|| match a {
                Some(a) => format!("`{s}` {b:.3} → {a:.3}"),
                None => format!("`{s}` {b:.3} → none"),
            })
        })
        .collect();
    let worse = (judged(&after) && !judged(&before)) || !fell.is_empty();
    let sentence = if worse {
        format!(
            "the calibration makes the validation worse (verdict {} → {}{}): keep the configured values",
            code(before.verdict),
            code(after.verdict),
            if fell.is_empty() { String::new() } else { format!("; hit rates on the fused map {}", fell.join(", ")) }
        )
    } else {
        format!(
            "validated with the calibration pasted in: verdict {} → {}, the fused map's mean entropy {:.4} → {:.4} nats, no sensor's hit rate on it falls by more than {HIT_RATE_SLACK}",
            code(before.verdict),
            code(after.verdict),
            before.fused_entropy_nats,
            after.fused_entropy_nats
        )
    };
    Ok(Ok(Revalidation { before, after, worse, sentence }))
}
