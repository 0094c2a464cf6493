//! What a run tells its caller as it goes: a leaf, so every stage can report progress.

/// What a run tells its caller as it goes (the CLI draws a progress bar from it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress<'a> {
    /// A phase starts, with the number of steps when known.
    Phase {
        /// What it does.
        name: &'a str,
        /// Steps in it.
        total: u64,
    },
    /// Steps done since the last report.
    Advance(u64),
    /// The phase ended.
    Done,
}
