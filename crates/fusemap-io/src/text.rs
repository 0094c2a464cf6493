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

/// [`printable`], with `|` escaped too: for a cell of a Markdown table, where a `|` from
/// the log would split the row.
pub fn table_cell(s: &str) -> Cow<'_, str> {
    match printable(s) {
        Cow::Borrowed(b) if !b.contains('|') => Cow::Borrowed(b),
        other => Cow::Owned(other.replace('|', "\\|")),
    }
}

#[cfg(test)]
mod tests {
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
