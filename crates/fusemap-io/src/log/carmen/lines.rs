//! One line of a CARMEN log: its message type, its fields, and the message it makes
//! (`FLASER`/`RLASER`, `ROBOTLASER1`, `ODOM`, `PARAM`), or why it makes none. The reader in
//! the parent module streams the lines; this is the text format.

use super::*;

/// What one line is.
#[allow(clippy::large_enum_variant)] // Returned once per line and unpacked at once (see LogMessage).
pub(super) enum Parsed<'a> {
    /// Blank, comment or `PARAM`.
    Ignored,
    Message(LogMessage),
    /// A message type the reader does not use.
    Skipped(&'a str),
    /// What is wrong with it.
    Malformed(String),
}

pub(super) fn parse_line<'a>(
    bytes: &'a [u8],
    options: &CarmenOptions,
    params: &mut BTreeMap<String, String>,
) -> Parsed<'a> {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Parsed::Malformed("the line is not UTF-8 text".into());
    };
    let Some(kind) = text.split_ascii_whitespace().next() else {
        return Parsed::Ignored;
    };
    if kind.starts_with('#') {
        return Parsed::Ignored;
    }
    let result = match kind {
        "FLASER" | "RLASER" => parse_flaser(kind, text, options),
        "ROBOTLASER1" => parse_laser_with_params(kind, text, true),
        "RAWLASER1" | "RAWLASER2" | "RAWLASER3" | "RAWLASER4" => parse_laser_with_params(kind, text, false),
        "ODOM" => parse_odom(text),
        "PARAM" => parse_param(text, params).map(|()| None),
        _ if is_type_name(kind) => return Parsed::Skipped(kind),
        _ => return Parsed::Malformed(format!("not a CARMEN message: the line starts with `{}`", shorten(kind))),
    };
    match result {
        Ok(Some(message)) => Parsed::Message(message),
        Ok(None) => Parsed::Ignored,
        Err(why) => Parsed::Malformed(format!("{kind}: {why}")),
    }
}

/// CARMEN message types are upper-case words: `FLASER`, `ROBOTLASER1`, `GPSNMEAGGA`.
pub(super) fn is_type_name(s: &str) -> bool {
    s.len() <= 32
        && s.as_bytes()[0].is_ascii_uppercase()
        && s.bytes().all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
}

/// `s`, cut to at most 24 characters for a message.
pub(super) fn shorten(s: &str) -> String {
    match s.char_indices().nth(24) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// The fields of one line, read in order; errors name the 1-based field (the message
/// type is field 1, as in awk).
pub(super) struct Fields<'a> {
    tokens: SplitAsciiWhitespace<'a>,
    /// 1-based number of the field `next` returns.
    number: usize,
    /// How many fields the line has.
    total: usize,
}

impl<'a> Fields<'a> {
    /// The fields of `text` after the message type.
    fn new(text: &'a str) -> Self {
        let mut tokens = text.split_ascii_whitespace();
        tokens.next();
        Self { tokens, number: 2, total: text.split_ascii_whitespace().count() }
    }

    fn next(&mut self, what: &str) -> Result<&'a str, String> {
        let token = self
            .tokens
            .next()
            .ok_or_else(|| format!("the line ends at field {} before {what}", self.number.saturating_sub(1)))?;
        self.number += 1;
        Ok(token)
    }

    fn bad(&self, what: &str, token: &str, is_not: &str) -> String {
        format!("field {} ({what}): `{}` is not {is_not}", self.number - 1, shorten(token))
    }

    fn f64(&mut self, what: &str) -> Result<f64, String> {
        let token = self.next(what)?;
        token.parse().map_err(|_| self.bad(what, token, "a number"))
    }

    fn finite(&mut self, what: &str) -> Result<f64, String> {
        let token = self.next(what)?;
        match token.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.bad(what, token, "a finite number")),
            Err(_) => Err(self.bad(what, token, "a number")),
        }
    }

    fn count(&mut self, what: &str) -> Result<usize, String> {
        let token = self.next(what)?;
        token.parse().map_err(|_| self.bad(what, token, "a count"))
    }

    fn stamp(&mut self, what: &str) -> Result<Stamp, String> {
        let token = self.next(what)?;
        parse_stamp(token).ok_or_else(|| self.bad(what, token, "a time stamp in seconds"))
    }

    fn pose(&mut self, what: [&str; 3]) -> Result<Pose2, String> {
        Ok(Pose2::new(self.finite(what[0])?, self.finite(what[1])?, self.finite(what[2])?))
    }

    /// `n` range readings as f32 (NaN and inf kept), with the largest finite one.
    fn ranges(&mut self, n: usize) -> Result<(Vec<f32>, f32), String> {
        let mut ranges =
            crate::bounded::vec_with_capacity(n).map_err(|e| format!("no memory for {n} range readings ({e})"))?;
        let mut largest = f32::NEG_INFINITY;
        for _ in 0..n {
            let token = self.next("a range reading")?;
            let r: f32 = token.parse().map_err(|_| self.bad("range reading", token, "a number"))?;
            if r.is_finite() && r > largest {
                largest = r;
            }
            ranges.push(r);
        }
        Ok((ranges, largest))
    }

    /// Checks that the line has exactly `fixed + counts` fields.
    fn expect_total(&self, fixed: usize, counts: &[usize], what: &str) -> Result<(), String> {
        let expected = counts.iter().try_fold(fixed, |acc, &c| acc.checked_add(c)).unwrap_or(usize::MAX);
        if expected == self.total {
            Ok(())
        } else {
            Err(format!("expected {expected} fields for {what}, found {}", self.total))
        }
    }

    /// Checks that the line has at least `fixed + n` fields.
    fn expect_at_least(&self, fixed: usize, n: usize, what: &str) -> Result<(), String> {
        let expected = fixed.saturating_add(n);
        if self.total >= expected {
            Ok(())
        } else {
            Err(format!("expected at least {expected} fields for {what}, found {}", self.total))
        }
    }
}

/// Parses a time stamp in decimal seconds exactly: `123.456789`, `-0.042`, and the
/// `%g` form `1.13486e+09`, whose decimal point is moved digit by digit. A value below
/// one nanosecond (`6.53023e-43`, which some corrected logs hold) is truncated to 0,
/// as [`Stamp::parse_decimal`] truncates digits beyond nanoseconds.
pub(super) fn parse_stamp(s: &str) -> Option<Stamp> {
    let Some(e) = s.find(['e', 'E']) else {
        return Stamp::parse_decimal(s);
    };
    let (mantissa, exponent) = (&s[..e], &s[e + 1..]);
    let exponent: i64 = exponent.parse().ok()?;
    let (sign, body) = match mantissa.as_bytes().first()? {
        b'-' => ("-", &mantissa[1..]),
        b'+' => ("", &mantissa[1..]),
        _ => ("", mantissa),
    };
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    if (int.is_empty() && frac.is_empty())
        || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit())
        || body.len() > 64
    {
        return None;
    }
    // The digits, with the decimal point after `point` of them.
    let point = (int.len() as i64).checked_add(exponent)?;
    if point < -9 {
        return Some(Stamp::ZERO);
    }
    if point > 20 {
        return None; // beyond ±292 years in nanoseconds
    }
    let digits = || int.bytes().chain(frac.bytes()).map(char::from);
    let n = (int.len() + frac.len()) as i64;
    let mut out = String::with_capacity(96);
    out.push_str(sign);
    if point <= 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', (-point) as usize));
        out.extend(digits());
    } else if point >= n {
        out.extend(digits());
        out.extend(std::iter::repeat_n('0', (point - n) as usize));
    } else {
        out.extend(digits().take(point as usize));
        out.push('.');
        out.extend(digits().skip(point as usize));
    }
    Stamp::parse_decimal(&out)
}

/// `FLASER`/`RLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_ts host logger_ts`.
pub(super) fn parse_flaser(kind: &str, text: &str, options: &CarmenOptions) -> Result<Option<LogMessage>, String> {
    let mut f = Fields::new(text);
    let n = f.count("the number of readings")?;
    f.expect_total(11, &[n], &format!("{n} readings"))?;
    let (ranges, largest) = f.ranges(n)?;
    let pose = f.pose(["x", "y", "theta"])?;
    let odom = f.pose(["odom_x", "odom_y", "odom_theta"])?;
    let stamp = f.stamp("ipc_timestamp")?;
    f.next("ipc_hostname")?;
    let receive = f.stamp("logger_timestamp")?;
    let range_max = options.flaser_range_max.unwrap_or_else(|| flaser_range_max(largest));
    let (angle_min, angle_increment) = flaser_angles(n);
    Ok(Some(LogMessage::Scan(ScanMessage {
        topic: kind.to_string(),
        frame_id: String::new(),
        receive_stamp: Some(receive),
        scan: LaserScan { stamp, angle_min, angle_increment, ranges },
        angle_max: f32::NAN,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max,
        pose: Some(pose),
        odom_pose: Some(odom),
        laser_pose: None,
    })))
}

/// The `FLASER` no-return rule, from the largest finite value on the line.
pub(super) fn flaser_range_max(largest: f32) -> f32 {
    if largest > MODE_50M_LIMIT {
        RANGE_MAX_80M_MODE
    } else if largest > MODE_32M_LIMIT {
        RANGE_MAX_50M_MODE
    } else if largest >= RANGE_MAX_32M_MODE {
        RANGE_MAX_32M_MODE
    } else {
        RANGE_MAX_50M_MODE
    }
}

/// `ROBOTLASER1` (`with_poses`) and `RAWLASERn`: the laser's parameters, ranges and
/// remissions, then for `ROBOTLASER1` the laser and robot poses and the velocities.
pub(super) fn parse_laser_with_params(kind: &str, text: &str, with_poses: bool) -> Result<Option<LogMessage>, String> {
    // Fields besides the readings: type, 7 parameters, 2 counts, 3 stamp fields, and
    // for ROBOTLASER1 two poses and 5 velocities/safety values.
    let fixed = if with_poses { 24 } else { 13 };
    let mut f = Fields::new(text);
    f.f64("laser_type")?;
    let start_angle = f.finite("start_angle")?;
    f.f64("field_of_view")?;
    let resolution = f.finite("angular_resolution")?;
    let maximum_range = f.f64("maximum_range")?;
    f.f64("accuracy")?;
    f.f64("remission_mode")?;
    let n = f.count("the number of readings")?;
    f.expect_at_least(fixed, n, &format!("{n} readings"))?;
    let (ranges, largest) = f.ranges(n)?;
    let m = f.count("the number of remissions")?;
    f.expect_total(fixed, &[n, m], &format!("{n} readings and {m} remissions"))?;
    for _ in 0..m {
        let token = f.next("a remission")?;
        token.parse::<f32>().map_err(|_| f.bad("remission", token, "a number"))?;
    }
    let (laser_pose, pose) = if with_poses {
        let laser = f.pose(["laser_x", "laser_y", "laser_theta"])?;
        let robot = f.pose(["robot_x", "robot_y", "robot_theta"])?;
        for what in ["tv", "rv", "forward_safety_dist", "side_safety_dist", "turn_axis"] {
            f.f64(what)?;
        }
        (Some(laser), Some(robot))
    } else {
        (None, None)
    };
    let stamp = f.stamp("ipc_timestamp")?;
    f.next("ipc_hostname")?;
    let receive = f.stamp("logger_timestamp")?;
    let range_max =
        if maximum_range.is_finite() && maximum_range > 0.0 { maximum_range as f32 } else { flaser_range_max(largest) };
    Ok(Some(LogMessage::Scan(ScanMessage {
        topic: kind.to_string(),
        frame_id: String::new(),
        receive_stamp: Some(receive),
        scan: LaserScan { stamp, angle_min: start_angle, angle_increment: resolution, ranges },
        angle_max: f32::NAN,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max,
        pose,
        odom_pose: None,
        laser_pose,
    })))
}

/// `ODOM x y theta tv rv accel ipc_ts host logger_ts`.
pub(super) fn parse_odom(text: &str) -> Result<Option<LogMessage>, String> {
    let mut f = Fields::new(text);
    f.expect_total(10, &[], "ODOM")?;
    let pose = f.pose(["x", "y", "theta"])?;
    let tv = f.f64("tv")?;
    let rv = f.f64("rv")?;
    f.f64("accel")?;
    let stamp = f.stamp("ipc_timestamp")?;
    f.next("ipc_hostname")?;
    let receive = f.stamp("logger_timestamp")?;
    Ok(Some(LogMessage::Odometry(OdomMessage {
        topic: "ODOM".to_string(),
        stamp,
        receive_stamp: Some(receive),
        frame_id: "odom".to_string(),
        child_frame_id: "base_link".to_string(),
        pose,
        // CARMEN logs no covariances: zeros, ROS's "unknown".
        pose_covariance: [0.0; 36],
        twist: [tv, 0.0, 0.0, 0.0, 0.0, rv],
        twist_covariance: [0.0; 36],
    })))
}

/// `PARAM name value …`: what follows the value (stamps, host) varies between logs.
pub(super) fn parse_param(text: &str, params: &mut BTreeMap<String, String>) -> Result<(), String> {
    let mut f = Fields::new(text);
    let name = f.next("the parameter name")?;
    let value = f.next("the parameter value")?;
    params.insert(name.to_string(), value.to_string());
    Ok(())
}
