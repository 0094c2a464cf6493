//! Small inline SVG plots for `report.html`: a curve or points over labelled axes, with
//! marked values and shaded spans. Written by hand (a few dozen lines) rather than through
//! a plotting crate: the report must be one self-contained file, and every plotting crate
//! checked draws to files or canvases, not to an SVG string with its axes' numbers.

use std::fmt::Write;

/// What to draw.
#[derive(Default)]
pub(crate) struct Plot<'a> {
    /// The x axis' label (with its unit).
    pub x_label: &'a str,
    /// The y axis' label.
    pub y_label: &'a str,
    /// A line through these points, in x order.
    pub line: &'a [[f64; 2]],
    /// Dots at these points.
    pub dots: &'a [[f64; 2]],
    /// Vertical lines at these x, each with a label.
    pub marks: Vec<(f64, String)>,
    /// Shaded x spans (an interval, a stretch of time).
    pub spans: Vec<(f64, f64)>,
}

const W: f64 = 520.0;
const H: f64 = 220.0;
const LEFT: f64 = 64.0;
const BOTTOM: f64 = 40.0;
const TOP: f64 = 12.0;
const RIGHT: f64 = 12.0;

/// A round number near a fifth of `span`, for ticks.
fn tick_step(span: f64) -> f64 {
    let raw = (span / 5.0).max(f64::MIN_POSITIVE);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag)
}

/// `[lo, hi]` of the finite values, widened to a range a tick step can divide (a flat
/// curve's span of a few ulps would give a step below the floats' spacing).
fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if lo > hi {
        return None;
    }
    let least = 1e-6 * lo.abs().max(hi.abs()).max(1e-12);
    let pad = if hi - lo > least { 0.0 } else { least.max(lo.abs() * 0.05) };
    Some((lo - pad, hi + pad))
}

/// The ticks of `[lo, hi]` at multiples of `step`, at most a dozen.
fn ticks(lo: f64, hi: f64, step: f64) -> impl Iterator<Item = f64> {
    let first = (lo / step).ceil();
    (0..12).map(move |k| (first + k as f64) * step).take_while(move |&v| v <= hi + 1e-9 * step)
}

/// A number for a tick label: few digits, no trailing noise.
fn label(v: f64, step: f64) -> String {
    let digits = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.digits$}")
}

/// The plot as an `<svg>` element; `None` without any finite point.
pub(crate) fn svg(p: &Plot) -> Option<String> {
    let pts = || p.line.iter().chain(p.dots);
    let xs = pts().map(|q| q[0]).chain(p.marks.iter().map(|m| m.0)).chain(p.spans.iter().flat_map(|s| [s.0, s.1]));
    let (x0, x1) = range(xs)?;
    let (y0, y1) = range(pts().map(|q| q[1]))?;
    let sx = |x: f64| LEFT + (x - x0) / (x1 - x0) * (W - LEFT - RIGHT);
    let sy = |y: f64| H - BOTTOM - (y - y0) / (y1 - y0) * (H - BOTTOM - TOP);
    let mut s = format!(r#"<svg class="plot" viewBox="0 0 {W} {H}" width="{W}" height="{H}" role="img">"#);
    for &(a, b) in &p.spans {
        let _ = write!(
            s,
            r##"<rect x="{:.1}" y="{TOP}" width="{:.1}" height="{:.1}" fill="#f4d9a6"/>"##,
            sx(a),
            (sx(b) - sx(a)).max(1.0),
            H - BOTTOM - TOP
        );
    }
    axes(&mut s, (x0, x1), (y0, y1), &sx, &sy);
    let path: Vec<String> = p
        .line
        .iter()
        .filter(|q| q[0].is_finite() && q[1].is_finite())
        .map(|q| format!("{:.1},{:.1}", sx(q[0]), sy(q[1])))
        .collect();
    if path.len() > 1 {
        let _ =
            write!(s, r##"<polyline fill="none" stroke="#1f5fbf" stroke-width="1.5" points="{}"/>"##, path.join(" "));
    }
    for q in p.dots.iter().filter(|q| q[0].is_finite() && q[1].is_finite()) {
        let _ = write!(s, r##"<circle cx="{:.1}" cy="{:.1}" r="2.5" fill="#c0392b"/>"##, sx(q[0]), sy(q[1]));
    }
    for (x, text) in &p.marks {
        let _ = write!(
            s,
            r##"<line x1="{0:.1}" x2="{0:.1}" y1="{TOP}" y2="{1:.1}" stroke="#2e7d32" stroke-dasharray="4 3"/><text x="{2:.1}" y="{3:.1}" font-size="11" fill="#2e7d32">{4}</text>"##,
            sx(*x),
            H - BOTTOM,
            sx(*x) + 3.0,
            TOP + 11.0,
            super::report_page::escape(text)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text><text x="14" y="{:.1}" font-size="12" text-anchor="middle" transform="rotate(-90 14 {:.1})">{}</text></svg>"#,
        LEFT + (W - LEFT - RIGHT) / 2.0,
        H - 6.0,
        super::report_page::escape(p.x_label),
        (H - BOTTOM) / 2.0,
        (H - BOTTOM) / 2.0,
        super::report_page::escape(p.y_label)
    );
    Some(s)
}

/// The frame, the ticks and their numbers.
fn axes(s: &mut String, (x0, x1): (f64, f64), (y0, y1): (f64, f64), sx: &dyn Fn(f64) -> f64, sy: &dyn Fn(f64) -> f64) {
    let _ = write!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{:.1}" height="{:.1}" fill="none" stroke="#555"/>"##,
        W - LEFT - RIGHT,
        H - BOTTOM - TOP
    );
    let (xs, ys) = (tick_step(x1 - x0), tick_step(y1 - y0));
    for x in ticks(x0, x1, xs) {
        let _ = write!(
            s,
            r##"<line x1="{0:.1}" x2="{0:.1}" y1="{1:.1}" y2="{2:.1}" stroke="#555"/><text x="{0:.1}" y="{3:.1}" font-size="11" text-anchor="middle">{4}</text>"##,
            sx(x),
            H - BOTTOM,
            H - BOTTOM + 4.0,
            H - BOTTOM + 16.0,
            label(x, xs)
        );
    }
    for y in ticks(y0, y1, ys) {
        let _ = write!(
            s,
            r##"<line x1="{0:.1}" x2="{1:.1}" y1="{2:.1}" y2="{2:.1}" stroke="#555"/><text x="{3:.1}" y="{4:.1}" font-size="11" text-anchor="end">{5}</text>"##,
            LEFT - 4.0,
            LEFT,
            sy(y),
            LEFT - 6.0,
            sy(y) + 4.0,
            label(y, ys)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round() {
        assert_eq!(tick_step(1.0), 0.2);
        assert_eq!(tick_step(0.6), 0.2);
        assert_eq!(tick_step(37.0), 10.0);
        assert_eq!(label(0.25, 0.05), "0.25");
        assert_eq!(label(20.0, 10.0), "20");
    }

    #[test]
    fn a_curve_with_a_mark_is_drawn_and_nothing_is_not() {
        let line = [[-0.1, 3.0], [0.0, 1.0], [0.1, 2.5]];
        let p = Plot {
            x_label: "offset, s",
            y_label: "cost, m",
            line: &line,
            marks: vec![(0.0, "estimate".into())],
            ..Default::default()
        };
        let s = svg(&p).unwrap();
        assert!(s.starts_with("<svg") && s.ends_with("</svg>"));
        assert!(s.contains("<polyline") && s.contains("estimate") && s.contains("offset, s"));
        assert!(svg(&Plot { line: &[[f64::NAN, 1.0]], ..Default::default() }).is_none());
        // A flat curve a few ulps high ends, with a dozen ticks at most.
        let flat = [[0.0, 0.1], [1.0, 0.1 + f64::EPSILON / 8.0], [2.0, 1e-300]];
        assert!(svg(&Plot { line: &flat[..2], ..Default::default() }).unwrap().matches("<text").count() < 30);
        assert!(svg(&Plot { line: &flat[1..], ..Default::default() }).is_some());
    }
}
