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
}

/// fusemap-io's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
