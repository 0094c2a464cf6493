//! CARMEN text logs (`.log`, `.clf`, plain or gzipped), read line by line as
//! [`LogMessage`]s.
//!
//! # What is read
//!
//! | line | becomes |
//! |---|---|
//! | `FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_ts host logger_ts` | [`LogMessage::Scan`] |
//! | `RLASER …` (the rear laser, same layout as `FLASER`) | [`LogMessage::Scan`] |
//! | `ROBOTLASER1 type start_angle fov res max_range accuracy remission_mode n r1..rn m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis ipc_ts host logger_ts` | [`LogMessage::Scan`] |
//! | `RAWLASER1`…`RAWLASER4 type start_angle fov res max_range accuracy remission_mode n r1..rn m rem1..remm ipc_ts host logger_ts` | [`LogMessage::Scan`] |
//! | `ODOM x y theta tv rv accel ipc_ts host logger_ts` | [`LogMessage::Odometry`] (twist `[tv, 0, 0, 0, 0, rv]`, covariances zero: unknown) |
//! | `PARAM name value …` | kept in [`CarmenReader::params`] |
//! | `#…` comments and blank lines | ignored |
//! | any other message type (`NEFF`, `TRUEPOS`, `SYNC`, …) | counted in [`ReadStats::skipped_by_type`] |
//!
//! Every scan has `topic` = the message type, `frame_id` = `""`, `scan.stamp` = the IPC
//! time stamp, `receive_stamp` = the logger time stamp, `time_increment` = `scan_time` =
//! 0 (CARMEN does not say) and `range_min` = 0. `FLASER`/`RLASER` carry `pose` (x y theta,
//! the corrected pose in corrected logs) and `odom_pose`; `ROBOTLASER1` carries `pose`
//! (the robot pose) and `laser_pose`; `RAWLASERn` carries no pose.
//!
//! Time stamps are decimal seconds and are parsed exactly, digit by digit
//! ([`Stamp::parse_decimal`]), never through `f64`. Some logs print them with `%g`
//! (`1.13486e+09`): such a number is converted by moving its decimal point, which is
//! exact too, and passed on as written (coarse as it is) for the log doctor to judge.
//!
//! # Beam angles
//!
//! `FLASER`/`RLASER` lines carry no angles; they follow from the number of readings `n`
//! (see [`flaser_angles`]). `ROBOTLASER1` and `RAWLASERn` give `start_angle` and the
//! angular resolution, which are used as written.
//!
//! # No-returns
//!
//! CARMEN writes "no return" as the sensor's maximum value, never as inf: 81.91 or 81.83
//! for a SICK LMS in its 80 m mode, 50.0 to about 51.25 in the 50 m-mode logs. The range
//! values are left as written; the reader states the limit in `range_max`, so that the
//! lidar model (which treats `r >= min(its max_range, range_max)` as a no-return) never
//! takes a sentinel for a hit:
//!
//! * `FLASER`/`RLASER`: per line, `range_max = 81.0` when any finite value on the line is
//!   above 51.5, else `50.0`. 50 m-mode logs never go above ≈51.25, and the 80 m-mode
//!   sentinels are ≥ 81.8, so a line whose values all stay below 51.5 either comes from a
//!   50 m-mode sensor (its sentinels ≥ 50 are then no-returns) or from an 80 m-mode
//!   sensor that saw nothing far on that line. The cost of the rule is that a real return
//!   between 50 and 51.5 m in an 80 m-mode log, on a line with no farther value, is
//!   treated as a no-return: rare and negligible. A line whose largest value lies in
//!   [32.7, 32.77] m is a sensor counting millimetres in 16 bits (the Örebro log writes
//!   32.759–32.767 for no-return): `range_max = 32.7` there; a real 32.7 m return on a
//!   line with nothing farther is lost, again negligible. [`CarmenOptions::flaser_range_max`]
//!   replaces the rule for logs it does not fit.
//! * `ROBOTLASER1`/`RAWLASERn`: the line's `maximum_range` when it is finite and > 0
//!   (values at or beyond it are then no-returns by themselves), else the `FLASER` rule.
//!
//! # Errors
//!
//! A malformed line (too few or too many fields for its counts, a number that does not
//! parse, a count that does not fit the line, a non-finite pose, bytes that are not
//! UTF-8, a line that does not start with a message type) is skipped and counted in
//! [`ReadStats::malformed`] with a description naming file, line and what was wrong; with
//! [`CarmenOptions::strict`] it is returned as [`Error::Format`] at
//! [`Location::Line`] instead, and reading can go on with the next line. A NaN or
//! infinite *range* is not malformed: it is kept, for the lidar model to count as
//! invalid. A gzip stream that ends early is an [`Error::Truncated`], a corrupt one an
//! [`Error::Format`], for the whole file, after which the reader returns `None`.

use super::{LogMessage, LogReader, OdomMessage, ReadStats, ScanMessage};
use crate::bounded::read_until_bounded;
use crate::{Error, Location, Result};
use flate2::bufread::MultiGzDecoder;
use fusemap_core::config::LimitsConfig;
use fusemap_core::geometry::Pose2;
use fusemap_core::sensor::LaserScan;
use fusemap_core::time::Stamp;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fs::File;
use std::io::{BufRead, BufReader, ErrorKind, Read};
use std::path::{Path, PathBuf};
use std::str::SplitAsciiWhitespace;

mod lines;
pub mod rewrite;
use lines::*;

/// The first two bytes of every gzip stream.
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Buffer size for the file and for decompressed text.
const BUFFER: usize = 64 * 1024;

/// `range_max` of a `FLASER`/`RLASER` line whose values reach beyond [`MODE_50M_LIMIT`].
const RANGE_MAX_80M_MODE: f32 = 81.0;
/// `range_max` of any other `FLASER`/`RLASER` line.
const RANGE_MAX_50M_MODE: f32 = 50.0;
/// No 50 m-mode log goes beyond ≈51.25 m; 80 m-mode sentinels are ≥ 81.8 m.
const MODE_50M_LIMIT: f32 = 51.5;
/// `range_max` of a line whose largest value is a 16-bit millimetre overflow (32.7–32.768 m,
/// the Örebro log's no-return).
const RANGE_MAX_32M_MODE: f32 = 32.7;
/// The largest value a 16-bit millimetre counter writes, 32.767 m, with rounding room.
const MODE_32M_LIMIT: f32 = 32.77;

/// Message types [`sniff`] recognises as CARMEN (read or skipped by the reader).
const KNOWN_TYPES: &[&str] = &[
    "FLASER",
    "RLASER",
    "LASER1",
    "LASER2",
    "LASER3",
    "LASER4",
    "ROBOTLASER0",
    "ROBOTLASER1",
    "ROBOTLASER2",
    "RAWLASER1",
    "RAWLASER2",
    "RAWLASER3",
    "RAWLASER4",
    "ODOM",
    "TRUEPOS",
    "PARAM",
    "SYNC",
    "NEFF",
    "SONAR",
    "BUMPER",
    "SCANMARK",
    "POSITIONLASER",
    "IMU",
    "GPSNMEAGGA",
    "GPSNMEARMC",
];

/// How [`CarmenReader`] treats what it cannot use.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CarmenOptions {
    /// Return a malformed line as [`Error::Format`] instead of skipping and counting it.
    pub strict: bool,
    /// `range_max` for every `FLASER`/`RLASER` line, replacing the per-line rule of the
    /// module documentation (for a log whose sensor has another maximum).
    pub flaser_range_max: Option<f32>,
    /// The longest line read, bytes (default
    /// [`DEFAULT_MAX_DECOMPRESSED_BYTES`](crate::log::DEFAULT_MAX_DECOMPRESSED_BYTES)): a
    /// longer one — a gzip that inflates to one endless line — ends the read with an error
    /// naming the line, before it is held whole.
    pub max_line_bytes: Option<u64>,
    /// The most beams one laser line may hold (default `[limits] beams_per_scan`'s,
    /// 10⁶): a line with more ends the read with [`Error::Limit`] naming the key.
    pub max_beams: Option<u64>,
}

/// The beam angles of a `FLASER`/`RLASER` line with `n` readings, as
/// `(angle_min, angle_increment)` in radians.
///
/// * n = 180: 1° steps from −90° (the last beam is +89°);
/// * n = 181: 1° steps over [−90°, +90°];
/// * n = 360: 0.5° steps from −90° (the last beam is +89.5°);
/// * n = 361: 0.5° steps over [−90°, +90°];
/// * any other n ≥ 2: spread evenly over [−90°, +90°], first and last beam included
///   (CARMEN has no convention for them; a 180° field of view is the usual one);
/// * n ≤ 1: a single beam straight ahead (0, 0).
pub fn flaser_angles(n: usize) -> (f64, f64) {
    match n {
        180 | 181 => (-PI / 2.0, PI / 180.0),
        360 | 361 => (-PI / 2.0, PI / 360.0),
        0 | 1 => (0.0, 0.0),
        _ => (-PI / 2.0, PI / (n - 1) as f64),
    }
}

/// True when `first_bytes` (the start of a file, any length; a few KiB is plenty) look
/// like a CARMEN log.
///
/// Gzipped content is recognised by its magic bytes and decompressed here (as far as
/// the given bytes go), so the caller passes the file's first bytes as they are. The
/// test: skipping blank lines and `#`/`##` comments, the first line starts with a known
/// CARMEN message type (`FLASER`, `ODOM`, `PARAM`, `ROBOTLASER1`, `NEFF`, …). When the
/// bytes hold only comments, they must include CARMEN's header comment
/// (`# message formats defined: …`). A ROS bag (`#ROSBAG`) is never CARMEN.
pub fn sniff(first_bytes: &[u8]) -> bool {
    if first_bytes.starts_with(&GZIP_MAGIC) {
        let mut text = Vec::new();
        let mut decoder = flate2::read::MultiGzDecoder::new(first_bytes);
        let mut chunk = [0u8; 4096];
        while text.len() < BUFFER {
            match decoder.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(k) => text.extend_from_slice(&chunk[..k]),
            }
        }
        sniff_text(&text)
    } else {
        sniff_text(first_bytes)
    }
}

fn sniff_text(bytes: &[u8]) -> bool {
    let mut saw_header = false;
    let mut lines = bytes.split(|&b| b == b'\n').peekable();
    while let Some(line) = lines.next() {
        let complete = lines.peek().is_some();
        let line = line.trim_ascii_start();
        if line.is_empty() {
            continue;
        }
        if line.starts_with(b"#") {
            if line.starts_with(b"#ROSBAG") {
                return false;
            }
            if line.windows(b"message formats defined".len()).any(|w| w == b"message formats defined") {
                saw_header = true;
            }
            continue;
        }
        let token = match line.iter().position(|b| b.is_ascii_whitespace()) {
            Some(end) => &line[..end],
            None if complete => line,
            // The first token is cut off by the end of the bytes: undecided.
            None => return saw_header,
        };
        return KNOWN_TYPES.iter().any(|t| t.as_bytes() == token);
    }
    saw_header
}

/// The byte source: as given, or gunzipped.
enum Input<R> {
    Plain(R),
    Gzip(BufReader<MultiGzDecoder<R>>),
    /// Gzip decompressed on a second thread ([`CarmenReader::open`]).
    GzipAhead(BufReader<crate::read_ahead::ReadAhead>),
}

/// A CARMEN log opened for reading: messages in file order, streamed line by line.
///
/// Also an [`Iterator`] over the same items as [`LogReader::next_message`].
pub struct CarmenReader<R> {
    input: Input<R>,
    path: PathBuf,
    options: CarmenOptions,
    line: Vec<u8>,
    line_number: u64,
    done: bool,
    stats: ReadStats,
    params: BTreeMap<String, String>,
}

impl CarmenReader<BufReader<File>> {
    /// Opens the log at `path`, plain text or gzip (recognised by its magic bytes, not
    /// by the file name).
    pub fn open(path: impl AsRef<Path>, options: CarmenOptions) -> Result<Self> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let mut reader = BufReader::with_capacity(BUFFER, file);
        let input = if reader.fill_buf().map_err(|e| Error::io(path, e))?.starts_with(&GZIP_MAGIC) {
            // A file is ours to hand to another thread: decompress there, parse here, so
            // a gzipped log reads at the speed of the parser rather than of both in turn.
            let ahead = crate::read_ahead::ReadAhead::spawn(MultiGzDecoder::new(reader), 4 * BUFFER, 4)
                .map_err(|e| Error::io(path, e))?;
            Input::GzipAhead(BufReader::with_capacity(BUFFER, ahead))
        } else {
            Input::Plain(reader)
        };
        Ok(Self::with_input(path.to_path_buf(), input, options))
    }
}

impl<R: BufRead> CarmenReader<R> {
    /// Reads a log from `reader`, plain text or gzip (recognised by the magic bytes the
    /// first `fill_buf` shows, which for files and byte slices is the start of the data).
    /// `name` names the log in errors and descriptions.
    pub fn from_reader(name: impl AsRef<Path>, mut reader: R, options: CarmenOptions) -> Result<Self> {
        let path = name.as_ref().to_path_buf();
        let gzip = reader.fill_buf().map_err(|e| Error::io(&path, e))?.starts_with(&GZIP_MAGIC);
        let input = if gzip {
            Input::Gzip(BufReader::with_capacity(BUFFER, MultiGzDecoder::new(reader)))
        } else {
            Input::Plain(reader)
        };
        Ok(Self::with_input(path, input, options))
    }

    fn with_input(path: PathBuf, input: Input<R>, options: CarmenOptions) -> Self {
        Self {
            input,
            path,
            options,
            line: Vec::with_capacity(8 * 1024),
            line_number: 0,
            done: false,
            stats: ReadStats::default(),
            params: BTreeMap::new(),
        }
    }

    /// The `PARAM` lines read so far, name → value (the last one wins; a value is the
    /// first word after the name).
    pub fn params(&self) -> &BTreeMap<String, String> {
        &self.params
    }

    /// The value of `PARAM name`, if read so far.
    pub fn param(&self, name: &str) -> Option<&str> {
        self.params.get(name).map(String::as_str)
    }

    /// The number of lines read so far.
    pub fn line_number(&self) -> u64 {
        self.line_number
    }

    /// The name given to the log (its path for [`CarmenReader::open`]).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads the next line into `self.line`; `Ok(None)` when it is longer than the limit
    /// (the reader has then read one byte past the limit and stops).
    fn read_line(&mut self) -> std::io::Result<Option<usize>> {
        self.line.clear();
        let limit = self.options.max_line_bytes.unwrap_or(crate::log::DEFAULT_MAX_DECOMPRESSED_BYTES);
        let n = match &mut self.input {
            Input::Plain(r) => read_until_bounded(r, b'\n', limit, &mut self.line),
            Input::Gzip(r) => read_until_bounded(r, b'\n', limit, &mut self.line),
            Input::GzipAhead(r) => read_until_bounded(r, b'\n', limit, &mut self.line),
        }?;
        Ok((n as u64 <= limit || self.line.ends_with(b"\n") && n as u64 - 1 <= limit).then_some(n))
    }

    fn read_error(&self, e: std::io::Error) -> Error {
        if matches!(self.input, Input::Plain(_)) {
            return Error::io(&self.path, e);
        }
        let after = self.line_number;
        match e.kind() {
            ErrorKind::UnexpectedEof => {
                Error::truncated(&self.path, Location::File, format!("gzip stream ends early after line {after}"))
            }
            ErrorKind::InvalidInput | ErrorKind::InvalidData => {
                Error::format(&self.path, Location::File, format!("gzip stream is corrupt after line {after}: {e}"))
            }
            _ => Error::io(&self.path, e),
        }
    }
}

impl<R: BufRead> LogReader for CarmenReader<R> {
    fn next_message(&mut self) -> Option<Result<LogMessage>> {
        while !self.done {
            match self.read_line() {
                Ok(Some(0)) => self.done = true,
                Ok(None) => {
                    self.done = true;
                    let limit = self.options.max_line_bytes.unwrap_or(crate::log::DEFAULT_MAX_DECOMPRESSED_BYTES);
                    self.line = Vec::new();
                    let what = format!(
                        "longer than the limit of {limit} bytes (limits.decompressed_mib raises it): not a CARMEN \
                         log line; reading stops here"
                    );
                    return Some(Err(Error::limit(&self.path, Location::Line(self.line_number + 1), what)));
                }
                Ok(Some(_)) => {
                    self.line_number += 1;
                    match parse_line(&self.line, &self.options, &mut self.params) {
                        Parsed::Ignored => {}
                        Parsed::Message(LogMessage::Scan(s)) => {
                            let max = self.options.max_beams.unwrap_or(LimitsConfig::default().beams_per_scan);
                            return Some(match super::image::scan_over_limit(s.scan.ranges.len(), max) {
                                Some(why) => Err(Error::limit(&self.path, Location::Line(self.line_number), why)),
                                None => Ok(LogMessage::Scan(s)),
                            });
                        }
                        Parsed::Message(m) => return Some(Ok(m)),
                        Parsed::Skipped(kind) => self.stats.skip_type(kind),
                        Parsed::Malformed(message) => {
                            let err = Error::format(&self.path, Location::Line(self.line_number), message);
                            if self.options.strict {
                                return Some(Err(err));
                            }
                            self.stats.malformed(err.to_string());
                        }
                    }
                }
                Err(e) => {
                    self.done = true;
                    return Some(Err(self.read_error(e)));
                }
            }
        }
        None
    }

    fn stats(&self) -> &ReadStats {
        &self.stats
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<LogMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_message()
    }
}

#[cfg(test)]
mod tests;
