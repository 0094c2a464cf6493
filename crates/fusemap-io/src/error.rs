//! The one error type of fusemap-io: every error names the file and, where there is one,
//! the place in it (line, record, message) and what was wrong.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole.
    File,
    /// A 1-based line of a text file.
    Line(u64),
    /// A line and a field name or column of a text file.
    LineField(u64, String),
    /// A byte offset of a binary file.
    Offset(u64),
    /// The n-th (1-based) message of a log, with its topic where known.
    Message {
        /// 1-based index among the log's messages.
        index: u64,
        /// Topic (ROS) or message type (CARMEN).
        topic: String,
    },
    /// A named key or field (config and world files).
    Field(String),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(l) => write!(f, ":{l}"),
            Location::LineField(l, field) => write!(f, ":{l}: field `{field}`"),
            Location::Offset(o) => write!(f, ": at byte {o}"),
            Location::Message { index, topic } => write!(f, ": message {index} on `{topic}`"),
            Location::Field(k) => write!(f, ": `{k}`"),
        }
    }
}

/// An error reading or writing a file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused (not found, permission, disk full…).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The content is not what the format says.
    #[error("{}{location}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// Where in it.
        location: Location,
        /// What is wrong, in plain words.
        message: String,
    },
    /// The file ends before its container does (a recording cut short: a bag whose
    /// last record or index is missing, an MCAP without its end, a gzip stream that stops):
    /// everything the reader returned before it is sound.
    #[error("{}{location}: {message}", path.display())]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Where the file ends.
        location: Location,
        /// What was cut off, in plain words.
        message: String,
    },
    /// A `[limits]` budget is broken at `location` (a message or chunk that inflates past
    /// `limits.decompressed_mib`, say): reading on would take memory the user did not
    /// allow, so the run ends here, naming the limit and the key that raises it. Never
    /// skippable: a limit that silently dropped data would hide that the budget is too
    /// small for the log.
    #[error("{}{location}: {message}", path.display())]
    Limit {
        /// The file.
        path: PathBuf,
        /// Where the budget was reached.
        location: Location,
        /// Which limit, the value met, and the key that raises it.
        message: String,
    },
    /// Refusing to overwrite one of the run's inputs.
    #[error("{}: refusing to overwrite an input file", path.display())]
    WouldOverwriteInput {
        /// The output path that is also an input.
        path: PathBuf,
    },
}

impl Error {
    /// An OS error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io { path: path.to_path_buf(), source }
    }

    /// A format error at `location` in `path`.
    pub fn format(path: &Path, location: Location, message: impl Into<String>) -> Self {
        Error::Format { path: path.to_path_buf(), location, message: message.into() }
    }

    /// The file `path` ends at `location` inside its container (see [`Error::Truncated`]).
    pub fn truncated(path: &Path, location: Location, message: impl Into<String>) -> Self {
        Error::Truncated { path: path.to_path_buf(), location, message: message.into() }
    }

    /// A broken budget at `location` in `path` (see [`Error::Limit`]).
    pub fn limit(path: &Path, location: Location, message: impl Into<String>) -> Self {
        Error::Limit { path: path.to_path_buf(), location, message: message.into() }
    }

    /// True for [`Error::Truncated`]: the log ends early, and what was read before it can
    /// be used as the log.
    pub fn is_truncation(&self) -> bool {
        matches!(self, Error::Truncated { .. })
    }

    /// True when the error concerns one message of a log and a caller that wants the
    /// rest of the log may count it and read on: the [`crate::log::LogReader`] that
    /// returned it has consumed the message and its next call yields the message after.
    ///
    /// Only an [`Error::Format`] at [`Location::Message`] is skippable: a payload that
    /// does not decode (truncated, a length that overruns it, bytes left over, a
    /// big-endian CDR encapsulation, a per-message zstd frame that does not decompress).
    /// Its container framing was sound, so the reader knows where the next message starts.
    ///
    /// Everything else ends the read, for a reason:
    /// - [`Error::Io`]: the operating system failed; reading on would repeat it or
    ///   silently lose data.
    /// - [`Error::Format`] at [`Location::File`] or [`Location::Offset`]: the container
    ///   itself is damaged (not a log, a truncated or corrupt chunk or record, a gzip
    ///   stream that ends early, a connection whose MD5 sum differs from the standard
    ///   definition), so where the next message starts is unknown, or every message of
    ///   that connection would be misread.
    /// - [`Error::Format`] at [`Location::Line`], [`Location::LineField`] or
    ///   [`Location::Field`]: a config, world or map file is wrong and running on would
    ///   use a default the user did not choose; a CARMEN reader returns line errors only
    ///   in strict mode, where the user asked for a malformed line to stop the read (the
    ///   lenient mode already skips and counts those lines in
    ///   [`crate::log::ReadStats::malformed`]).
    /// - [`Error::Truncated`]: the file ends; a caller may use what came before
    ///   ([`Error::is_truncation`]), but there is nothing after it to read.
    /// - [`Error::WouldOverwriteInput`]: never to be worked around.
    pub fn is_skippable(&self) -> bool {
        matches!(self, Error::Format { location: Location::Message { .. }, .. })
    }

    /// The topic of the message a skippable error is about.
    pub fn message_topic(&self) -> Option<&str> {
        match self {
            Error::Format { location: Location::Message { topic, .. }, .. } => Some(topic),
            _ => None,
        }
    }
}

/// fusemap-io's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    fn at(location: Location) -> Error {
        Error::format(Path::new("run.bag"), location, "bad")
    }

    #[test]
    fn only_a_message_that_does_not_decode_is_skippable() {
        assert!(at(Location::Message { index: 3, topic: "/fix".into() }).is_skippable());
        for location in [
            Location::File,
            Location::Line(4),
            Location::LineField(4, "x".into()),
            Location::Offset(4096),
            Location::Field("resolution".into()),
        ] {
            assert!(!at(location.clone()).is_skippable(), "{location:?}");
        }
        let os = Error::io(Path::new("run.bag"), std::io::Error::other("disk on fire"));
        assert!(!os.is_skippable());
        assert!(!Error::WouldOverwriteInput { path: "map.pgm".into() }.is_skippable());
        let limit = Error::limit(Path::new("run.bag"), Location::Message { index: 3, topic: "/scan".into() }, "big");
        assert!(!limit.is_skippable());
        let cut = Error::truncated(Path::new("run.bag"), Location::Offset(4096), "the file ends");
        assert!(!cut.is_skippable() && cut.is_truncation() && !at(Location::File).is_truncation());
        assert_eq!(cut.to_string(), "run.bag: at byte 4096: the file ends");
    }
}
