//! Strings from a log on their way to a person: topic names, frame ids and CARMEN tokens
//! are whatever the log says, and a log can say `\x1b]0;…\x07` (rewrite the terminal's
//! title), `\x1b[2J` (clear it), a NUL or a newline that forges a row of a table. Every such
//! string is escaped before it reaches a terminal or a report; `summary.json` needs no
//! help (JSON escapes control characters itself).

use std::borrow::Cow;
use std::fmt::Write;

/// `s` with every control character (C0, DEL, C1) written as a visible escape — `\n`,
/// `\t`, `\r`, `\0`, else `\u{1b}` — so the text cannot act on the terminal.
/// Borrowed when nothing needs escaping.
pub fn printable(s: &str) -> Cow<'_, str> {
    if !s.chars().any(char::is_control) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\0' => out.push_str("\\0"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// `s` with every number written out to more than 24 characters (Rust and the TOML
/// parser print an `f64` in full: 1e300 as 301 digits, 1e-300 as 302) put in scientific
/// notation, the shortest form that reads back as the same `f64`. Borrowed when there is
/// none.
pub fn compact_numbers(s: &str) -> Cow<'_, str> {
    const LONG: usize = 24;
    let b = s.as_bytes();
    let mut out = String::new();
    let (mut copied, mut i) = (0, 0);
    while i < b.len() {
        let starts = b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.'));
        if !starts {
            i += 1;
            continue;
        }
        let mut end = i;
        while end < b.len() && b[end].is_ascii_digit() {
            end += 1;
        }
        if end + 1 < b.len() && b[end] == b'.' && b[end + 1].is_ascii_digit() {
            end += 1;
            while end < b.len() && b[end].is_ascii_digit() {
                end += 1;
            }
        }
        if end - i > LONG {
            if let Ok(v) = s[i..end].parse::<f64>() {
                out.push_str(&s[copied..i]);
                let _ = write!(out, "{v:e}");
                copied = end;
            }
        }
        i = end;
    }
    if copied == 0 {
        return Cow::Borrowed(s);
    }
    out.push_str(&s[copied..]);
    Cow::Owned(out)
}

/// [`printable`], with `|` escaped too: for a cell of a Markdown table, where a `|` from
/// the log would split the row.
pub fn table_cell(s: &str) -> Cow<'_, str> {
    match printable(s) {
        Cow::Borrowed(b) if !b.contains('|') => Cow::Borrowed(b),
        other => Cow::Owned(other.replace('|', "\\|")),
    }
}

/// An error and its sources, `outer: inner: innermost` (a source whose text the outer
/// message already holds is not repeated).
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(inner) = source {
        let text = inner.to_string();
        if !s.contains(&text) {
            s.push_str(": ");
            s.push_str(&text);
        }
        source = inner.source();
    }
    s
}

/// An error as fusemap prints it after `error: `: its chain on one line, numbers a
/// reader can take in, and nothing a log wrote into a name (escape sequences, NUL)
/// reaching the terminal as itself. The CLI and the Python package both use it.
pub fn error_line(e: &dyn std::error::Error) -> String {
    let s = compact_numbers(&error_chain(e)).replace('\n', " ");
    printable(&s).into_owned()
}

#[cfg(test)]
mod tests {
    #[test]
    fn long_numbers_are_put_in_scientific_notation() {
        use super::compact_numbers;
        let huge = format!("got {}, over", 1e300);
        assert_eq!(compact_numbers(&huge), "got 1e300, over");
        let tiny = format!("got {} m", 1e-300);
        assert_eq!(compact_numbers(&tiny), "got 1e-300 m");
        let toml = format!("floating point `{:.1}`, expected usize", 1e300);
        assert_eq!(compact_numbers(&toml), "floating point `1e300`, expected usize");
        // Stamps in nanoseconds, line numbers, hashes and names stay as they are.
        for s in ["at stamp 1000050000000 ns", "robot.toml:6: x", "id a1234567890123456789012345678", "v1.2.3"] {
            assert!(matches!(compact_numbers(s), std::borrow::Cow::Borrowed(_)), "{s}");
        }
    }

    use super::*;

    #[test]
    fn plain_names_pass_untouched() {
        for s in ["/scan", "base_link", "FLASER", "sensor_msgs/msg/LaserScan", "größe µ°"] {
            assert!(matches!(printable(s), Cow::Borrowed(_)), "{s}");
            assert!(matches!(table_cell(s), Cow::Borrowed(_)), "{s}");
        }
    }

    #[test]
    fn terminal_controls_and_row_breaks_are_made_visible() {
        assert_eq!(printable("/scan\x1b]0;pwned\x07"), "/scan\\u{1b}]0;pwned\\u{7}");
        assert_eq!(printable("a\nb\r\tc\0d\u{7f}e\u{9b}f"), "a\\nb\\r\\tc\\0d\\u{7f}e\\u{9b}f");
        assert_eq!(table_cell("/a | 1 | 2 |\n| /forged"), "/a \\| 1 \\| 2 \\|\\n\\| /forged");
        for s in ["\x1b[2J", "x\ny", "\u{85}", "\0"] {
            assert!(!printable(s).chars().any(char::is_control), "{s:?}");
        }
    }
}
