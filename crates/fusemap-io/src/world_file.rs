//! World files for the simulator: walls, a trajectory and a scanner in one small TOML
//! file (TOML v1.0.0, <https://toml.io/en/v1.0.0>), so a test world can be written and
//! reviewed as text instead of code. `worlds/corridor.toml` at the repository root is the
//! design document's corridor (§3.1, §3.3).
//!
//! ```toml
//! # The simulated 2D lidar (fusemap_core::sim::ScannerSpec).
//! [scanner]
//! beams = 181                        # beams per scan, >= 1
//! angle_min = -1.5707963267948966    # first beam, radians, sensor frame
//! angle_max = 1.5707963267948966     # last beam, radians
//! range_max = 10.0                   # metres; no wall within it reads exactly range_max
//! rate_hz = 10.0                     # scans per second (optional, default 10)
//!
//! # One table per wall: a line segment between two points, metres, world frame.
//! [[wall]]
//! from = [-20.0, 2.0]
//! to = [4.0, 2.0]
//!
//! # The robot's poses [x, y, theta] (metres, radians), one scan at each. Either a list:
//! [trajectory]
//! poses = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]
//! # or a straight line, pose i = start + i * step for i = 0 .. count - 1:
//! # start = [0.0, 0.0, 0.0]
//! # step = [0.1, 0.0, 0.0]
//! # count = 40
//! ```
//!
//! Every table refuses unknown keys. Errors name the file and the line for TOML syntax
//! and type errors, and the field path (`wall[3].to`, `trajectory.count`) — with its line
//! when it is written in the file — for values that parse but make no sense.

use crate::config_file::{field_error, read_text, toml_error};
use crate::Result;
use fusemap_core::config::LimitsConfig;
use fusemap_core::geometry::{Point2, Pose2};
use fusemap_core::sim::{ScannerSpec, Segment, World};
use serde::Deserialize;
use std::path::Path;

/// A loaded, validated world file.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldFile {
    /// The walls.
    pub world: World,
    /// The simulated scanner.
    pub scanner: ScannerSpec,
    /// `world_from_base` of each scan, in order.
    pub poses: Vec<Pose2>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWorld {
    scanner: ScannerSpec,
    #[serde(default)]
    wall: Vec<RawWall>,
    trajectory: RawTrajectory,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWall {
    from: Vec<f64>,
    to: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTrajectory {
    poses: Option<Vec<Vec<f64>>>,
    start: Option<Vec<f64>>,
    step: Option<Vec<f64>>,
    count: Option<u64>,
}

/// Reads and validates the world file at `path`.
///
/// Errors: [`Error::Io`](crate::Error::Io) when the file cannot be read,
/// [`Error::Format`](crate::Error::Format) for anything
/// wrong inside it (see the module documentation).
pub fn load_world(path: &Path) -> Result<WorldFile> {
    load_world_with(path, &LimitsConfig::default())
}

/// [`load_world`] within `limits` (`world_poses`, `beams_per_scan`).
pub fn load_world_with(path: &Path, limits: &LimitsConfig) -> Result<WorldFile> {
    let text = read_text(path)?;
    parse_world_str_with(&text, path, limits)
}

/// Parses and validates world-file `text` within the default limits; `path` is only used
/// in error messages.
pub fn parse_world_str(text: &str, path: &Path) -> Result<WorldFile> {
    parse_world_str_with(text, path, &LimitsConfig::default())
}

/// [`parse_world_str`] within `limits` (`world_poses`, `beams_per_scan`).
pub fn parse_world_str_with(text: &str, path: &Path, limits: &LimitsConfig) -> Result<WorldFile> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let raw: RawWorld = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    let bad = |field: &str, message: String| field_error(path, text, field, message);

    let scanner =
        check_scanner(&raw.scanner, limits.beams_per_scan).map_err(|(f, m)| bad(&format!("scanner.{f}"), m))?;

    if raw.wall.is_empty() {
        return Err(bad("wall", "the world needs at least one [[wall]] table".into()));
    }
    let mut segments = Vec::with_capacity(raw.wall.len());
    for (i, w) in raw.wall.iter().enumerate() {
        let a = point(&w.from).map_err(|m| bad(&format!("wall[{i}].from"), m))?;
        let b = point(&w.to).map_err(|m| bad(&format!("wall[{i}].to"), m))?;
        if a == b {
            return Err(bad(
                &format!("wall[{i}].to"),
                format!("the wall has zero length (from and to are both ({}, {}))", a.x, a.y),
            ));
        }
        segments.push(Segment { a, b });
    }

    // The cost is checked before the poses are built (10⁷ of them take a while); a count
    // past world_poses is left to `trajectory`'s own error.
    let t = &raw.trajectory;
    let n = t.poses.as_ref().map_or(t.count.unwrap_or(0), |p| p.len() as u64);
    if n <= limits.world_poses {
        check_work(n as usize, scanner.beams, segments.len(), limits.world_beams).map_err(|(f, m)| {
            let f = match (f, &t.poses) {
                ("trajectory", Some(_)) => "trajectory.poses",
                ("trajectory", None) => "trajectory.count",
                _ => f,
            };
            bad(f, m)
        })?;
    }
    let poses = trajectory(&raw.trajectory, limits.world_poses).map_err(|(f, m)| bad(&format!("trajectory{f}"), m))?;
    Ok(WorldFile { world: World { segments }, scanner, poses })
}

/// Beam-wall intersection tests a world run may make (every beam is tested against every
/// wall): 4 × 10⁹, about ten seconds.
pub const MAX_WORLD_RAY_TESTS: f64 = 4e9;

/// Checks what simulating the scans costs: a world of `poses` poses, `beams` beams a
/// scan and `walls` walls, within `max_beams` in all (`limits.world_beams`). Errors are
/// (field, message). `world_poses` and
/// `beams_per_scan` alone do not bound it: 10⁵ poses of 181 beams took 7.5 s, so the 10⁷
/// `world_poses` allows would take 12 minutes, and hours among 80,000 walls.
fn check_work(
    poses: usize,
    beams: usize,
    walls: usize,
    max_beams: u64,
) -> std::result::Result<(), (&'static str, String)> {
    let total = poses as f64 * beams as f64;
    if total > max_beams as f64 {
        let why = format!(
            "{poses} poses of {beams} beams are {total:.3e} beams, more than the {max_beams:.0e} a world run may cast (limits.world_beams raises it)"
        );
        return Err(("trajectory", why));
    }
    let tests = total * walls as f64;
    if tests > MAX_WORLD_RAY_TESTS {
        let why = format!(
            "{walls} walls met by {total:.3e} beams are {tests:.3e} beam-wall tests, more than the {MAX_WORLD_RAY_TESTS:.0e} a world run may make: fewer walls or fewer poses"
        );
        return Err(("wall", why));
    }
    Ok(())
}

/// Checks a scanner; errors are (field name, message).
fn check_scanner(s: &ScannerSpec, max_beams: u64) -> std::result::Result<ScannerSpec, (&'static str, String)> {
    if s.beams == 0 || s.beams as u64 > max_beams {
        let why = format!("must be between 1 and {max_beams} (limits.beams_per_scan raises it), got {}", s.beams);
        return Err(("beams", why));
    }
    for (name, v) in [("angle_min", s.angle_min), ("angle_max", s.angle_max)] {
        if !v.is_finite() {
            return Err((name, format!("must be a finite number of radians, got {v}")));
        }
    }
    if s.beams > 1 && s.angle_min >= s.angle_max {
        return Err((
            "angle_max",
            format!("must be above angle_min ({}) when there are several beams, got {}", s.angle_min, s.angle_max),
        ));
    }
    if s.beams == 1 && s.angle_min > s.angle_max {
        return Err(("angle_max", format!("must not be below angle_min ({}), got {}", s.angle_min, s.angle_max)));
    }
    if !(s.range_max.is_finite() && s.range_max > 0.0) {
        return Err(("range_max", format!("must be a positive number of metres, got {}", s.range_max)));
    }
    if !(s.rate_hz.is_finite() && s.rate_hz > 0.0) {
        return Err(("rate_hz", format!("must be a positive number of scans per second, got {}", s.rate_hz)));
    }
    Ok(*s)
}

/// `[x, y]` with finite coordinates.
fn point(v: &[f64]) -> std::result::Result<Point2, String> {
    match *v {
        [x, y] if x.is_finite() && y.is_finite() => Ok(Point2::new(x, y)),
        [x, y] => Err(format!("coordinates must be finite numbers, got [{x}, {y}]")),
        _ => Err(format!("expected a point [x, y], got {} numbers", v.len())),
    }
}

/// `[x, y, theta]` with finite components.
fn pose(v: &[f64]) -> std::result::Result<Pose2, String> {
    match *v {
        [x, y, t] if x.is_finite() && y.is_finite() && t.is_finite() => Ok(Pose2::new(x, y, t)),
        [x, y, t] => Err(format!("components must be finite numbers, got [{x}, {y}, {t}]")),
        _ => Err(format!("expected a pose [x, y, theta], got {} numbers", v.len())),
    }
}

/// The trajectory's poses; errors are (field suffix such as `.count`, message).
fn trajectory(t: &RawTrajectory, max_poses: u64) -> std::result::Result<Vec<Pose2>, (String, String)> {
    let line_keys = t.start.is_some() || t.step.is_some() || t.count.is_some();
    match (&t.poses, line_keys) {
        (Some(_), true) => Err((String::new(), "give either `poses` or `start`, `step` and `count`, not both".into())),
        (None, false) => {
            Err((String::new(), "no poses: give `poses = [[x, y, theta], ...]` or `start`, `step` and `count`".into()))
        }
        (Some(list), false) => {
            if list.is_empty() {
                return Err((".poses".into(), "the trajectory needs at least one pose".into()));
            }
            if list.len() as u64 > max_poses {
                let why = format!("{} poses, more than {max_poses} (limits.world_poses raises it)", list.len());
                return Err((".poses".into(), why));
            }
            list.iter().enumerate().map(|(i, p)| pose(p).map_err(|m| (format!(".poses[{i}]"), m))).collect()
        }
        (None, true) => {
            let need = |name: &str| {
                (format!(".{name}"), "missing: the line form needs `start`, `step` and `count`".to_string())
            };
            let start = pose(t.start.as_deref().ok_or_else(|| need("start"))?).map_err(|m| (".start".into(), m))?;
            let step = pose(t.step.as_deref().ok_or_else(|| need("step"))?).map_err(|m| (".step".into(), m))?;
            let count = t.count.ok_or_else(|| need("count"))?;
            if count == 0 || count > max_poses {
                let why = format!("must be between 1 and {max_poses} (limits.world_poses raises it), got {count}");
                return Err((".count".into(), why));
            }
            (0..count)
                .map(|i| {
                    let k = i as f64;
                    let p = Pose2::new(start.x + k * step.x, start.y + k * step.y, start.theta + k * step.theta);
                    if p.x.is_finite() && p.y.is_finite() && p.theta.is_finite() {
                        Ok(p)
                    } else {
                        Err((".step".into(), format!("pose {i} is not finite: the step is too large")))
                    }
                })
                .collect()
        }
    }
}

impl WorldFile {
    /// The number of scans the trajectory gives.
    pub fn scan_count(&self) -> usize {
        self.poses.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Error, Location};
    use fusemap_core::sim::{corridor, SimulatedRun};
    use std::path::PathBuf;

    const GOOD: &str = "\
[scanner]
beams = 3
angle_min = -1.0
angle_max = 1.0
range_max = 5.0

[[wall]]
from = [0.0, 1.0]
to = [2, 1]

[[wall]]
from = [2.0, 1.0]
to = [2.0, -1.0]

[trajectory]
poses = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]
";

    fn parse(text: &str) -> Result<WorldFile> {
        parse_world_str(text, Path::new("w.toml"))
    }

    #[test]
    fn a_world_whose_scans_would_take_hours_is_refused_naming_what_to_shrink() {
        let max = LimitsConfig::default().world_beams;
        assert!(check_work(40, 181, 3, max).is_ok());
        assert!(check_work(100_000, 181, 3, max).is_ok());
        let (f, m) = check_work(10_000_000, 181, 3, max).unwrap_err();
        assert_eq!(f, "trajectory");
        assert!(m.contains("1.810e9 beams, more than the 2e7") && m.contains("limits.world_beams"), "{m}");
        assert!(check_work(10_000_000, 181, 2, 2_000_000_000).is_ok(), "raised, it holds");
        let (f, m) = check_work(1000, 181, 80_000, max).unwrap_err();
        assert_eq!(f, "wall");
        assert!(m.contains("80000 walls") && m.contains("more than the 4e9"), "{m}");
    }

    #[test]
    fn poses_and_beams_past_the_limits_name_the_key_that_raises_them() {
        let limits = LimitsConfig { world_poses: 1, beams_per_scan: 2, ..Default::default() };
        let e = parse_world_str_with(GOOD, Path::new("w.toml"), &limits).unwrap_err().to_string();
        assert!(e.contains("scanner.beams") && e.contains("limits.beams_per_scan") && e.contains("got 3"), "{e}");
        let limits = LimitsConfig { world_poses: 1, ..Default::default() };
        let e = parse_world_str_with(GOOD, Path::new("w.toml"), &limits).unwrap_err().to_string();
        assert!(e.contains("trajectory.poses") && e.contains("2 poses, more than 1 (limits.world_poses"), "{e}");
        let line = GOOD
            .replace("poses = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]", "start = [0, 0, 0]\nstep = [1, 0, 0]\ncount = 5");
        let e = parse_world_str_with(&line, Path::new("w.toml"), &limits).unwrap_err().to_string();
        assert!(e.contains("trajectory.count") && e.contains("limits.world_poses") && e.contains("got 5"), "{e}");
        assert!(parse_world_str_with(GOOD, Path::new("w.toml"), &LimitsConfig::default()).is_ok());
    }

    fn loc(text: &str) -> (Location, String) {
        match parse(text).unwrap_err() {
            Error::Format { location, message, path } => {
                assert_eq!(path, Path::new("w.toml"));
                (location, message)
            }
            e => panic!("expected a format error, got {e}"),
        }
    }

    #[test]
    fn good_world() {
        let w = parse(GOOD).unwrap();
        assert_eq!(w.world.segments, vec![Segment::new(0.0, 1.0, 2.0, 1.0), Segment::new(2.0, 1.0, 2.0, -1.0)]);
        assert_eq!(w.scanner.beams, 3);
        assert_eq!(w.scanner.rate_hz, 10.0);
        assert_eq!(w.poses, vec![Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.5, 0.0, 0.1)]);
        assert_eq!(w.scan_count(), 2);
    }

    #[test]
    fn corridor_file_is_the_documents_corridor() {
        let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../worlds/corridor.toml");
        let w = load_world(&p).unwrap();
        assert_eq!(w.world, corridor());
        assert_eq!(w.scanner, ScannerSpec::document());
        assert_eq!(w.poses, SimulatedRun::document_corridor().poses);
    }

    #[test]
    fn syntax_error_names_line() {
        let (l, m) = loc(&GOOD.replace("to = [2, 1]", "to = [2 1]"));
        assert_eq!(l, Location::Line(9), "{m}");
        assert!(!m.contains('\n'), "{m}");
        let (l, _) = loc(&GOOD.replace("[trajectory]", "[trajectory"));
        assert_eq!(l, Location::Line(15));
        let (l, _) = loc(&GOOD.replace("beams = 3", "beams = -3"));
        assert_eq!(l, Location::Line(2));
        let (l, _) = loc(&GOOD.replace("range_max = 5.0", "range_max = \"far\""));
        assert_eq!(l, Location::Line(5));
    }

    #[test]
    fn unknown_key_names_key_and_line() {
        let (l, m) = loc(&GOOD.replace("to = [2, 1]", "to = [2, 1]\ncolour = \"red\""));
        assert_eq!(l, Location::Line(10));
        assert!(m.contains("colour"), "{m}");
        let (l, m) = loc(&format!("{GOOD}\n[robot]\nname = \"r2\"\n"));
        assert_eq!(l, Location::Line(18), "{m}");
        assert!(m.contains("robot"), "{m}");
    }

    #[test]
    fn zero_length_wall() {
        let (l, m) = loc(&GOOD.replace("to = [2.0, -1.0]", "to = [2.0, 1.0]"));
        assert_eq!(l, Location::LineField(13, "wall[1].to".into()));
        assert!(m.contains("zero length"), "{m}");
    }

    #[test]
    fn wrong_point_sizes() {
        let (l, _) = loc(&GOOD.replace("from = [0.0, 1.0]", "from = [0.0, 1.0, 3.0]"));
        assert_eq!(l, Location::LineField(8, "wall[0].from".into()));
        let (l, _) = loc(&GOOD.replace("[0.5, 0.0, 0.1]", "[0.5, 0.0]"));
        assert_eq!(l, Location::LineField(16, "trajectory.poses[1]".into()));
    }

    #[test]
    fn no_walls_or_poses() {
        let no_walls = "[scanner]\nbeams = 1\nangle_min = 0\nangle_max = 0\nrange_max = 1\n[trajectory]\ncount = 1\nstart = [0, 0, 0]\nstep = [0, 0, 0]\n";
        assert_eq!(loc(no_walls).0, Location::Field("wall".into()));
        let (l, _) = loc(&GOOD.replace("poses = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]", "poses = []"));
        assert_eq!(l, Location::LineField(16, "trajectory.poses".into()));
        let (l, _) = loc(&GOOD.replace("poses = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]", ""));
        assert_eq!(l, Location::LineField(15, "trajectory".into()));
        let (l, m) = loc(&GOOD.replace("[trajectory]\nposes = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]\n", ""));
        assert_eq!(l, Location::Line(1), "{m}");
        assert!(m.contains("trajectory"), "{m}");
        let line = |extra: &str| GOOD.replace("poses = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.1]]", extra);
        let (l, _) = loc(&line("start = [0, 0, 0]\nstep = [1, 0, 0]\ncount = 0"));
        assert_eq!(l, Location::LineField(18, "trajectory.count".into()));
        let (l, _) = loc(&line("start = [0, 0, 0]\nstep = [1, 0, 0]\ncount = 10000001"));
        assert_eq!(l, Location::LineField(18, "trajectory.count".into()));
        let (l, _) = loc(&line("start = [0, 0, 0]\ncount = 3"));
        assert_eq!(l, Location::Field("trajectory.step".into()));
        let (l, _) = loc(&line("start = [0, 0, 0]\nstep = [1e308, 0, 0]\ncount = 3"));
        assert_eq!(l, Location::LineField(17, "trajectory.step".into()));
        let (l, _) = loc(&line("poses = [[0, 0, 0]]\ncount = 3"));
        assert_eq!(l, Location::LineField(15, "trajectory".into()));
    }

    #[test]
    fn nan_and_bad_scanners() {
        let (l, m) = loc(&GOOD.replace("from = [0.0, 1.0]", "from = [nan, 1.0]"));
        assert_eq!(l, Location::LineField(8, "wall[0].from".into()));
        assert!(m.contains("finite"), "{m}");
        let (l, _) = loc(&GOOD.replace("[0.5, 0.0, 0.1]", "[0.5, inf, 0.1]"));
        assert_eq!(l, Location::LineField(16, "trajectory.poses[1]".into()));
        let (l, _) = loc(&GOOD.replace("angle_min = -1.0", "angle_min = nan"));
        assert_eq!(l, Location::LineField(3, "scanner.angle_min".into()));
        let (l, _) = loc(&GOOD.replace("angle_min = -1.0", "angle_min = 1.0"));
        assert_eq!(l, Location::LineField(4, "scanner.angle_max".into()));
        let (l, _) = loc(&GOOD.replace("beams = 3", "beams = 0"));
        assert_eq!(l, Location::LineField(2, "scanner.beams".into()));
        let (l, _) = loc(&GOOD.replace("range_max = 5.0", "range_max = 0"));
        assert_eq!(l, Location::LineField(5, "scanner.range_max".into()));
        let (l, _) = loc(&GOOD.replace("range_max = 5.0", "range_max = 5.0\nrate_hz = -1"));
        assert_eq!(l, Location::LineField(6, "scanner.rate_hz".into()));
        // One beam may point one way.
        let one = GOOD.replace("beams = 3", "beams = 1").replace("angle_min = -1.0", "angle_min = 1.0");
        assert_eq!(parse(&one).unwrap().scanner.beams, 1);
    }

    #[test]
    fn missing_file_is_io() {
        let p = std::env::temp_dir().join(format!("fusemap-no-such-world-{}.toml", std::process::id()));
        assert!(matches!(load_world(&p), Err(Error::Io { .. })));
    }
}
