//! YAML input: rosbag2's `metadata.yaml` and `map_server`'s map description.
//!
//! Parsed with `saphyr`, a maintained pure-Rust YAML 1.2 parser, so every valid spelling
//! of the same document reads the same: block style, flow style (PyYAML's
//! `default_flow_style=True`) and JSON (a subset of YAML 1.2). A hand-written subset
//! parser read only the block style a given writer happened to produce.
//!
//! What stands in front of the parser, since these files come from other people:
//! - the file is read through [`read_to_end_bounded`](crate::bounded::read_to_end_bounded)
//!   and refused past [`MAX_YAML_BYTES`];
//! - aliases may expand to at most 100,000 nodes, saphyr's own budget (a "billion laughs"
//!   file of a few hundred bytes would otherwise expand to gigabytes), and nesting is
//!   bounded by the parser's recursion limit (the tests below check both);
//! - a key given twice in one mapping is an error, as the YAML specification says.
//!
//! Every node keeps its line, so an error names the line of the value it is about.

use crate::error::Result;
use saphyr::{LoadableYamlNode, MarkedYaml, Scalar, YamlData};
use std::path::Path;

/// A parsed YAML node with its position.
pub(crate) type Node<'a> = MarkedYaml<'a>;

/// The largest YAML file read: a rosbag2 bag of thousands of topics and storage files has
/// a `metadata.yaml` of a few hundred kilobytes; a map description is a few hundred bytes.
pub const MAX_YAML_BYTES: u64 = 16 << 20;

/// A parse error: the 1-based line (0 for the file as a whole) and what is wrong.
pub type YamlError = (u64, String);

/// Reads a YAML file as UTF-8 text, refusing one past [`MAX_YAML_BYTES`].
pub(crate) fn read_text(path: &Path) -> Result<String> {
    crate::input_file::read_text_within(path, MAX_YAML_BYTES, "a YAML description file")
}

/// Parses the first document of `text`; an empty file or one of comments only is an error.
pub(crate) fn parse(text: &str) -> std::result::Result<Node<'_>, YamlError> {
    let documents = Node::load_from_str(text).map_err(|e| {
        let at = e.marker();
        let why = if e.info().contains("duplicated key") { " (a key given twice)" } else { "" };
        (at.line() as u64, format!("not valid YAML: {}{why} (column {})", e.info(), at.col() + 1))
    })?;
    let root = documents.into_iter().next().ok_or_else(|| (0, "holds no YAML document".to_string()))?;
    if matches!(root.data, YamlData::Value(Scalar::Null)) {
        return Err((0, "holds no YAML document".to_string()));
    }
    Ok(root)
}

/// The node's 1-based line.
pub(crate) fn line(node: &Node<'_>) -> u64 {
    node.span.start.line() as u64
}

/// The node without its tag (`!!str x` is `x`).
fn untagged<'n, 'a>(node: &'n Node<'a>) -> &'n Node<'a> {
    match &node.data {
        YamlData::Tagged(_, inner) => untagged(inner),
        _ => node,
    }
}

/// The value of `key` in a mapping; `None` when `node` is no mapping or lacks the key.
pub(crate) fn get<'n, 'a>(node: &'n Node<'a>, key: &str) -> Option<&'n Node<'a>> {
    untagged(node).data.as_mapping_get(key)
}

/// True when the node is a mapping.
pub(crate) fn is_mapping(node: &Node<'_>) -> bool {
    untagged(node).data.is_mapping()
}

/// The items of a sequence.
pub(crate) fn items<'n, 'a>(node: &'n Node<'a>) -> Option<&'n [Node<'a>]> {
    untagged(node).data.as_vec().map(Vec::as_slice)
}

/// A scalar as text: a string, or a whole number as written (`5` in `version: 5`);
/// `null` (also `~` or nothing at all) is the empty string.
pub(crate) fn text(node: &Node<'_>) -> std::result::Result<String, String> {
    match &untagged(node).data {
        YamlData::Value(Scalar::String(s)) => Ok(s.to_string()),
        YamlData::Value(Scalar::Integer(i)) => Ok(i.to_string()),
        YamlData::Value(Scalar::Null) => Ok(String::new()),
        _ => Err(format!("expected text, got {}", kind(node))),
    }
}

/// A number (an integer or a float, `.inf` and `.nan` included so the caller can refuse
/// them by name). A quoted number is read too, as `map_server`'s own reader (yaml-cpp)
/// reads it.
pub(crate) fn number(node: &Node<'_>) -> std::result::Result<f64, String> {
    match &untagged(node).data {
        YamlData::Value(Scalar::Integer(i)) => Ok(*i as f64),
        YamlData::Value(Scalar::FloatingPoint(f)) => Ok(f.into_inner()),
        YamlData::Value(Scalar::String(s)) => match Scalar::parse_from_cow(s.trim().into()) {
            Scalar::Integer(i) => Ok(i as f64),
            Scalar::FloatingPoint(f) => Ok(f.into_inner()),
            _ => Err(format!("expected a number, got `{s}`")),
        },
        _ => Err(format!("expected a number, got {}", kind(node))),
    }
}

/// A boolean: `true`/`false` in any of YAML's spellings, or `0`/`1` as `map_server`
/// writes `negate`.
pub(crate) fn boolean(node: &Node<'_>) -> std::result::Result<bool, String> {
    match &untagged(node).data {
        YamlData::Value(Scalar::Boolean(b)) => Ok(*b),
        YamlData::Value(Scalar::Integer(0)) => Ok(false),
        YamlData::Value(Scalar::Integer(1)) => Ok(true),
        _ => Err(format!("expected 0 or 1, got {}", kind(node))),
    }
}

/// What a node is, for an error message: the scalar as written, or the collection's kind.
fn kind(node: &Node<'_>) -> String {
    match &untagged(node).data {
        YamlData::Value(Scalar::String(s)) => format!("`{s}`"),
        YamlData::Value(Scalar::Integer(i)) => format!("`{i}`"),
        YamlData::Value(Scalar::FloatingPoint(f)) => format!("`{f}`"),
        YamlData::Value(Scalar::Boolean(b)) => format!("`{b}`"),
        YamlData::Value(Scalar::Null) => "nothing (null)".into(),
        YamlData::Sequence(_) => "a list".into(),
        YamlData::Mapping(_) => "a mapping".into(),
        _ => "an unsupported YAML node".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_flow_and_json_read_the_same() {
        let block = "a:\n  b: [1, 2]\n  c: 'x y'\n  d:\n    - 0.5\n    - ~\n";
        let flow = "{a: {b: [1, 2], c: x y, d: [0.5, null]}}\n";
        let json = r#"{"a": {"b": [1, 2], "c": "x y", "d": [0.5, null]}}"#;
        for doc in [block, flow, json] {
            let root = parse(doc).unwrap();
            let a = get(&root, "a").unwrap();
            assert_eq!(items(get(a, "b").unwrap()).unwrap().iter().map(|n| number(n).unwrap()).sum::<f64>(), 3.0);
            assert_eq!(text(get(a, "c").unwrap()).unwrap(), "x y");
            let d = items(get(a, "d").unwrap()).unwrap();
            assert_eq!((number(&d[0]).unwrap(), text(&d[1]).unwrap()), (0.5, String::new()));
        }
    }

    #[test]
    fn errors_carry_the_line() {
        assert_eq!(parse("a: 1\nb: [\n").unwrap_err().0, 3);
        let (at, message) = parse("a: 1\nb: 2\na: 3\n").unwrap_err();
        assert_eq!(at, 3, "{message}");
        assert!(message.contains("twice"), "{message}");
        assert!(parse("").is_err() && parse("# only a comment\n").is_err());
        let root = parse("\n\nkey: value\n").unwrap();
        assert_eq!(line(get(&root, "key").unwrap()), 3);
    }

    #[test]
    fn an_alias_bomb_is_refused() {
        let mut doc = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n");
        for i in 1..9 {
            let p = i - 1;
            doc += &format!("a{i}: &a{i} [*a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}]\n");
        }
        let (_, message) = parse(&doc).unwrap_err();
        assert!(message.contains("alias"), "{message}");
        // A modest alias is fine.
        let root = parse("base: &b {x: 1}\nother: *b\n").unwrap();
        assert_eq!(number(get(get(&root, "other").unwrap(), "x").unwrap()).unwrap(), 1.0);
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let doc = "[".repeat(100_000);
        assert!(parse(&doc).is_err());
    }

    #[test]
    fn scalars() {
        let root = parse("s: '5'\ni: 5\nf: .inf\nq: \"0.25\"\nb: true\nz: 0\nl: [1]\n").unwrap();
        let at = |k| get(&root, k).unwrap();
        assert_eq!((text(at("s")).unwrap(), text(at("i")).unwrap()), ("5".into(), "5".into()));
        assert_eq!((number(at("f")).unwrap(), number(at("q")).unwrap()), (f64::INFINITY, 0.25));
        assert_eq!((boolean(at("b")), boolean(at("z"))), (Ok(true), Ok(false)));
        assert!(text(at("l")).unwrap_err().contains("a list"));
        assert!(boolean(at("f")).is_err() && number(at("b")).is_err());
    }

    #[test]
    fn files_past_the_budget_or_not_utf8_are_refused() {
        let dir = crate::testdata::temp_dir("yaml-read");
        let big = dir.join("big.yaml");
        std::fs::write(&big, vec![b'#'; MAX_YAML_BYTES as usize + 1]).unwrap();
        let e = read_text(&big).unwrap_err().to_string();
        assert!(e.contains("big.yaml") && e.contains("MiB"), "{e}");
        let latin1 = dir.join("latin1.yaml");
        std::fs::write(&latin1, b"a: 1\nb: caf\xe9\n").unwrap();
        let e = read_text(&latin1).unwrap_err().to_string();
        assert!(e.contains("latin1.yaml") && e.contains(":2") && e.contains("UTF-8"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
