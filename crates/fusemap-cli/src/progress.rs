//! Progress on stderr: bars on a terminal; off a terminal (a pipe, a log file, CI) a plain
//! line now and then, so a long run is not silent for minutes, and a short one prints
//! nothing.

use fusemap_pipeline::Progress;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Off a terminal, at most one line per this interval, the first after it: three a minute.
const LINE_INTERVAL: Duration = Duration::from_secs(20);

/// A progress bar of `len` steps.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    let pb = if len > 0 { ProgressBar::new(len) } else { ProgressBar::new_spinner() };
    if len > 0 {
        if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {per_sec} eta {eta}") {
            pb.set_style(style.progress_chars("=> "));
        }
    }
    pb.set_message(what.to_string());
    pb
}

/// A callback for the pipeline's progress reports: one bar per phase on a terminal,
/// [`PlainLines`] otherwise.
pub fn reporter() -> Box<dyn FnMut(Progress)> {
    if std::io::stderr().is_terminal() {
        Box::new(bars())
    } else {
        let mut lines = PlainLines::new(Instant::now());
        Box::new(move |p| {
            if let Some(line) = lines.report(p, Instant::now()) {
                eprintln!("{line}");
            }
        })
    }
}

/// One bar per phase.
fn bars() -> impl FnMut(Progress) {
    let mut current: Option<ProgressBar> = None;
    move |p| match p {
        Progress::Phase { name, total } => {
            if let Some(pb) = current.take() {
                pb.finish_and_clear();
            }
            current = Some(bar(total, name));
        }
        Progress::Advance(n) => {
            if let Some(pb) = &current {
                pb.inc(n);
            }
        }
        Progress::Done => {
            if let Some(pb) = current.take() {
                pb.finish_and_clear();
            }
        }
    }
}

/// Progress as plain lines (`fusemap: mapping 1200/13631 (8 %), 40 s`), at most one per
/// [`LINE_INTERVAL`], the first one interval after the start.
struct PlainLines {
    started: Instant,
    last: Instant,
    phase: String,
    done: u64,
    total: u64,
}

impl PlainLines {
    fn new(now: Instant) -> Self {
        Self { started: now, last: now, phase: String::new(), done: 0, total: 0 }
    }

    /// Takes a report at `now`; the line to print, when one is due.
    fn report(&mut self, p: Progress, now: Instant) -> Option<String> {
        match p {
            Progress::Phase { name, total } => {
                self.phase = name.to_string();
                (self.done, self.total) = (0, total);
            }
            Progress::Advance(n) => self.done += n,
            Progress::Done => return None,
        }
        if now.duration_since(self.last) < LINE_INTERVAL {
            return None;
        }
        self.last = now;
        let elapsed = now.duration_since(self.started).as_secs();
        Some(match (100 * self.done.min(self.total)).checked_div(self.total) {
            Some(share) => format!("fusemap: {} {}/{} ({share} %), {elapsed} s", self.phase, self.done, self.total),
            None => format!("fusemap: {} {}, {elapsed} s", self.phase, self.done),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_lines_come_a_few_a_minute_and_never_for_a_short_run() {
        let t0 = Instant::now();
        let at = |s: u64| t0 + Duration::from_secs(s);
        let mut lines = PlainLines::new(t0);
        assert_eq!(lines.report(Progress::Phase { name: "reading", total: 0 }, at(1)), None);
        assert_eq!(lines.report(Progress::Advance(500), at(19)), None);
        assert_eq!(lines.report(Progress::Advance(500), at(21)).as_deref(), Some("fusemap: reading 1000, 21 s"));
        assert_eq!(lines.report(Progress::Phase { name: "mapping", total: 400 }, at(30)), None);
        assert_eq!(lines.report(Progress::Advance(100), at(40)), None);
        assert_eq!(
            lines.report(Progress::Advance(100), at(41)).as_deref(),
            Some("fusemap: mapping 200/400 (50 %), 41 s")
        );
        assert_eq!(lines.report(Progress::Done, at(90)), None);
        // Over ten minutes of reports every second: three lines a minute.
        let mut lines = PlainLines::new(t0);
        let printed = (1..=600).filter(|&s| lines.report(Progress::Advance(1), at(s)).is_some()).count();
        assert_eq!(printed, 30);
    }
}
