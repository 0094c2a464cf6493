//! The doctor's look at the pose sensors: GNSS fix quality over time, and how far the
//! wheel odometry's turn rate disagrees with the gyro's (a constant offset is the gyro's
//! bias or a mis-mounted IMU; bursts are wheel slip).

use crate::recording::Inventory;
use fusemap_core::config::{Plan, SensorKind};
use fusemap_core::estimator::DEFAULT_ALTITUDE_RANGE_M;
use fusemap_core::geometry::normalize_angle;
use fusemap_core::time::Stamp;
use fusemap_io::log::ros2::msgs::sensor_msgs::NavSatStatus;
use std::fmt::Write as _;

/// GNSS fix quality over time: for each fix topic, ten equal stretches of its span with
/// the fixes of each status, and the longest stretch without a usable fix (usable as the
/// plan's GNSS table for the topic judges it, altitude band included).
pub fn gnss_quality(plan: &Plan, inv: &Inventory, out: &mut String, findings: &mut Vec<String>) -> std::fmt::Result {
    // The band of the GNSS table each topic is bound to, as the run binds it (the default
    // where binding fails: doctor then reports why).
    let bound = crate::sensors::bind(plan, &crate::sensors::topics_by_kind(inv)).ok();
    let band_of = |topic: &str| {
        bound
            .as_ref()
            .and_then(|b| b.sensors.iter().find(|s| s.sensor.kind == SensorKind::Gnss && s.topic == topic))
            .map_or(DEFAULT_ALTITUDE_RANGE_M, |s| s.sensor.altitude_range_m)
    };
    for (topic, fixes) in &inv.gnss {
        let band = band_of(topic);
        let (Some(first), Some(last)) = (fixes.iter().map(|f| f.stamp).min(), fixes.iter().map(|f| f.stamp).max())
        else {
            continue;
        };
        writeln!(out)?;
        writeln!(out, "GNSS fix quality on {topic} ({} fixes), by tenth of its span:", fixes.len())?;
        writeln!(out, "| from s | to s | RTK fixed | SBAS | fix | no fix / NaN |")?;
        writeln!(out, "|---:|---:|---:|---:|---:|---:|")?;
        let span = (last.0 - first.0).max(1);
        let mut bins = [[0u64; 4]; 10];
        for f in fixes {
            let b = (((f.stamp.0 - first.0) as i128 * 10 / span as i128) as usize).min(9);
            let k = if !crate::gnss_fixes::usable_fix(f, band) {
                3
            } else {
                match f.status {
                    NavSatStatus::STATUS_GBAS_FIX => 0,
                    NavSatStatus::STATUS_SBAS_FIX => 1,
                    _ => 2,
                }
            };
            bins[b][k] += 1;
        }
        for (i, b) in bins.iter().enumerate() {
            let (a, z) = (span as f64 * i as f64 / 10.0 * 1e-9, span as f64 * (i + 1) as f64 / 10.0 * 1e-9);
            writeln!(out, "| {a:.1} | {z:.1} | {} | {} | {} | {} |", b[0], b[1], b[2], b[3])?;
        }
        let mut good: Vec<Stamp> =
            fixes.iter().filter(|f| crate::gnss_fixes::usable_fix(f, band)).map(|f| f.stamp).collect();
        good.sort_unstable();
        if good.is_empty() {
            findings.push(format!("{topic}: no usable fix at all (every one NO_FIX, NaN or out of range)"));
            continue;
        }
        let gaps = good.windows(2).map(|w| (w[1].secs_since(w[0]), w[0]));
        if let Some((g, at)) = gaps.max_by(|a, b| a.0.total_cmp(&b.0)) {
            let period = span as f64 * 1e-9 / fixes.len().max(1) as f64;
            if g > 5.0 * period.max(0.2) {
                findings.push(format!(
                    "{topic}: no usable fix for {g:.1} s from {:.1} s into the topic (a dropout: the estimator carries \
                     the pose on odometry and gyro, and the smoother closes it from both ends)",
                    at.secs_since(first)
                ));
            }
        }
    }
    Ok(())
}

/// Odometry turn rate against the gyro's, over one-second windows.
pub fn odometry_vs_gyro(inv: &Inventory, out: &mut String, findings: &mut Vec<String>) -> std::fmt::Result {
    let (Some((otopic, odom)), Some((itopic, imu))) = (inv.odom.iter().next(), inv.imu.iter().next()) else {
        return Ok(());
    };
    let mut o: Vec<(Stamp, f64)> =
        odom.iter().filter(|m| m.pose.is_finite()).map(|m| (m.stamp, m.pose.theta)).collect();
    o.sort_by_key(|s| s.0);
    let mut g: Vec<(Stamp, f64)> =
        imu.iter().filter(|m| m.angular_velocity[2].is_finite()).map(|m| (m.stamp, m.angular_velocity[2])).collect();
    g.sort_by_key(|s| s.0);
    if o.len() < 2 || g.is_empty() {
        return Ok(());
    }
    let mut diffs = Vec::new();
    let mut i = 0;
    let mut gi = 0;
    while i + 1 < o.len() {
        // One window: from sample i to the first sample at least 1 s later.
        let Some(j) = (i + 1..o.len()).find(|&j| o[j].0.secs_since(o[i].0) >= 1.0) else { break };
        let dt = o[j].0.secs_since(o[i].0);
        if dt <= 2.0 {
            let odo_rate = normalize_angle(o[j].1 - o[i].1) / dt;
            while gi < g.len() && g[gi].0 < o[i].0 {
                gi += 1;
            }
            let inside: Vec<f64> = g[gi..].iter().take_while(|s| s.0 <= o[j].0).map(|s| s.1).collect();
            if inside.len() >= 2 {
                diffs.push(odo_rate - inside.iter().sum::<f64>() / inside.len() as f64);
            }
        }
        i = j;
    }
    if diffs.is_empty() {
        return Ok(());
    }
    let n = diffs.len() as f64;
    let mean = diffs.iter().sum::<f64>() / n;
    let sd = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    let bursts = diffs.iter().filter(|d| (*d - mean).abs() > 0.05).count();
    writeln!(out)?;
    writeln!(
        out,
        "odometry {otopic} vs gyro {itopic} turn rate over {} one-second windows: mean difference {:.4} rad/s, \
         spread {:.4} rad/s, {} windows off by more than 0.05 rad/s",
        diffs.len(),
        mean,
        sd,
        bursts
    )?;
    if mean.abs() > 0.05 {
        findings.push(format!(
            "odometry and gyro turn rates differ by {mean:.3} rad/s on average: check the IMU's mount (its z axis \
             must point up in base_link, REP 103)"
        ));
    }
    if bursts > 0 {
        findings.push(format!(
            "{bursts} one-second windows where the odometry turns more than 0.05 rad/s away from the gyro: wheel slip \
             (the estimator down-weights the odometry there)"
        ));
    }
    Ok(())
}
