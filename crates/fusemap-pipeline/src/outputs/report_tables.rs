//! The sections of `report.html` that read the commands' own results: the validation's
//! maps and verdict, the calibration's estimates with their intervals and cost curves, and
//! the estimator's rejections and innovations over time.

use super::report_page::{escape, list_items, section};
use super::svg_plot::{svg, Plot};
use serde_json::Value;
use std::fmt::Write;

fn f(v: &Value, digits: usize) -> String {
    v.as_f64().map_or("—".into(), |x| format!("{x:.digits$}"))
}

/// §5's table: each map's sensors, mean entropy and hit rates; the verdict in words.
pub(crate) fn validation(v: &Value) -> String {
    let Some(maps) = v["maps"].as_array() else {
        return section("validation", "Validation", "<p class=\"none\">Not validated: <code>fusemap validate</code> builds M1, M2 and M3 and judges them (§5).</p>");
    };
    let mut sensors: Vec<String> = Vec::new();
    for m in maps {
        for h in m["hit_rates"].as_array().into_iter().flatten() {
            let name = h["sensor"].as_str().unwrap_or("").to_string();
            if !sensors.contains(&name) {
                sensors.push(name);
            }
        }
    }
    let mut s = String::from("<table><tr><th>map</th><th>sensors</th><th>mean entropy, nats</th>");
    for n in &sensors {
        let _ = write!(s, "<th>hit rate of {}</th>", escape(n));
    }
    s.push_str("</tr>");
    for m in maps {
        let used: Vec<&str> = m["sensors"].as_array().into_iter().flatten().filter_map(|x| x.as_str()).collect();
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td>",
            escape(m["name"].as_str().unwrap_or("")),
            escape(&used.join(", ")),
            f(&m["mean_entropy_nats"], 4)
        );
        for n in &sensors {
            let rate = m["hit_rates"].as_array().into_iter().flatten().find(|h| h["sensor"].as_str() == Some(n));
            let _ = write!(s, "<td>{}</td>", rate.map_or("—".into(), |h| f(&h["rate"], 3)));
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>");
    let _ = write!(
        s,
        "<p class=\"verdict\"><b>{}</b>: {}</p>",
        escape(v["verdict"].as_str().unwrap_or("")),
        escape(v["sentence"].as_str().unwrap_or(""))
    );
    for n in v["not_built"].as_array().into_iter().flatten().filter_map(|x| x.as_str()) {
        let _ = write!(s, "<p class=\"none\">Not built: {}</p>", escape(n));
    }
    section("validation", "Validation", &s)
}

/// The parameters of one calibrated sensor, as rows `(name, value, low, high)`.
fn parameters(c: &Value) -> Vec<[String; 4]> {
    let mut rows = Vec::new();
    for (key, unit, scale) in [
        ("x", "m", 1.0),
        ("y", "m", 1.0),
        ("z", "m", 1.0),
        ("roll", "°", 180.0 / std::f64::consts::PI),
        ("pitch", "°", 180.0 / std::f64::consts::PI),
        ("yaw", "°", 180.0 / std::f64::consts::PI),
        ("time_offset_s", "s", 1.0),
        ("scale", "× true distance", 1.0),
        ("wheel_base", "× assumed", 1.0),
    ] {
        let i = &c[key];
        if i.is_null() {
            continue;
        }
        let g = |k: &str| i[k].as_f64().map_or("—".into(), |x| format!("{:.4}", x * scale));
        rows.push([format!("{key}, {unit}"), g("value"), g("low"), g("high")]);
    }
    rows
}

/// The estimates with their 95 % intervals, the cost before and after, the cost curves,
/// and what the log does not determine.
pub(crate) fn calibration(c: &Value) -> String {
    let Some(list) = c["sensors"].as_array() else {
        return section("calibration", "Calibration", "<p class=\"none\">Not calibrated: <code>fusemap calibrate</code> estimates clock offsets, mounts and the odometry from the log.</p>");
    };
    let mut s = String::from("<table><tr><th>sensor</th><th>parameter</th><th>estimate</th><th>95 % low</th><th>95 % high</th><th>cost before → after</th></tr>");
    let mut plots = String::new();
    for sensor in list {
        let name = escape(sensor["name"].as_str().unwrap_or(""));
        let cost = format!("{} → {}", f(&sensor["cost_before"], 4), f(&sensor["cost_after"], 4));
        for [p, v, lo, hi] in parameters(sensor) {
            let _ = write!(
                s,
                "<tr><td>{name}</td><td>{}</td><td>{v}</td><td>{lo}</td><td>{hi}</td><td>{cost}</td></tr>",
                escape(&p)
            );
        }
        for (key, curve, label, scale) in [
            ("time_offset_s", "clock_curve", "clock offset, s", 1.0),
            ("yaw", "yaw_curve", "mount yaw, °", 180.0 / std::f64::consts::PI),
        ] {
            let pts: Vec<[f64; 2]> = sensor[curve]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|p| Some([p[0].as_f64()? * scale, p[1].as_f64()?]))
                .collect();
            let i = &sensor[key];
            let (value, low, high) = (i["value"].as_f64(), i["low"].as_f64(), i["high"].as_f64());
            let plot = Plot {
                x_label: label,
                y_label: "cost, m",
                line: &pts,
                marks: value.map(|v| (v * scale, "estimate".to_string())).into_iter().collect(),
                spans: low.zip(high).map(|(l, h)| (l * scale, h * scale)).into_iter().collect(),
                ..Default::default()
            };
            if let (false, Some(svg)) = (pts.is_empty(), svg(&plot)) {
                let _ = write!(
                    plots,
                    "<figure><figcaption>{name}: cost over the {}</figcaption>{svg}</figure>",
                    escape(label)
                );
            }
        }
    }
    s.push_str("</table>");
    if let Some(r) = c["revalidation"]["sentence"].as_str() {
        let _ = write!(s, "<p class=\"verdict\">{}</p>", escape(r));
    }
    s.push_str(&plots);
    let undetermined = list_items(&c["undetermined"]);
    if !undetermined.is_empty() {
        let _ = write!(s, "<p>Not determined:</p><ul>{undetermined}</ul>");
    }
    section("calibration", "Calibration", &s)
}

/// The GNSS fixes the estimator's gate rejected, by time and NIS, over its wheel-slip
/// stretches; nothing when it rejected none and saw no slip.
pub(crate) fn rejections_over_time(e: &Value) -> String {
    let stamp = |v: &Value| v.as_f64().map(|ns| ns * 1e-9);
    let rejected: Vec<(f64, f64)> = e["rejected_fixes"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|r| Some((stamp(&r["stamp"])?, r["nis"].as_f64()?)))
        .collect();
    let slips: Vec<(f64, f64)> = e["slip_stretches"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|r| Some((stamp(&r["start"])?, stamp(&r["end"])?)))
        .collect();
    let Some(t0) = rejected.iter().map(|r| r.0).chain(slips.iter().map(|s| s.0)).reduce(f64::min) else {
        return "<p>No GNSS fix was rejected and no wheel slip was seen.</p>".into();
    };
    let dots: Vec<[f64; 2]> = rejected.iter().map(|(t, n)| [t - t0, *n]).collect();
    let spans = slips.iter().map(|(a, b)| (a - t0, b - t0)).collect();
    let plot = Plot {
        x_label: "time since the first event, s",
        y_label: "NIS of the rejected fix",
        dots: &dots,
        spans,
        ..Default::default()
    };
    match svg(&plot) {
        Some(svg) => format!(
            "<figure><figcaption>GNSS fixes rejected by the gate (red, {}) and wheel-slip stretches (shaded, {})</figcaption>{svg}</figure>",
            rejected.len(),
            slips.len()
        ),
        None => format!("<p>{} wheel-slip stretches; no GNSS fix rejected.</p>", slips.len()),
    }
}

/// Each correction kind's mean NIS of accepted corrections over time, divided by its
/// degrees of freedom: near 1 where the filter is consistent (Bar-Shalom et al., §5.4),
/// well above where its noise figures are too small for that stretch, below where too
/// large. One plot per kind that has corrections, times from the earliest of them.
pub(crate) fn nis_over_time(e: &Value) -> String {
    let kinds = [
        ("fixes", "GNSS fixes"),
        ("poses", "absolute poses"),
        ("headings", "headings"),
        ("zero_rate", "zero-rate updates"),
    ];
    // A kind without corrections has no bins (and a start of 0).
    let start = |k: &str| {
        let o = &e[k]["innovation"]["over_time"];
        o["bins"].as_array().is_some_and(|b| !b.is_empty()).then(|| o["start"].as_f64()).flatten()
    };
    let Some(t0) = kinds.iter().filter_map(|(k, _)| start(k)).reduce(f64::min) else {
        return String::new();
    };
    let mut out = String::new();
    for (kind, name) in kinds {
        let i = &e[kind]["innovation"];
        let (Some(start), Some(bin_s), Some(dof)) = (start(kind), i["over_time"]["bin_s"].as_f64(), i["dof"].as_f64())
        else {
            continue;
        };
        let line: Vec<[f64; 2]> = i["over_time"]["bins"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
            .filter(|(_, b)| b["accepted"].as_u64().unwrap_or(0) > 0)
            .filter_map(|(k, b)| {
                Some([(start - t0) * 1e-9 + (k as f64 + 0.5) * bin_s, b["mean_nis_accepted"].as_f64()? / dof.max(1.0)])
            })
            .collect();
        let plot = Plot {
            x_label: "time since the first correction, s",
            y_label: "mean NIS ÷ dof",
            line: &line,
            ..Default::default()
        };
        if let (false, Some(svg)) = (line.is_empty(), svg(&plot)) {
            let _ = write!(
                out,
                "<figure><figcaption>{name}: mean NIS of the accepted ones per {} s, over its {} degrees of freedom (about 1 when consistent)</figcaption>{svg}</figure>",
                f(&i["over_time"]["bin_s"], 0),
                f(&i["dof"], 0)
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_calibration_shows_its_intervals_and_curves() {
        let c = json!({"sensors": [{"name": "camera", "time_offset_s": {"value": -0.04, "low": -0.045, "high": -0.035},
            "cost_before": 0.1, "cost_after": 0.05, "clock_curve": [[-0.1, 0.2], [-0.04, 0.05], [0.1, 0.3]]}],
            "undetermined": ["pitch: not estimated"]});
        let s = calibration(&c);
        assert!(
            s.contains("-0.0400") && s.contains("-0.0450") && s.contains("<svg") && s.contains("pitch: not estimated")
        );
    }

    #[test]
    fn a_validation_names_its_verdict() {
        let v = json!({"maps": [{"name": "m1", "sensors": ["laser"], "mean_entropy_nats": 0.4,
            "hit_rates": [{"sensor": "laser", "rate": 0.98}]}], "verdict": "no_gain", "sentence": "no clear gain", "not_built": ["m2: no camera"]});
        let s = validation(&v);
        assert!(s.contains("no_gain") && s.contains("0.980") && s.contains("m2: no camera"));
    }

    #[test]
    fn rejections_are_plotted_over_time() {
        let e = json!({"rejected_fixes": [{"stamp": 2.0e9, "nis": 70.0}], "slip_stretches": [{"start": 1.0e9, "end": 1.5e9}]});
        assert!(rejections_over_time(&e).contains("<circle"));
        assert!(rejections_over_time(&json!({})).contains("No GNSS fix"));
    }

    #[test]
    fn nis_is_plotted_over_time_per_kind() {
        let bins = json!([{"count": 3, "accepted": 3, "mean_nis_accepted": 2.2}, {"count": 0, "accepted": 0, "mean_nis_accepted": 0.0},
            {"count": 5, "accepted": 4, "mean_nis_accepted": 1.8}]);
        let e = json!({"fixes": {"innovation": {"dof": 2, "over_time": {"start": 1.0e9, "bin_s": 2.0, "bins": bins}}},
            "zero_rate": {"innovation": {"dof": 1, "over_time": {"start": 0.0, "bin_s": 1.0, "bins": []}}}});
        let s = nis_over_time(&e);
        assert_eq!(s.matches("<svg").count(), 1, "{s}");
        assert!(s.contains("GNSS fixes") && s.contains("per 2 s"));
        assert!(nis_over_time(&json!({})).is_empty());
    }
}
