//! `fusemap validate`, planned and run: the design document's validation (§5) for any
//! sensor set, in one pass over the log. (With more than two sensors making the map, the
//! same pass also builds one map without each, §4.3: reported, not judged; they share
//! `[limits]`' budget with M1, M2 and M3.)
//!
//! The pose track is built as `map` builds it (the estimator, SLAM). One mapping pass
//! then feeds three maps from the log's earlier part: M1 (the lidars), M2 (the cameras) and
//! M3 (every sensor), each placed with the same track; the later `validate.holdout_share`
//! of the log is held out of all three, and its lidar returns and camera obstacle pixels
//! are counted per cell instead ([`fusemap_core::fusion::HeldOut`]). Each sensor's hit
//! rate on each map and each map's mean entropy over the cells any of them observed give the
//! verdict ([`fusemap_core::metrics::judge`]).
//!
//! Pose sensors (odometry, IMU, GNSS) place every map's evidence and are in every map: to
//! leave one out would need a second track, which this pass does not build.

use crate::job::{JobError, LogJob};
use crate::outputs::{finish, prepare, ExportOptions, RunRecord, Summary};
use crate::recording::Inventory;
use crate::sensors::Bound;
use crate::track::{ChosenTrack, Track};
use crate::{PassMaps, PipelineError, Progress, Stage};
use fusemap_core::config::Plan;
use fusemap_core::fusion::{Engine, HeldOut, MapSet, SensorSelection, OBSTACLE_PROBABILITY};
use fusemap_core::geometry::Pose2;
use fusemap_core::grid::logodds::{logit, probability};
use fusemap_core::grid::{CellBox, FusionGrid, Raster};
use fusemap_core::measurement::{SensorId, SensorKind};
use fusemap_core::metrics::{
    binary_entropy, entropy_where, judge, motion_agreement, Judgement, MapFigures, MapRole, MotionAgreement,
    SensorHits, Verdict,
};
use fusemap_core::time::{Stamp, SyncMode};
use fusemap_io::npz::{NpyArray, NpyData};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The validation file's name in the output directory.
pub const VALIDATE_NPZ: &str = "fusion_validate.npz";

/// A validation, planned.
pub struct ValidateJob {
    /// The configuration, the log and the output directory.
    pub job: LogJob,
}

/// One held-out sensor.
#[derive(Clone, Debug, Serialize)]
pub struct HeldOutSensor {
    /// Its name.
    pub sensor: String,
    /// Its kind.
    pub kind: SensorKind,
    /// Its observations (scans, frames) in the held-out period.
    pub observations: u64,
    /// Their endpoints (lidar returns, camera obstacle pixels of static classes).
    pub endpoints: u64,
}

/// What `validate` found: `summary.json`'s `validation`.
#[derive(Clone, Debug, Serialize)]
pub struct Validation {
    /// The share of the log held out.
    pub holdout_share: f64,
    /// The maps built, M1, M2, M3 in that order (those the log allows), then with more
    /// than two sensors making the map, one map without each (`without NAME`).
    pub maps: Vec<MapFigures>,
    /// The maps that could not be built, each with why.
    pub not_built: Vec<String>,
    /// The held-out period's sensors.
    pub held_out: Vec<HeldOutSensor>,
    /// The cells the entropies are averaged over: those any map observed (a cell one map
    /// never observed counts at the prior in it).
    pub entropy_cells: u64,
    /// Where the fusion gain comes from: the cells the best single-sensor map already
    /// knows, and those only the fused map knows.
    pub gain_split: Option<GainSplit>,
    /// Where SLAM corrected a track of the pose sensors: its lidar's direction of travel
    /// against theirs (a wrong lidar yaw turns it).
    pub lidar_motion: Vec<LidarMotion>,
    /// The verdict.
    #[serde(flatten)]
    pub judgement: Judgement,
}

/// A SLAM lidar's direction of travel against the pose sensors'.
#[derive(Clone, Debug, Serialize)]
pub struct LidarMotion {
    /// The lidar.
    pub lidar: String,
    /// The angle between the two tracks' straight steps.
    #[serde(flatten)]
    pub agreement: MotionAgreement,
}

/// The pose sensors' track at the first lidar's scan stamps (with its clock offset, as
/// SLAM stamps its poses), before SLAM corrects it; empty for poses on the scan lines.
fn raw_at_scans(raw: &ChosenTrack, inv: &Inventory, bound: &Bound) -> Vec<(Stamp, Pose2)> {
    let (Track::Timed(track), Some(b)) = (&raw.track, bound.lidars.first()) else { return Vec::new() };
    let Some(topic) = inv.scans.get(&b.topic) else { return Vec::new() };
    let offset = crate::offset_ns(b.lidar.time_offset_s);
    let mut at: Vec<(Stamp, Pose2)> = topic
        .stamps
        .iter()
        .map(|s| Stamp(s.0.saturating_add(offset)))
        .filter_map(|t| track.pose_at(t, SyncMode::Interpolate).ok().map(|p| (t, p)))
        .collect();
    at.sort_by_key(|p| p.0);
    at.dedup_by_key(|p| p.0);
    at
}

/// Straight steps of at least this length compare the directions of travel, metres.
const MOTION_STEP_M: f64 = 0.5;
/// … turning less than this, radians.
const MOTION_MAX_TURN_RAD: f64 = 0.05;

/// SLAM's lidar against the pose sensors, where SLAM corrected a timed track.
fn lidar_motion(bound: &Bound, chosen: &ChosenTrack, raw: &[(Stamp, Pose2)]) -> Vec<(String, MotionAgreement)> {
    let (Some(slam), Some(b)) = (&chosen.slam, bound.lidars.first()) else { return Vec::new() };
    let pairs: Vec<(Pose2, Pose2)> = slam
        .scan_poses
        .iter()
        .filter_map(|(t, p)| raw.binary_search_by_key(t, |r| r.0).ok().map(|i| (raw[i].1, *p)))
        .collect();
    motion_agreement(&pairs, MOTION_STEP_M, MOTION_MAX_TURN_RAD)
        .map(|m| (b.lidar.name.clone(), m))
        .into_iter()
        .collect()
}

/// What the run wrote and found.
pub struct ValidateRun {
    /// The fused map's summary (`summary.json`, with `validation`).
    pub summary: Summary,
    /// The validation.
    pub validation: Validation,
}

/// The maps of the pass: M3 first (the primary, written as the run's map), then M1, M2,
/// then the leave-one-out maps.
fn validation_maps(plan: &Plan, inv: &Inventory, bound: &Bound) -> Result<MapSet, PipelineError> {
    let grid = || FusionGrid::new(plan.geometry, plan.occupancy);
    let mut maps = MapSet::new("m3", SensorSelection::All, grid())
        .with("m1", SensorSelection::Kinds(vec![SensorKind::Lidar]), grid())
        .with("m2", SensorSelection::Kinds(vec![SensorKind::Camera]), grid());
    // §4.3's leave-one-out maps, when more than two sensors make the map.
    let cameras = crate::map_pass::planned_cameras(plan, inv, &mut Vec::new())?;
    let names: Vec<String> =
        bound.lidars.iter().map(|b| b.lidar.name.clone()).chain(cameras.into_iter().map(|c| c.name)).collect();
    if names.len() > 2 {
        for n in names {
            maps.add(format!("{LEFT_OUT}{n}"), SensorSelection::without(vec![n]), grid());
        }
    }
    Ok(maps)
}

/// The name of the map without sensor `x` is this followed by `x`.
const LEFT_OUT: &str = "without ";

impl ValidateJob {
    /// `fusemap validate [--config C] --out DIR LOG`.
    pub fn plan(config: Option<&Path>, log: &Path, out: &Path) -> Result<Self, JobError> {
        Ok(Self { job: LogJob::plan(config, log, out)? })
    }

    /// Maps, validates and writes the set: the fused map's files, `fusion_validate.npz`
    /// and `summary.json` with its `validation`.
    pub fn run(self, progress: &mut dyn FnMut(Progress)) -> Result<ValidateRun, JobError> {
        let started = Instant::now();
        let job = &self.job;
        let (plan, input) = (&job.plan, job.log.display().to_string());
        let outputs = prepare(&job.out, &job.inputs)?;
        let named = |e| job.named(e);
        let inv = job.read(progress)?;
        let (run, validation, rasters) = validated(plan, &inv, progress).map_err(named)?;
        write_validate_npz(&outputs.staged(VALIDATE_NPZ), &validation, &rasters, plan)?;
        let mut notes = run.notes;
        notes.push(format!("validation: {}", validation.judgement.sentence));
        let record = RunRecord {
            source_kind: &run.format.to_string(),
            source: &input,
            started,
            notes,
            log: Some(serde_json::to_value(&run.report)?),
            trajectory: Some(&run.trajectory),
            validation: Some(serde_json::to_value(&validation)?),
            calibration: None,
            endpoints: None,
            map_from_odom: run.map_from_odom.as_ref().map(|(f, m)| (f.as_str(), *m)),
            seconds: crate::outputs::Seconds::of_log(&run.report),
        };
        let export = ExportOptions::of(plan, None);
        let summary = finish(&run.engine, outputs, &export, record)?;
        Ok(ValidateRun { summary, validation })
    }
}

/// The pass of `validate` over a log already read: the track as `map` builds it, then the
/// maps of [`validation_maps`] from the earlier part and the held-out later part; the
/// run, the validation and each map's raster. `calibrate` runs it again with the
/// calibrated mounts.
pub(crate) fn validated(
    plan: &Plan,
    inv: &Inventory,
    progress: &mut dyn FnMut(Progress),
) -> Result<(crate::MapRun, Validation, Vec<Option<Raster>>), PipelineError> {
    let (bound, raw, track_s) = crate::run::prepare_track(plan, inv)?;
    let raw_at_scans = raw_at_scans(&raw, inv, &bound);
    let (chosen, track_s) = crate::run::correct(plan, inv, &bound, raw, track_s, progress)?;
    let motion = lidar_motion(&bound, &chosen, &raw_at_scans);
    let set = validation_maps(plan, inv, &bound)?;
    let maps =
        PassMaps { set: Some(set), holdout_share: Some(plan.holdout_share), camera_samples: false, endpoints: false };
    let run = crate::map_with_track(plan, inv, &bound, chosen, track_s, maps, progress)?;
    let (validation, rasters) = validate(&run.engine, plan, motion)?;
    Ok((run, validation, rasters))
}

/// The sensors registered with the engine, by id.
fn sensors(engine: &Engine) -> Vec<(SensorId, String, SensorKind)> {
    engine.sensor_stats().enumerate().map(|(i, s)| (SensorId(i as u16), s.name.clone(), s.kind)).collect()
}

/// The figures of every map the log allows, the verdict, and each map's raster over the
/// shared cells (`None`: not built).
fn validate(
    engine: &Engine,
    plan: &Plan,
    motion: Vec<(String, MotionAgreement)>,
) -> Result<(Validation, Vec<Option<Raster>>), PipelineError> {
    let held = engine.held_out().cloned().unwrap_or_default();
    let all = sensors(engine);
    let (built, mut not_built) = built_maps(engine, &all);
    let area = shared_area(built.iter().map(|b| b.4), &not_built, plan)?;
    let cells = (area.width() as u64).saturating_mul(area.height() as u64);
    let mut rasters: Vec<Option<Raster>> = vec![None, None, None];
    for (name, _, _, grid, _) in &built {
        let slot = ROLES.iter().position(|r| r.0 == *name).expect("a role");
        rasters[slot] = Some(grid.raster(area));
    }
    // The same cells for every map (§5.1): those any map observed, unknown ones at the
    // prior; never-observed cells of the box would only dilute the differences.
    let mut shared = vec![false; cells as usize];
    for r in rasters.iter().flatten() {
        shared.iter_mut().zip(&r.known).for_each(|(s, &k)| *s |= k);
    }
    let mut figures = Vec::new();
    for (name, role, used, grid, _) in built {
        let slot = ROLES.iter().position(|r| r.0 == name).expect("a role");
        let raster = rasters[slot].as_ref().expect("rastered above");
        figures.push(MapFigures {
            name: name.to_string(),
            role,
            sensors: used,
            mean_entropy_nats: entropy_where(raster, &shared).map_or(f64::NAN, |e| e.0),
            hit_rates: hit_rates(&held, &all, grid),
        });
    }
    figures.extend(left_out(engine, area, &shared, &held, &all));
    let entropy_cells = shared.iter().filter(|&&s| s).count() as u64;
    let held_out = all
        .iter()
        .filter(|(id, ..)| held.observations(*id) > 0)
        .map(|(id, name, kind)| {
            let endpoints = held.hit_rate(*id, engine.maps().primary().grid()).endpoints;
            HeldOutSensor { sensor: name.clone(), kind: *kind, observations: held.observations(*id), endpoints }
        })
        .collect::<Vec<_>>();
    if held_out.is_empty() {
        not_built.push("no hit rates: no sensor observed anything in the held-out period".into());
    }
    let split = gain_split(&figures, &rasters, &shared);
    let mut judgement = judge(&figures, &motion, &plan.validation);
    if let (Verdict::NoGain, Some(_), Some(g)) = (judgement.verdict, judgement.fusion_gain_nats, &split) {
        judgement.sentence.push_str(&why_no_gain(g, plan));
    }
    let validation = Validation {
        holdout_share: plan.holdout_share,
        maps: figures,
        not_built,
        held_out,
        entropy_cells,
        gain_split: split,
        lidar_motion: motion.into_iter().map(|(lidar, agreement)| LidarMotion { lidar, agreement }).collect(),
        judgement,
    };
    Ok((validation, rasters))
}

/// The box of every built map's observed cells (`areas`), which the maps are compared on
/// cell by cell; refused when no map was built or the box is past `limits.export_cells`.
fn shared_area(
    areas: impl Iterator<Item = CellBox>,
    not_built: &[String],
    plan: &Plan,
) -> Result<CellBox, PipelineError> {
    let Some(area) = areas.reduce(CellBox::union) else {
        return Err(PipelineError::refused(
            Stage::Validation,
            format!("nothing to validate: {}", not_built.join("; ")),
        ));
    };
    let cells = (area.width() as u64).saturating_mul(area.height() as u64);
    if cells > plan.limits.export_cells {
        return Err(PipelineError::refused(
            Stage::Validation,
            format!(
                "the maps span {} × {} cells, more than limits.export_cells ({}): the validation compares them cell \
             by cell on one raster; raise the limit or use a coarser map.resolution",
                area.width(),
                area.height(),
                plan.limits.export_cells
            ),
        ));
    }
    Ok(area)
}

/// The roles of the validation's maps, in the order of `fusion_validate.npz`.
const ROLES: [(&str, MapRole); 3] = [("m1", MapRole::Lidar), ("m2", MapRole::Camera), ("m3", MapRole::Fused)];

/// A map the pass built: its name, role, sensors, grid and observed box.
type Built<'a> = (&'static str, MapRole, Vec<String>, &'a FusionGrid, CellBox);

/// M1, M2 and M3 as the pass built them, and those it could not build, each with why.
fn built_maps<'a>(engine: &'a Engine, all: &[(SensorId, String, SensorKind)]) -> (Vec<Built<'a>>, Vec<String>) {
    let mut built = Vec::new();
    let mut not_built = Vec::new();
    for (name, role) in ROLES {
        let m = engine.maps().by_name(name).expect("the validation's maps");
        let used: Vec<String> =
            all.iter().filter(|(id, _, kind)| m.sensors().includes(*id, *kind)).map(|(_, n, _)| n.clone()).collect();
        match (used.is_empty(), m.grid().known_box()) {
            (true, _) => not_built.push(format!("{name}: {}", missing(&role))),
            (false, None) => not_built.push(format!(
                "{name}: its sensors observed nothing before the held-out period (the log is shorter than the \
                 training period, its stamps do not advance, or its sensors are silent until late)"
            )),
            (false, Some(b)) => built.push((name, role, used, m.grid(), b)),
        }
    }
    (built, not_built)
}

/// Why the fusion gains nothing: where the cells are, and how certain.
fn why_no_gain(g: &GainSplit, plan: &Plan) -> String {
    format!(
        ". Why: the {} map already knows {:.1} % of the cells, and there the fused map is {:.4} nats more \
         certain on average ({:.1} % of them are at a clamp already, where no evidence lowers the entropy: \
         map.clamp_min {} holds {:.3} nats); the {} cells only the fused map knows are {:.3} nats more certain \
         each",
        g.single,
        100.0 * g.shared_cells as f64 / (g.shared_cells + g.added_cells).max(1) as f64,
        g.shared_gain_nats,
        100.0 * g.at_clamp_share,
        plan.occupancy.clamp_min,
        binary_entropy(plan.occupancy.clamp_min),
        g.added_cells,
        g.added_gain_nats
    )
}

/// The figures of the leave-one-out maps, over the same cells as M1, M2 and M3 (M3 knows
/// every cell they know).
fn left_out(
    engine: &Engine,
    area: CellBox,
    shared: &[bool],
    held: &HeldOut,
    all: &[(SensorId, String, SensorKind)],
) -> Vec<MapFigures> {
    // A sensor the pass did not map (a camera left out with a note) never got an id: its
    // map is M3 again, and not reported.
    let unmapped = |m: &&fusemap_core::fusion::MapEntry| matches!(m.sensors(), SensorSelection::Without { ids, .. } if ids.is_empty());
    let maps = engine.maps().iter().filter(|m| m.name().starts_with(LEFT_OUT)).filter(|m| !unmapped(m));
    maps.map(|m| MapFigures {
        name: m.name().to_string(),
        role: MapRole::LeftOut,
        sensors: all.iter().filter(|(id, _, kind)| m.sensors().includes(*id, *kind)).map(|s| s.1.clone()).collect(),
        mean_entropy_nats: entropy_where(&m.grid().raster(area), shared).map_or(f64::NAN, |e| e.0),
        hit_rates: hit_rates(held, all, m.grid()),
    })
    .collect()
}

/// Where the fusion gain comes from (see [`Validation::gain_split`]).
#[derive(Clone, Debug, Serialize)]
pub struct GainSplit {
    /// The best (lowest-entropy) single-sensor map.
    pub single: String,
    /// Cells it knows.
    pub shared_cells: u64,
    /// Its entropy minus the fused map's there, mean per cell, nats.
    pub shared_gain_nats: f64,
    /// Cells only the fused map knows (the other sensors' coverage).
    pub added_cells: u64,
    /// The prior's entropy minus the fused map's there, mean per cell, nats.
    pub added_gain_nats: f64,
    /// The share of `shared_cells` the single map holds at a clamp (`map.clamp_min`,
    /// `map.clamp_max`): no evidence makes them more certain, so fusion cannot lower
    /// their entropy.
    pub at_clamp_share: f64,
}

/// The fusion gain split into sharper cells and new cells.
fn gain_split(figures: &[MapFigures], rasters: &[Option<Raster>], shared: &[bool]) -> Option<GainSplit> {
    let best = figures
        .iter()
        .filter(|m| matches!(m.role, MapRole::Lidar | MapRole::Camera))
        .min_by(|a, b| a.mean_entropy_nats.total_cmp(&b.mean_entropy_nats))?;
    let slot = match best.role {
        MapRole::Lidar => 0,
        _ => 1,
    };
    let (single, fused) = (rasters[slot].as_ref()?, rasters[2].as_ref()?);
    let h = |r: &Raster, i: usize| binary_entropy(probability(r.log_odds[i] as f64));
    let clamps = [logit(single.params.clamp_min) as f32, logit(single.params.clamp_max) as f32];
    let (mut sn, mut sg, mut an, mut ag, mut clamped) = (0u64, 0.0, 0u64, 0.0, 0u64);
    for i in (0..shared.len()).filter(|&i| shared[i]) {
        let d = h(single, i) - h(fused, i);
        if single.known[i] {
            (sn, sg) = (sn + 1, sg + d);
            clamped += u64::from(clamps.iter().any(|c| (single.log_odds[i] - c).abs() < 1e-3));
        } else {
            (an, ag) = (an + 1, ag + d);
        }
    }
    let mean = |sum: f64, n: u64| if n > 0 { sum / n as f64 } else { 0.0 };
    Some(GainSplit {
        single: best.name.clone(),
        shared_cells: sn,
        shared_gain_nats: mean(sg, sn),
        added_cells: an,
        added_gain_nats: mean(ag, an),
        at_clamp_share: if sn > 0 { clamped as f64 / sn as f64 } else { 0.0 },
    })
}

/// Why a map of `role` has no sensor.
fn missing(role: &MapRole) -> &'static str {
    match role {
        MapRole::Lidar => "no lidar is mapped",
        MapRole::Camera => {
            "no camera is mapped (the log has none, or its streams are unusable: see the notes), so the camera's \
             map and its hit rates are left out"
        }
        MapRole::Fused | MapRole::LeftOut => "no sensor is mapped",
    }
}

/// Every held-out sensor's hit rate on `grid`.
fn hit_rates(held: &HeldOut, sensors: &[(SensorId, String, SensorKind)], grid: &FusionGrid) -> Vec<SensorHits> {
    sensors
        .iter()
        .filter(|(id, ..)| held.observations(*id) > 0)
        .map(|(id, name, kind)| SensorHits { sensor: name.clone(), kind: *kind, hit: held.hit_rate(*id, grid) })
        .collect()
}

/// Writes `fusion_validate.npz` (see the README's "Validation" for its arrays).
fn write_validate_npz(
    path: &Path,
    v: &Validation,
    rasters: &[Option<Raster>],
    plan: &Plan,
) -> Result<(), fusemap_io::Error> {
    let shape_of = rasters.iter().flatten().next().map(|r| (r.height, r.width, r.resolution, r.origin));
    let (h, w, resolution, origin) = shape_of.unwrap_or((0, 0, plan.geometry.resolution(), Default::default()));
    let occupancy = |r: &Option<Raster>| -> Vec<f32> {
        match r {
            Some(r) => r
                .log_odds
                .iter()
                .zip(&r.known)
                .map(|(&l, &k)| if k { probability(l as f64) as f32 } else { f32::NAN })
                .collect(),
            None => vec![f32::NAN; h * w],
        }
    };
    let (m1, m2, m3) = (occupancy(&rasters[0]), occupancy(&rasters[1]), occupancy(&rasters[2]));
    let by_role = |role: MapRole| v.maps.iter().find(|m| m.role == role);
    let roles = [MapRole::Lidar, MapRole::Camera, MapRole::Fused];
    let entropy: Vec<f64> = roles.iter().map(|r| by_role(*r).map_or(f64::NAN, |m| m.mean_entropy_nats)).collect();
    let held: Vec<String> = v.held_out.iter().map(|s| s.sensor.clone()).collect();
    let rate = |m: Option<&MapFigures>, sensor: Option<&str>| -> f64 {
        let Some(m) = m else { return f64::NAN };
        let hits = m.hit_rates.iter().filter(|h| sensor.is_none_or(|s| h.sensor == s));
        let (e, k) = hits.fold((0u64, 0u64), |(e, k), h| (e + h.hit.endpoints, k + h.hit.hits));
        if e > 0 {
            k as f64 / e as f64
        } else {
            f64::NAN
        }
    };
    let hit_rate: Vec<f64> = roles.iter().map(|r| rate(by_role(*r), None)).collect();
    let by_sensor: Vec<f64> =
        roles.iter().flat_map(|r| held.iter().map(move |s| (*r, s))).map(|(r, s)| rate(by_role(r), Some(s))).collect();
    let sensors: Vec<String> =
        roles.iter().map(|r| by_role(*r).map_or(String::new(), |m| m.sensors.join(","))).collect();
    let params =
        [plan.holdout_share, OBSTACLE_PROBABILITY, plan.validation.min_gain_nats, plan.validation.hit_rate_drop];
    let (res, org) = ([resolution], [origin.x, origin.y]);
    let verdict =
        [serde_json::to_value(v.judgement.verdict).ok().and_then(|j| j.as_str().map(String::from)).unwrap_or_default()];
    let arrays = vec![
        ("m1", NpyArray::new(&[h, w], NpyData::F32(&m1))),
        ("m2", NpyArray::new(&[h, w], NpyData::F32(&m2))),
        ("m3", NpyArray::new(&[h, w], NpyData::F32(&m3))),
        ("entropy", NpyArray::new(&[3], NpyData::F64(&entropy))),
        ("hit_rate", NpyArray::new(&[3], NpyData::F64(&hit_rate))),
        ("hit_rate_by_sensor", NpyArray::new(&[3, held.len()], NpyData::F64(&by_sensor))),
        ("held_out_sensors", NpyArray::new(&[held.len()], NpyData::Str(&held))),
        ("sensors", NpyArray::new(&[3], NpyData::Str(&sensors))),
        ("verdict", NpyArray::new(&[], NpyData::Str(&verdict))),
        ("params", NpyArray::new(&[params.len()], NpyData::F64(&params))),
        ("resolution", NpyArray::new(&[], NpyData::F64(&res))),
        ("origin", NpyArray::new(&[2], NpyData::F64(&org))),
    ];
    fusemap_io::npz::write_arrays(path, arrays)
}
