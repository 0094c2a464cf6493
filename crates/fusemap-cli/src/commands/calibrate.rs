//! `fusemap calibrate`: the lidar's mount and clock offset and the wheel odometry's scale and wheel base estimated from the
//! log, with 95 % intervals, and what it cannot determine. The job is the library's
//! ([`fusemap_pipeline::calibrate`]); this prints its table.

use crate::progress;
use anyhow::Result;
use fusemap_core::calibration::Interval;
use fusemap_pipeline::calibrate::{CalibrateJob, Calibration, CALIBRATION_TOML};
use std::fmt::Write;
use std::path::Path;

/// `fusemap calibrate [--config C] --out DIR LOG`.
pub fn run(config: Option<&Path>, log: &Path, out: &Path) -> Result<()> {
    let job = CalibrateJob::plan(config, log, out)?;
    let run = job.run(&mut progress::reporter())?;
    print!("{}", run.summary);
    print!("{}", table(&run.calibration));
    if !run.calibration.sensors.is_empty() {
        println!("calibration   {}", super::shown(&out.join(CALIBRATION_TOML)));
    }
    println!("outputs       {}", super::shown(out));
    super::fail_without_map(&run.summary, out)
}

/// The estimates, one line per parameter.
pub fn table(c: &Calibration) -> String {
    let mut s = String::new();
    let show = |i: &Interval, unit: &str, f: f64, d: usize| {
        format!("{:.d$} {unit} (95 %: {:.d$} .. {:.d$})", i.value * f, i.low * f, i.high * f)
    };
    for e in &c.sensors {
        let name = fusemap_io::text::printable(&e.name).into_owned();
        for (k, v, unit, f, d) in [
            ("x", &e.x, "m", 1.0, 4),
            ("y", &e.y, "m", 1.0, 4),
            ("z", &e.z, "m", 1.0, 4),
            ("roll", &e.roll, "°", 180.0 / std::f64::consts::PI, 3),
            ("pitch", &e.pitch, "°", 180.0 / std::f64::consts::PI, 3),
            ("yaw", &e.yaw, "°", 180.0 / std::f64::consts::PI, 3),
            ("scale", &e.scale, "×", 1.0, 4),
            ("time_offset_s", &e.time_offset_s, "s", 1.0, 4),
            ("wheel_base", &e.wheel_base, "× assumed", 1.0, 4),
        ] {
            if let Some(i) = v {
                let _ = writeln!(s, "calibrated    {name} {k} {}", show(i, unit, f, d));
            }
        }
    }
    for u in &c.undetermined {
        let _ = writeln!(s, "undetermined  {}", fusemap_io::text::printable(u));
    }
    s
}
