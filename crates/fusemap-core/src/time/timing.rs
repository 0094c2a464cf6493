//! Timing of one message stream: rate, jitter, regressions, gaps and header-stamp delay
//! (the figures of `ros2 topic hz` and `ros2 topic delay`, the design document's §4.3
//! habit 1, computed over a whole log).

use super::Stamp;
use serde::Serialize;

/// Thresholds for calling something a fault.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TimingLimits {
    /// A pause between consecutive stamps longer than this is a gap, seconds.
    pub gap_s: f64,
    /// |receive − header| beyond this is a far-off header stamp, seconds.
    pub far_delay_s: f64,
}

impl Default for TimingLimits {
    fn default() -> Self {
        Self { gap_s: 0.5, far_delay_s: 1.0 }
    }
}

/// Header-stamp delay statistics (receive time − header stamp).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DelayStats {
    /// Messages with a receive time.
    pub count: u64,
    /// Mean delay, seconds.
    pub mean_s: f64,
    /// Smallest delay, seconds (negative: stamped in the future of its receipt).
    pub min_s: f64,
    /// Largest delay, seconds.
    pub max_s: f64,
    /// Messages whose |delay| exceeds the limit.
    pub far: u64,
}

/// Timing of one stream, in file order.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StreamTiming {
    /// Messages.
    pub count: u64,
    /// Earliest header stamp, seconds.
    pub first_s: Option<f64>,
    /// Latest header stamp, seconds.
    pub last_s: Option<f64>,
    /// `last − first`, seconds.
    pub span_s: f64,
    /// Mean rate over the span, Hz.
    pub rate_hz: f64,
    /// Median period between consecutive increasing stamps, seconds.
    pub median_period_s: f64,
    /// Standard deviation of that period, seconds.
    pub jitter_s: f64,
    /// Stamps earlier than the one before them.
    pub regressions: u64,
    /// Stamps equal to the one before them.
    pub duplicates: u64,
    /// Pauses longer than the gap limit.
    pub gaps: u64,
    /// The longest pause, seconds.
    pub max_gap_s: f64,
    /// Delay of header stamps behind receive times, when the format records both.
    pub delay: Option<DelayStats>,
}

impl StreamTiming {
    /// Analyses `header` stamps in file order, with `receive` times where known
    /// (`receive` may be empty or shorter: missing entries count as unknown).
    pub fn analyze(header: &[Stamp], receive: &[Option<Stamp>], limits: TimingLimits) -> Self {
        let count = header.len() as u64;
        let first = header.iter().min().copied();
        let last = header.iter().max().copied();
        let span_s = match (first, last) {
            (Some(a), Some(b)) => b.secs_since(a),
            _ => 0.0,
        };
        let mut periods = Vec::with_capacity(header.len());
        let (mut regressions, mut duplicates, mut gaps) = (0, 0, 0);
        let mut max_gap_s: f64 = 0.0;
        for w in header.windows(2) {
            let dt = w[1].secs_since(w[0]);
            if dt < 0.0 {
                regressions += 1;
            } else if dt == 0.0 {
                duplicates += 1;
            } else {
                periods.push(dt);
                max_gap_s = max_gap_s.max(dt);
                if dt > limits.gap_s {
                    gaps += 1;
                }
            }
        }
        let (median_period_s, jitter_s) = if periods.is_empty() {
            (0.0, 0.0)
        } else {
            let mean = periods.iter().sum::<f64>() / periods.len() as f64;
            let var = periods.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / periods.len() as f64;
            periods.sort_by(f64::total_cmp);
            (periods[periods.len() / 2], var.sqrt())
        };
        let delays: Vec<f64> = header.iter().zip(receive).filter_map(|(h, r)| r.map(|r| r.secs_since(*h))).collect();
        let delay = (!delays.is_empty()).then(|| DelayStats {
            count: delays.len() as u64,
            mean_s: delays.iter().sum::<f64>() / delays.len() as f64,
            min_s: delays.iter().copied().fold(f64::INFINITY, f64::min),
            max_s: delays.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            far: delays.iter().filter(|d| d.abs() > limits.far_delay_s).count() as u64,
        });
        Self {
            count,
            first_s: first.map(Stamp::as_secs_f64),
            last_s: last.map(Stamp::as_secs_f64),
            span_s,
            rate_hz: if span_s > 0.0 { (count - 1) as f64 / span_s } else { 0.0 },
            median_period_s,
            jitter_s,
            regressions,
            duplicates,
            gaps,
            max_gap_s,
            delay,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn st(v: &[f64]) -> Vec<Stamp> {
        v.iter().map(|&s| Stamp::from_secs_f64(s).unwrap()).collect()
    }

    #[test]
    fn faults_are_counted() {
        let h = st(&[0.0, 0.1, 0.2, 0.2, 0.15, 0.3, 1.3, 1.4]);
        let r: Vec<_> = st(&[0.01, 0.11, 0.21, 0.21, 0.16, 2.0, 1.31, 1.41]).into_iter().map(Some).collect();
        let t = StreamTiming::analyze(&h, &r, TimingLimits::default());
        assert_eq!(t.count, 8);
        assert_eq!(t.regressions, 1);
        assert_eq!(t.duplicates, 1);
        assert_eq!(t.gaps, 1);
        assert!((t.max_gap_s - 1.0).abs() < 1e-9);
        assert!((t.span_s - 1.4).abs() < 1e-9);
        assert!((t.rate_hz - 5.0).abs() < 1e-9);
        let d = t.delay.unwrap();
        assert_eq!(d.far, 1);
        assert!((d.max_s - 1.7).abs() < 1e-9);
    }

    #[test]
    fn steady_stream() {
        let h: Vec<Stamp> = (0..101).map(|i| Stamp(i * 100_000_000)).collect();
        let t = StreamTiming::analyze(&h, &[], TimingLimits::default());
        assert!((t.rate_hz - 10.0).abs() < 1e-9);
        assert!((t.median_period_s - 0.1).abs() < 1e-12);
        assert!(t.jitter_s < 1e-9);
        assert_eq!(t.delay, None);
        assert_eq!(t.regressions + t.duplicates + t.gaps, 0);
        assert_eq!(StreamTiming::analyze(&[], &[], TimingLimits::default()).count, 0);
    }
}
