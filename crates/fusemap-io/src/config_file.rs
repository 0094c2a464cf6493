//! Loading the run configuration from a TOML file (TOML v1.0.0, <https://toml.io/en/v1.0.0>).
//!
//! The file maps one to one onto [`fusemap_core::config::Config`]; `configs/example.toml`
//! at the repository root lists every key with its default and meaning. Unknown keys are
//! errors (the types use serde's `deny_unknown_fields`): a misspelt `p_ocupied` must not
//! be silently ignored while the run uses the default.
//!
//! Every error names the file and where in it:
//! * syntax and type errors carry the 1-based line the TOML parser points at, and the
//!   parser's one-line message (which names the key, e.g. ``unknown field `p_ocupied` ``);
//! * validation errors ([`Config::validate`]) name the field as a TOML path
//!   (`lidar[0].p_occ`) and, when the key is written in the file, its line. A field the
//!   file leaves at its default has no line.

use crate::input_file::line_of;
use crate::{Error, Location, Result};
use fusemap_core::config::{Config, Plan};
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Reads, parses and validates the configuration file at `path`.
///
/// Errors: [`Error::Io`] when the file cannot be read, [`Error::Format`] for anything
/// wrong inside it (see the module documentation).
pub fn load_config(path: &Path) -> Result<Config> {
    let text = read_text(path)?;
    parse_config_str(&text, path)
}

/// Reads, parses and validates the configuration file at `path`, giving the validated
/// plan (validated once; [`load_config`] gives the file's values instead).
pub fn load_plan(path: &Path) -> Result<Plan> {
    let text = read_text(path)?;
    Ok(parse_plan_str(&text, path)?.1)
}

/// Parses and validates configuration `text`; `path` is only used in error messages.
pub fn parse_config_str(text: &str, path: &Path) -> Result<Config> {
    Ok(parse_plan_str(text, path)?.0)
}

/// Parses and validates configuration `text`: the file's values and the plan validated
/// from them; `path` is only used in error messages.
pub fn parse_plan_str(text: &str, path: &Path) -> Result<(Config, Plan)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let config: Config = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    // serde fills a fixed-size array (`[f64; 2]`) from the first elements of a longer
    // TOML array without complaint, so `origin = [x, y, yaw]` would silently lose yaw.
    if let Some(n) = array_len(text, "map.origin").filter(|&n| n != 2) {
        return Err(field_error(path, text, "map.origin", format!("expected [x, y], got {n} numbers")));
    }
    for i in 0..config.sensor.len() {
        let field = format!("sensor[{i}].datum");
        if let Some(n) = array_len(text, &field).filter(|&n| n != 3) {
            return Err(field_error(
                path,
                text,
                &field,
                format!("expected [latitude, longitude, altitude], got {n} numbers"),
            ));
        }
    }
    let plan = config.validate().map_err(|e| field_error(path, text, &e.field, e.message))?;
    Ok((config, plan))
}

/// Reads a config, world or scenario file as UTF-8 text, refusing one past
/// [`MAX_DESCRIPTION_BYTES`](crate::input_file::MAX_DESCRIPTION_BYTES); invalid UTF-8 is
/// a format error at the line where it starts.
pub fn read_text(path: &Path) -> Result<String> {
    use crate::input_file::{read_text_within, MAX_DESCRIPTION_BYTES};
    read_text_within(path, MAX_DESCRIPTION_BYTES, "a config, world or scenario file")
}

/// Turns a `toml` error into an [`Error::Format`] at the line its span starts on, with
/// the message reduced to one line.
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let location = match e.span() {
        Some(span) => Location::Line(line_of(text.as_bytes(), span.start)),
        None => Location::File,
    };
    Error::format(path, location, one_line(e.message()))
}

/// The first non-empty line of a possibly multi-line message, with a following
/// `expected …` line appended when the first line alone would not say what was wrong
/// (the TOML parser's syntax errors come as "invalid string" / "expected `\"`").
fn one_line(message: &str) -> String {
    let mut lines = message.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("invalid TOML").to_string();
    match lines.next() {
        Some(next) if next.starts_with("expected") && !first.contains("expected") => {
            format!("{first}, {next}")
        }
        _ => first,
    }
}

/// A validation error on `field` (a TOML path such as `lidar[0].p_occ`), located at the
/// field's line when the file writes it.
pub fn field_error(path: &Path, text: &str, field: &str, message: String) -> Error {
    let location = match field_line(text, field) {
        Some(line) => Location::LineField(line, field.to_string()),
        None => Location::Field(field.to_string()),
    };
    Error::format(path, location, message)
}

/// The line where the TOML path `field` (`map.prior`, `lidar[0].mount`, `wall[3].to`)
/// is written in `text`, `None` when it is not (left at its default) or the text does
/// not parse.
pub(crate) fn field_line(text: &str, field: &str) -> Option<u64> {
    let root = DeTable::parse(text).ok()?;
    let (span, _) = locate(&root, field)?;
    Some(line_of(text.as_bytes(), span.start))
}

/// The number of elements of the array at `field`, `None` when it is absent or not an
/// array.
fn array_len(text: &str, field: &str) -> Option<usize> {
    let root = DeTable::parse(text).ok()?;
    match locate(&root, field)?.1 {
        DeValue::Array(items) => Some(items.len()),
        _ => None,
    }
}

/// The span and value of the TOML path `field` in a parsed document.
fn locate<'r, 'i>(root: &'r Spanned<DeTable<'i>>, field: &str) -> Option<(Range<usize>, &'r DeValue<'i>)> {
    let mut found: Option<(Range<usize>, &'r DeValue<'i>)> = None;
    for segment in field.split('.') {
        let (name, indices) = split_indices(segment)?;
        let table = match found {
            None => root.get_ref(),
            Some((_, DeValue::Table(t))) => t,
            Some(_) => return None,
        };
        let (_, value) = table.iter().find(|(k, _)| k.get_ref() == name)?;
        let mut here = (value.span(), value.get_ref());
        for index in indices {
            let DeValue::Array(items) = here.1 else {
                return None;
            };
            let item = items.get(index)?;
            here = (item.span(), item.get_ref());
        }
        found = Some(here);
    }
    found
}

/// `lidar[0]` → (`lidar`, [0]); `map` → (`map`, []).
fn split_indices(segment: &str) -> Option<(&str, Vec<usize>)> {
    let name_end = segment.find('[').unwrap_or(segment.len());
    let (name, mut rest) = segment.split_at(name_end);
    let mut indices = Vec::new();
    while let Some(r) = rest.strip_prefix('[') {
        let close = r.find(']')?;
        indices.push(r[..close].parse().ok()?);
        rest = &r[close + 1..];
    }
    rest.is_empty().then_some((name, indices))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn parse(text: &str) -> Result<Config> {
        parse_config_str(text, Path::new("robot.toml"))
    }

    fn location(e: Error) -> (Location, String) {
        match e {
            Error::Format { location, message, path } => {
                assert_eq!(path, Path::new("robot.toml"));
                (location, message)
            }
            other => panic!("expected a format error, got {other}"),
        }
    }

    #[test]
    fn empty_file_is_the_default() {
        assert_eq!(parse("").unwrap(), Config::default());
        assert_eq!(parse("# nothing\n\n").unwrap(), Config::default());
    }

    #[test]
    fn values_are_read() {
        let c = parse(
            "[map]\nresolution = 0.1\norigin = [-5, -5.0]\n\n[[sensor]]\nkind = \"lidar\"\nname = \"front\"\np_occ = 0.8\n\
             max_range_policy = \"clear\"\n[sensor.base_from_sensor]\nx = 0.2\n\n[[sensor]]\nkind = \"lidar\"\n\
             name = \"rear\"\n\n[[sensor]]\nkind = \"gnss\"\ndatum = [48.1, 11.5, 520.0]\n",
        )
        .unwrap();
        assert_eq!(c.map.resolution, 0.1);
        assert_eq!(c.map.origin, Some([-5.0, -5.0]));
        assert_eq!(c.sensor.len(), 3);
        assert_eq!(c.sensor[0].p_occ, Some(0.8));
        assert_eq!(c.sensor[0].base_from_sensor.map(|m| m.x), Some(0.2));
        assert_eq!(c.sensor[1].name.as_deref(), Some("rear"));
        assert_eq!(c.sensor[1].p_occ, None);
        assert_eq!(c.sensor[2].datum, Some([48.1, 11.5, 520.0]));
        let plan = c.validate().unwrap();
        assert_eq!(plan.lidars.len(), 2);
        assert_eq!(plan.lidars[1].model.params().p_occ, 0.9);
    }

    #[test]
    fn a_class_table_may_leave_out_its_colour() {
        let c = parse("[[class]]\nid = 3\nname = \"rack\"\np_occupied = 0.8\n").unwrap();
        assert_eq!(c.class[0].color, None);
        let classes = c.validate().unwrap().classes;
        assert_eq!(classes.get(0).color, fusemap_core::config::default_class_color(3));
    }

    #[test]
    fn unknown_key_names_key_and_line() {
        let e = parse("[map]\nresolution = 0.05\n\n[[sensor]]\nkind = \"lidar\"\np_ocupied = 0.9\n").unwrap_err();
        let text = e.to_string();
        let (loc, msg) = location(e);
        assert_eq!(loc, Location::Line(6), "{text}");
        assert!(msg.contains("p_ocupied"), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
        assert!(text.starts_with("robot.toml:6: "), "{text}");
        // The tables of the old layout are refused, not ignored.
        let e = parse("[[lidar]]\nname = \"laser\"\n").unwrap_err();
        assert!(e.to_string().contains("lidar"), "{e}");
        let e = parse("colour = 1\n").unwrap_err();
        assert_eq!(location(e).0, Location::Line(1));
    }

    #[test]
    fn wrong_type_names_line() {
        let e = parse("[map]\nprior = 0.5\nresolution = \"fine\"\n").unwrap_err();
        let (loc, msg) = location(e);
        assert_eq!(loc, Location::Line(3), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
        let e = parse("[[sensor]]\nkind = \"lidar\"\nmax_range_policy = \"sometimes\"\n").unwrap_err();
        let (loc, msg) = location(e);
        assert_eq!(loc, Location::Line(3), "{msg}");
        assert!(msg.contains("sometimes"), "{msg}");
    }

    #[test]
    fn syntax_error_names_line() {
        let e = parse("[map]\nresolution = 0.05\nprior = = 0.5\n").unwrap_err();
        let (loc, msg) = location(e);
        assert_eq!(loc, Location::Line(3), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
        let e = parse("[map\n").unwrap_err();
        assert_eq!(location(e).0, Location::Line(1));
        let e = parse("a = \"unterminated\n").unwrap_err();
        assert_eq!(location(e).0, Location::Line(1));
    }

    #[test]
    fn validation_names_field_and_line() {
        let e = parse("[map]\nprior = 0.5\n\n[[sensor]]\nkind = \"lidar\"\np_occ = 0.3\n").unwrap_err();
        let text = e.to_string();
        let (loc, msg) = location(e);
        assert_eq!(loc, Location::LineField(6, "sensor[0].p_occ".into()));
        assert!(msg.contains("0.3"), "{msg}");
        assert!(text.contains("sensor[0].p_occ"), "{text}");
        // NaN is valid TOML but not a valid probability.
        let e = parse("[map]\nprior = nan\n").unwrap_err();
        assert_eq!(location(e).0, Location::LineField(2, "map.prior".into()));
        // A field left at its default has no line: the prior makes the default p_free wrong.
        let e = parse("[map]\nprior = 0.3\nclamp_min = 0.1\n\n[[sensor]]\nkind = \"lidar\"\n").unwrap_err();
        assert_eq!(location(e).0, Location::Field("sensor[0].p_free".into()));
        // A whole table.
        let e = parse("[map]\nclamp_max = 0.4\n").unwrap_err();
        assert_eq!(location(e).0, Location::LineField(1, "map".into()));
        let e = parse("[map]\norigin = [1.0, 2.0, 0.5]\n").unwrap_err();
        assert_eq!(location(e).0, Location::LineField(2, "map.origin".into()));
        assert!(parse("[map]\norigin = [1.0]\n").is_err());
        let e = parse("[[sensor]]\nkind = \"imu\"\nname = \"a\"\n[[sensor]]\nkind = \"lidar\"\nname = \"a\"\n")
            .unwrap_err();
        assert_eq!(location(e).0, Location::LineField(6, "sensor[1].name".into()));
        let e = parse("[[sensor]]\nkind = \"imu\"\np_occ = 0.7\n").unwrap_err();
        assert_eq!(location(e).0, Location::LineField(3, "sensor[0].p_occ".into()));
        let e = parse("[[sensor]]\nkind = \"gnss\"\ndatum = [48.1, 11.5]\n").unwrap_err();
        assert_eq!(location(e).0, Location::Line(3));
        let e = parse("[[sensor]]\nkind = \"gnss\"\ndatum = [48.1, 11.5, 500, 1]\n").unwrap_err();
        assert_eq!(location(e).0, Location::LineField(3, "sensor[0].datum".into()));
    }

    #[test]
    fn missing_file_is_io() {
        let p = std::env::temp_dir().join(format!("fusemap-no-such-config-{}.toml", std::process::id()));
        assert!(matches!(load_config(&p), Err(Error::Io { path, .. }) if path == p));
    }

    #[test]
    fn not_utf8_names_line() {
        let p = std::env::temp_dir().join(format!("fusemap-latin1-{}.toml", std::process::id()));
        std::fs::write(&p, b"[map]\n# caf\xe9\n").unwrap();
        let e = load_config(&p).unwrap_err();
        assert!(matches!(&e, Error::Format { location: Location::Line(2), .. }), "{e}");
        std::fs::remove_file(&p).unwrap();
    }

    #[test]
    fn example_file_is_the_default() {
        let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../configs/example.toml");
        let c = load_config(&p).unwrap();
        let d = Config::default();
        assert_eq!((c.map, &c.log, &c.estimator), (d.map, &d.log, &d.estimator));
        assert_eq!(format!("{:?}", c.slam.validate()), format!("{:?}", d.slam.validate()));
        // Its one sensor table is the default lidar, written out.
        assert_eq!(c.sensor.len(), 1);
        let (plan, default) = (c.validate().unwrap(), d.validate().unwrap());
        assert_eq!(plan.lidars[0].name, default.lidars[0].name);
        assert_eq!(plan.lidars[0].model.params(), default.lidars[0].model.params());
        assert_eq!(plan.lidars[0].topic, None);
        // Every other section: [fusion], [limits], and the [[class]] tables, which write
        // out the default class table.
        assert_eq!(format!("{:?}", c.fusion), format!("{:?}", d.fusion));
        assert_eq!(format!("{:?}", c.limits), format!("{:?}", d.limits));
        assert_eq!(c.validate, d.validate);
        assert_eq!(plan.classes, default.classes);
        assert_eq!(c.class.len(), default.classes.len());
        // The whole plan but how its lidar came to be (the example lists it; the default
        // plans it): every section's validated form, with what each derives from the others.
        let mut listed = plan.clone();
        listed.lidars[0].explicit = default.lidars[0].explicit;
        assert_eq!(format!("{listed:?}"), format!("{default:?}"));
        // Every line that sets a value carries its own comment block above it: no bare keys.
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let l = l.trim();
            if l.contains('=') && !l.starts_with('#') {
                assert!(i > 0 && lines[i - 1].trim_start().starts_with('#'), "line {} has no comment: {l}", i + 1);
            }
        }
    }

    #[test]
    fn field_paths() {
        let text = "[map]\nprior = 0.5\n\n[[sensor]]\nname = \"a\"\n[sensor.base_from_sensor]\nyaw = 1\n[[sensor]]\nname = \"b\"\n";
        assert_eq!(field_line(text, "map.prior"), Some(2));
        assert_eq!(field_line(text, "sensor[0].name"), Some(5));
        assert_eq!(field_line(text, "sensor[0].base_from_sensor.yaw"), Some(7));
        assert_eq!(field_line(text, "sensor[1].name"), Some(9));
        assert_eq!(field_line(text, "sensor[2].name"), None);
        assert_eq!(field_line(text, "map.resolution"), None);
        assert_eq!(field_line(text, "map[0]"), None);
        assert_eq!(split_indices("a[1][2]"), Some(("a", vec![1, 2])));
        assert_eq!(split_indices("a[x]"), None);
        assert_eq!(one_line("invalid string\nexpected `\"`, `'`"), "invalid string, expected `\"`, `'`");
        assert_eq!(one_line("\n  unknown field `x`\n"), "unknown field `x`");
    }
}
