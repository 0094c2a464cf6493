//! `report.html`: the page a user sends a colleague, beside every run's outputs (`map`,
//! `validate`, `calibrate`, `demo`). One self-contained file: the pictures inlined as
//! `data:` URIs, the plots as inline SVG, no script, no network. It is read from
//! `summary.json`'s content and the run's pictures, so it says nothing the files do not.
//!
//! Its sections, each an element with a fixed `id` (what the browser test looks for):
//! `overview`, `map`, `sensors`, `findings`, `estimator`, `slam`, `validation`,
//! `calibration`. A section a run has nothing for says so instead of disappearing.

use base64::Engine as _;
use serde_json::Value;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// A picture of the run, with how to read it.
pub(crate) struct Picture {
    /// Its heading.
    pub title: String,
    /// The PNG file.
    pub path: PathBuf,
    /// What its colours mean: `(CSS colour, meaning)`.
    pub legend: Vec<(String, String)>,
    /// The map's width in metres (for the scale bar).
    pub width_m: f64,
    /// The part shown, as shares of the picture's width and height from its top left:
    /// `[left, right, top, bottom]` (the observed area, without the stray rays around it).
    pub crop: [f64; 4],
}

/// The section ids, in page order.
pub const SECTIONS: [&str; 8] =
    ["overview", "map", "sensors", "findings", "estimator", "slam", "validation", "calibration"];

/// `<`, `>`, `&` and quotes escaped.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A number for a table: up to four significant decimals, `—` for null.
fn num(v: &Value) -> String {
    match v {
        Value::Number(n) if n.is_i64() || n.is_u64() => n.to_string(),
        Value::Number(n) => {
            let f = n.as_f64().unwrap_or(f64::NAN);
            if f != 0.0 && (f.abs() >= 1e5 || f.abs() < 1e-3) {
                format!("{f:.3e}")
            } else {
                format!("{f:.4}").trim_end_matches('0').trim_end_matches('.').to_string()
            }
        }
        Value::Null => "—".into(),
        Value::String(s) => escape(s),
        other => escape(&other.to_string()),
    }
}

/// A table from a header and rows of cells (already HTML).
fn table(head: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::from("<table>");
    if head.iter().any(|h| !h.is_empty()) {
        s.push_str("<tr>");
        for h in head {
            let _ = write!(s, "<th>{}</th>", escape(h));
        }
        s.push_str("</tr>");
    }
    for r in rows {
        s.push_str("<tr>");
        for c in r {
            let _ = write!(s, "<td>{c}</td>");
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>");
    s
}

/// The non-zero counters of an object of counts, as `name n, …`; `none` when all are 0.
fn nonzero(v: &Value) -> String {
    let Some(o) = v.as_object() else { return "—".into() };
    let parts: Vec<String> = o
        .iter()
        .filter(|(_, n)| n.as_f64().is_some_and(|n| n != 0.0))
        .map(|(k, n)| format!("{} {}", escape(&k.replace('_', " ")), num(n)))
        .collect();
    if parts.is_empty() {
        "none".into()
    } else {
        parts.join(", ")
    }
}

/// A section of the page.
pub(crate) fn section(id: &str, title: &str, body: &str) -> String {
    format!("<section id=\"{id}\"><h2>{}</h2>{body}</section>\n", escape(title))
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;color:#222}\
h1{font-size:1.5em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}\
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em;text-align:left;font-size:.9em}\
th{background:#f2f2f2}figure{display:inline-block;width:500px;margin:.5em 1em .5em 0;vertical-align:top}\
.crop{position:relative;overflow:hidden;border:1px solid #999;background:#fff}.crop img{position:absolute;image-rendering:pixelated}\
.bar{height:6px;background:#000;margin-top:4px}.legend span{display:inline-block;width:.9em;height:.9em;border:1px solid #555;margin:0 .3em 0 .8em;vertical-align:middle}\
.verdict{font-size:1.1em;padding:.5em;background:#eef4ff;border-left:4px solid #1f5fbf}.none{color:#777}";

/// The page.
pub(crate) fn page(summary: &Value, pictures: &[Picture]) -> String {
    let title = format!("fusemap report: {}", summary["source"].as_str().unwrap_or("run"));
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(&title),
        escape(&title)
    );
    s.push_str(&overview(summary));
    s.push_str(&map(pictures));
    s.push_str(&sensors(&summary["log"]));
    s.push_str(&findings(summary));
    s.push_str(&estimator(&summary["log"]["estimator"]["estimator"]));
    s.push_str(&slam(&summary["log"]["slam"]));
    s.push_str(&super::report_tables::validation(&summary["validation"]));
    s.push_str(&super::report_tables::calibration(&summary["calibration"]));
    s.push_str("</body></html>\n");
    s
}

/// Writes the page to `path`.
pub(crate) fn write_report(path: &Path, summary: &Value, pictures: &[Picture]) -> Result<(), fusemap_io::Error> {
    let html = page(summary, pictures);
    fusemap_io::atomic::write_atomic(path, |w| std::io::Write::write_all(w, html.as_bytes()))
}

fn overview(s: &Value) -> String {
    let rows = [
        ("source", num(&s["source"])),
        ("format", num(&s["source_kind"])),
        ("scans", num(&s["scans"])),
        ("camera frames", num(&s["camera_frames"])),
        ("pose source", num(&s["log"]["pose_source"])),
        (
            "map",
            format!(
                "{} × {} cells of {} m",
                num(&s["map"]["width"]),
                num(&s["map"]["height"]),
                num(&s["map"]["resolution"])
            ),
        ),
        (
            "known cells",
            format!("{} ({} of the box)", num(&s["entropy"]["known_cells"]), num(&s["entropy"]["known_share"])),
        ),
        ("mean entropy, nats", num(&s["entropy"]["mean_entropy_nats"])),
        ("wall time, s", format!("{} ({})", num(&s["wall_time_s"]), phases(&s["seconds"]))),
        ("fusemap", num(&s["fusemap_version"])),
    ];
    let rows: Vec<Vec<String>> = rows.into_iter().map(|(k, v)| vec![escape(k), v]).collect();
    section("overview", "Overview", &table(&["", ""], &rows))
}

/// Where the wall time went (`summary.json`'s `seconds`), phase by phase.
fn phases(seconds: &Value) -> String {
    const PHASES: [&str; 7] = ["simulate", "read", "estimator", "slam", "map", "outputs", "other"];
    let shown = PHASES.iter().filter(|k| seconds[**k].is_number());
    shown.map(|k| format!("{k} {}", num(&seconds[*k]))).collect::<Vec<_>>().join(", ")
}

/// A round length near a fifth of `width_m`.
fn bar_length(width_m: f64) -> f64 {
    let raw = (width_m / 5.0).max(0.01);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0].iter().map(|m| m * mag).rev().find(|l| *l <= raw).unwrap_or(mag)
}

fn map(pictures: &[Picture]) -> String {
    if pictures.is_empty() {
        return section(
            "map",
            "Map",
            "<p class=\"none\">No picture: the run observed no cell, or its map is too large to draw densely.</p>",
        );
    }
    let mut body = String::new();
    for p in pictures {
        let Ok(bytes) = std::fs::read(&p.path) else { continue };
        let Some((w_px, h_px)) = png_size(&bytes) else { continue };
        let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
        let [left, right, top, bottom] = p.crop;
        let (cw, ch) = ((right - left).max(1e-6), (bottom - top).max(1e-6));
        let shown_m = cw * p.width_m;
        let bar = bar_length(shown_m);
        let legend: String =
            p.legend.iter().map(|(c, t)| format!("<span style=\"background:{c}\"></span>{}", escape(t))).collect();
        let _ = write!(
            body,
            "<figure><figcaption><b>{title}</b></figcaption><div class=\"crop\" style=\"aspect-ratio:{:.2}/{:.2}\">\
             <img alt=\"{title}\" style=\"width:{:.3}%;left:{:.3}%;top:{:.3}%\" src=\"data:image/png;base64,{data}\"></div>\
             <div class=\"bar\" style=\"width:{:.2}%\"></div><small>{bar} m</small><div class=\"legend\"><small>{legend}</small></div></figure>",
            cw * w_px as f64,
            ch * h_px as f64,
            100.0 / cw,
            -100.0 * left / cw,
            -100.0 * top / ch,
            100.0 * bar / shown_m.max(1e-9),
            title = escape(&p.title),
        );
    }
    if body.is_empty() {
        body.push_str("<p class=\"none\">The run's pictures could not be read back.</p>");
    }
    section("map", "Map", &body)
}

/// A PNG's width and height from its header.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    let ihdr = bytes.get(16..24)?;
    let w = u32::from_be_bytes(ihdr[..4].try_into().ok()?);
    let h = u32::from_be_bytes(ihdr[4..].try_into().ok()?);
    (bytes.starts_with(b"\x89PNG") && w > 0 && h > 0).then_some((w, h))
}

fn sensors(log: &Value) -> String {
    let mut rows = Vec::new();
    for l in log["lidars"].as_array().into_iter().flatten() {
        rows.push(vec![
            format!("lidar {}", num(&l["name"])),
            num(&l["topic"]),
            format!("{} of {} scans", num(&l["scans_used"]), num(&l["scans_read"])),
            num(&l["timing"]["rate_hz"]),
            num(&l["time_offset_s"]),
            nonzero(&l["scans_skipped"]),
        ]);
    }
    for c in log["cameras"].as_array().into_iter().flatten() {
        rows.push(vec![
            format!("camera {}", num(&c["name"])),
            num(&c["topic"]),
            format!(
                "{} of {} frames ({} paired)",
                num(&c["frames_used"]),
                num(&c["labels_read"]),
                num(&c["frames_paired"])
            ),
            "—".into(),
            num(&c["time_offset_s"]),
            nonzero(&c["frames_skipped"]),
        ]);
    }
    rows.extend(pose_sensors(log));
    if rows.is_empty() {
        return section("sensors", "Sensors", "<p class=\"none\">No log report: this run did not read a log.</p>");
    }
    let head = ["sensor", "topic", "used", "rate, Hz", "clock offset, s", "skipped, by reason"];
    section("sensors", "Sensors", &table(&head, &rows))
}

/// The pose sensors (`log.sensors` maps a name to `kind topic`), with what the estimator
/// used of each where it made the track.
fn pose_sensors(log: &Value) -> Vec<Vec<String>> {
    let e = &log["estimator"]["estimator"];
    let mut rows = Vec::new();
    for (name, what) in log["sensors"].as_object().into_iter().flatten() {
        let Some((kind, topic)) = what.as_str().and_then(|w| w.split_once(' ')) else { continue };
        let counts = match kind {
            "wheel_odometry" => &e["odometry"],
            "imu" => &e["gyro"],
            "gnss" => &e["fixes"],
            _ => continue,
        };
        let used = if counts.is_null() {
            "—".to_string()
        } else {
            format!("{} of {} messages", num(&counts["used"]), num(&counts["received"]))
        };
        let skipped = counts.as_object().map_or("—".into(), |o| {
            let rest: serde_json::Map<String, Value> = o
                .iter()
                .filter(|(k, v)| !["used", "received"].contains(&k.as_str()) && v.is_number())
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect();
            nonzero(&Value::Object(rest))
        });
        rows.push(vec![
            format!("{} {}", escape(kind), escape(name)),
            escape(topic),
            used,
            "—".into(),
            "—".into(),
            skipped,
        ]);
    }
    rows
}

/// The strings of the array `v` as escaped `<li>` items, joined; empty without any.
pub(crate) fn list_items(v: &Value) -> String {
    v.as_array().into_iter().flatten().filter_map(|n| n.as_str()).map(|n| format!("<li>{}</li>", escape(n))).collect()
}

fn findings(s: &Value) -> String {
    let notes = list_items(&s["notes"]);
    let body = if notes.is_empty() {
        "<p class=\"none\">Nothing to report.</p>".to_string()
    } else {
        format!("<ul>{notes}</ul>")
    };
    let hint = "<p><small>The run's notes: what it skipped, replaced or could not use, and why.</small></p>";
    let doctor = list_items(&s["log"]["log_findings"]);
    let doctor = match (s["log"]["log_findings"].is_array(), doctor.is_empty()) {
        (false, _) => String::new(),
        (true, true) => "<h3>The log</h3><p class=\"none\">No clock or pose-sensor fault found.</p>".to_string(),
        (true, false) => format!("<h3>The log</h3><ul>{doctor}</ul>"),
    };
    let tail = "<p><small>The log's findings are <code>fusemap doctor LOG</code>'s: its streams' timing and its pose sensors, checked without mapping.</small></p>";
    section("findings", "Findings", &format!("{body}{hint}{doctor}{tail}"))
}

fn estimator(e: &Value) -> String {
    if e.is_null() {
        return section("estimator", "Estimator", "<p class=\"none\">The estimator did not make this run's track.</p>");
    }
    let mut rows = Vec::new();
    for kind in ["fixes", "poses", "headings", "zero_rate"] {
        let k = &e[kind];
        if k["received"].as_u64().unwrap_or(0) == 0 {
            continue;
        }
        let i = &k["innovation"];
        rows.push(vec![
            escape(&kind.replace('_', " ")),
            format!("{} of {}", num(&k["used"]), num(&k["received"])),
            format!("{} (dof {})", num(&i["mean_nis_accepted"]), num(&i["dof"])),
            num(&i["share_above_gate"]),
            num(&k["rejected_gate"]),
        ]);
    }
    let mut body =
        table(&["correction", "used", "mean NIS accepted", "share above gate", "rejected by the gate"], &rows);
    let _ = write!(
        body,
        "<p>Odometry scale {} ± {}; gyro bias {} ± {} rad/s.</p>",
        num(&e["odometry_scale"]),
        num(&e["odometry_scale_sigma"]),
        num(&e["gyro_bias"]),
        num(&e["gyro_bias_sigma"])
    );
    body.push_str(&super::report_tables::nis_over_time(e));
    body.push_str(&super::report_tables::rejections_over_time(e));
    section("estimator", "Estimator", &body)
}

fn slam(s: &Value) -> String {
    let c = &s["counts"];
    if c.is_null() {
        return section("slam", "SLAM", "<p class=\"none\">SLAM did not correct this run's track.</p>");
    }
    let rows: Vec<Vec<String>> = [
        ("scans matched", "matched"),
        ("nodes", "nodes"),
        ("submaps", "submaps"),
        ("loop searches", "loop_searches"),
        ("loop closures accepted", "loop_accepted"),
        ("… rejected", "loop_rejected"),
        ("… degenerate (a corridor)", "loop_degenerate"),
        ("… disagreeing", "loop_disagreeing"),
        ("longest loop closed, m", "longest_loop_m"),
        ("travel, m", "travel_m"),
        ("GNSS fixes as priors", "fix_priors"),
        ("optimisations", "optimisations"),
        ("track jumps", "track_jumps"),
    ]
    .iter()
    .map(|(t, k)| vec![escape(t), num(&c[*k])])
    .collect();
    section("slam", "SLAM", &table(&["", ""], &rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_section_is_on_an_empty_run_page() {
        let page = page(&serde_json::json!({"source": "a <b>", "notes": []}), &[]);
        for id in SECTIONS {
            assert!(page.contains(&format!("<section id=\"{id}\">")), "{id}");
        }
        assert!(page.contains("a &lt;b&gt;") && !page.contains("<b>a"));
    }

    #[test]
    fn the_findings_hold_the_logs_apart_from_the_runs() {
        let s = serde_json::json!({"notes": ["a note"], "log": {"log_findings": ["/odom pauses <b>"]}});
        let f = findings(&s);
        assert!(
            f.contains("<li>a note</li>") && f.contains("<h3>The log</h3><ul><li>/odom pauses &lt;b&gt;</li></ul>")
        );
        let none = findings(&serde_json::json!({"notes": [], "log": {"log_findings": []}}));
        assert!(none.contains("No clock or pose-sensor fault found"));
        assert!(!findings(&serde_json::json!({"notes": []})).contains("<h3>"));
    }

    #[test]
    fn scale_bars_are_round() {
        assert_eq!(bar_length(48.0), 5.0);
        assert_eq!(bar_length(10.0), 2.0);
        assert_eq!(bar_length(0.3), 0.05);
    }

    #[test]
    fn numbers_read_short() {
        assert_eq!(num(&serde_json::json!(0.38716195900131006)), "0.3872");
        assert_eq!(num(&serde_json::json!(2)), "2");
        assert_eq!(num(&serde_json::json!(0.5)), "0.5");
        assert_eq!(num(&serde_json::json!(1.2e-6)), "1.200e-6");
        assert_eq!(nonzero(&serde_json::json!({"late": 0, "in_pose_gap": 3})), "in pose gap 3");
    }
}
