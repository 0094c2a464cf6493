//! Progress bars on stderr; indicatif draws nothing when stderr is not a terminal.

use fusemap_pipeline::Progress;
use indicatif::{ProgressBar, ProgressStyle};

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

/// A callback for the pipeline's progress reports, drawing one bar per phase.
pub fn reporter() -> impl FnMut(Progress) {
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
