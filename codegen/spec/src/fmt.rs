//! Canonical formatting of spec files (`coforge fmt`), so that diffs stay reviewable.
//!
//! The file is parsed into a tree of YAML nodes and written back with fixed rules:
//! - the top-level sections in the order of [`SECTIONS`] (unknown keys last, as written);
//! - two spaces per level; sequence items indented under their key;
//! - one blank line between top-level keys, none elsewhere;
//! - flow collections (`{ a: 1 }`, `[a, b]`) stay flow, on one line, with single spaces;
//! - plain scalars are kept exactly as written (so `0x1018` stays hex);
//! - quoted scalars are re-quoted in their own style; folded (`>`) text is re-wrapped at
//!   [`WIDTH`] columns, literal (`|`) text is re-indented.
//!
//! Comments, anchors, aliases and tags are refused: a spec carries its text in
//! `description`/`note`, and formatting must never drop anything.

use granit_parser::{Event, Parser, ScalarStyle, StructureStyle};
use std::fmt::Write as _;

/// Folded text is wrapped to this many columns (including indentation) where it can be.
pub const WIDTH: usize = 100;

/// The top-level sections of a spec in canonical order (`spec/README.md`).
pub const SECTIONS: &[&str] = &["format", "device", "node", "hardware", "modes", "objects", "pdo", "emergencies", "serial", "redundant_pairs", "errata"];

#[derive(Debug, Clone, PartialEq)]
enum Node {
    Scalar(String, ScalarStyle),
    Seq(bool, Vec<Node>),
    Map(bool, Vec<(Node, Node)>),
}

/// Formats a spec file canonically. Errors name the line of the offending construct.
pub fn format(text: &str) -> Result<String, String> {
    let mut events = Vec::new();
    for ev in Parser::new_from_str(text) {
        let (ev, span) = ev.map_err(|e| format!("YAML syntax error: {e}"))?;
        let line = span.start.line();
        match &ev {
            Event::Comment(..) => return Err(format!("line {line}: comments are not allowed in spec files; put the text into a `description` or `note`")),
            Event::Alias(_) | Event::Anchor(..) | Event::UnresolvedAlias(_) => {
                return Err(format!("line {line}: anchors and aliases are not allowed in spec files"));
            }
            Event::Scalar(_, _, anchor, tag) | Event::SequenceStart(_, anchor, tag) | Event::MappingStart(_, anchor, tag) if *anchor != 0 || tag.is_some() => {
                return Err(format!("line {line}: anchors and tags are not allowed in spec files"));
            }
            _ => {}
        }
        events.push(ev);
    }
    let mut it = events.into_iter().filter(|e| !matches!(e, Event::StreamStart | Event::StreamEnd | Event::DocumentStart(..) | Event::DocumentEnd));
    let root = match it.next() {
        Some(first) => node(first, &mut it)?,
        None => return Err("the file is empty".into()),
    };
    if it.next().is_some() {
        return Err("a spec file holds exactly one YAML document".into());
    }
    let Node::Map(false, mut entries) = root else { return Err("a spec file is a block mapping at the top level".into()) };
    // A stable sort: keys that are not sections (errors for `coforge check`) keep their order.
    entries.sort_by_key(|(k, _)| match k {
        Node::Scalar(key, ScalarStyle::Plain) => SECTIONS.iter().position(|s| s == key).unwrap_or(SECTIONS.len()),
        _ => SECTIONS.len(),
    });
    let mut out = String::new();
    for (i, (k, v)) in entries.iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        entry(&mut out, k, v, 0);
    }
    Ok(out)
}

fn node<'a>(first: Event<'a>, it: &mut impl Iterator<Item = Event<'a>>) -> Result<Node, String> {
    match first {
        Event::Scalar(v, style, ..) => Ok(Node::Scalar(v.into_owned(), style)),
        Event::SequenceStart(style, ..) => {
            let mut items = Vec::new();
            loop {
                match it.next() {
                    Some(Event::SequenceEnd) => break,
                    Some(ev) => items.push(node(ev, it)?),
                    None => return Err("unterminated sequence".into()),
                }
            }
            Ok(Node::Seq(style == StructureStyle::Flow, items))
        }
        Event::MappingStart(style, ..) => {
            let mut entries = Vec::new();
            loop {
                match it.next() {
                    Some(Event::MappingEnd) => break,
                    Some(ev) => {
                        let key = node(ev, it)?;
                        let value = node(it.next().ok_or("mapping ends after a key")?, it)?;
                        entries.push((key, value));
                    }
                    None => return Err("unterminated mapping".into()),
                }
            }
            Ok(Node::Map(style == StructureStyle::Flow, entries))
        }
        other => Err(format!("unexpected YAML event {other:?}")),
    }
}

fn pad(out: &mut String, indent: usize) {
    out.extend(std::iter::repeat_n(' ', indent));
}

/// `key: value` at `indent`, with the value laid out by its kind.
fn entry(out: &mut String, key: &Node, value: &Node, indent: usize) {
    pad(out, indent);
    out.push_str(&inline(key));
    out.push(':');
    after_marker(out, value, indent);
}

/// Writes a value that follows `key:` or `-` whose line starts at `indent`.
fn after_marker(out: &mut String, value: &Node, indent: usize) {
    match value {
        Node::Scalar(v, style @ (ScalarStyle::Literal | ScalarStyle::Folded)) => block_scalar(out, v, *style, indent + 2),
        Node::Map(false, entries) if !entries.is_empty() => {
            out.push('\n');
            for (k, v) in entries {
                entry(out, k, v, indent + 2);
            }
        }
        Node::Seq(false, items) if !items.is_empty() => {
            out.push('\n');
            for item in items {
                seq_item(out, item, indent + 2);
            }
        }
        other => {
            out.push(' ');
            out.push_str(&inline(other));
            out.push('\n');
        }
    }
}

fn seq_item(out: &mut String, item: &Node, indent: usize) {
    pad(out, indent);
    out.push('-');
    match item {
        Node::Map(false, entries) if !entries.is_empty() => {
            // The first key shares the dash's line; the rest align under it.
            let mut rest = String::new();
            for (k, v) in entries {
                entry(&mut rest, k, v, indent + 2);
            }
            out.push(' ');
            out.push_str(rest.get(indent + 2..).unwrap_or(""));
        }
        other => after_marker(out, other, indent),
    }
}

/// Scalars and flow collections on one line.
fn inline(n: &Node) -> String {
    match n {
        Node::Scalar(v, ScalarStyle::Plain) => v.clone(),
        Node::Scalar(v, ScalarStyle::SingleQuoted) if !v.contains('\n') => format!("'{}'", v.replace('\'', "''")),
        Node::Scalar(v, _) => double_quoted(v),
        Node::Seq(_, items) => format!("[{}]", items.iter().map(inline).collect::<Vec<_>>().join(", ")),
        Node::Map(_, entries) if entries.is_empty() => "{}".into(),
        Node::Map(_, entries) => format!("{{ {} }}", entries.iter().map(|(k, v)| format!("{}: {}", inline(k), inline(v))).collect::<Vec<_>>().join(", ")),
    }
}

fn double_quoted(v: &str) -> String {
    let mut s = String::from("\"");
    for c in v.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\t' => s.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(s, "\\u{:04X}", u32::from(c));
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// `|`/`>` block scalars. Folded text is re-wrapped; anything folding cannot carry exactly
/// (lines that start with blanks, leading newlines) is written in literal style instead.
fn block_scalar(out: &mut String, value: &str, style: ScalarStyle, indent: usize) {
    let body = value.trim_end_matches('\n');
    let trailing = value.len() - body.len();
    let chomp = match trailing {
        0 => "-",
        1 => "",
        _ => "+",
    };
    let foldable = style == ScalarStyle::Folded && !body.starts_with('\n') && !body.split('\n').any(|l| l.starts_with([' ', '\t']) || l.ends_with([' ', '\t']));
    if body.is_empty() {
        out.push_str(" \"\"\n");
        return;
    }
    if foldable {
        let _ = writeln!(out, " >{chomp}");
        // A run of k newlines between paragraphs is written as k blank lines.
        let mut rest = body;
        loop {
            let (para, after) = match rest.find('\n') {
                Some(i) => (&rest[..i], &rest[i..]),
                None => (rest, ""),
            };
            wrap(out, para, indent);
            let newlines = after.len() - after.trim_start_matches('\n').len();
            if newlines == 0 {
                break;
            }
            for _ in 0..newlines {
                out.push('\n');
            }
            rest = &after[newlines..];
        }
    } else {
        let _ = writeln!(out, " |{chomp}");
        for line in body.split('\n') {
            if !line.is_empty() {
                pad(out, indent);
                out.push_str(line);
            }
            out.push('\n');
        }
    }
    for _ in 1..trailing {
        out.push('\n');
    }
}

/// Writes one folded paragraph, breaking only at single spaces (a fold becomes one space).
fn wrap(out: &mut String, para: &str, indent: usize) {
    let mut line = String::new();
    let words: Vec<&str> = para.split(' ').collect();
    let mut i = 0;
    while i < words.len() {
        // Words joined by several spaces (empty words) must stay on one line.
        let mut chunk = words[i].to_string();
        while i + 1 < words.len() && (words[i + 1].is_empty() || chunk.ends_with(' ') || chunk.is_empty()) {
            i += 1;
            chunk.push(' ');
            chunk.push_str(words[i]);
        }
        if !line.is_empty() && indent + line.len() + 1 + chunk.len() > WIDTH {
            pad(out, indent);
            out.push_str(&line);
            out.push('\n');
            line.clear();
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(&chunk);
        i += 1;
    }
    pad(out, indent);
    out.push_str(&line);
    out.push('\n');
}

/// A short report of where `formatted` first differs from `original`, for `fmt --check`.
pub fn first_difference(original: &str, formatted: &str) -> String {
    let line = original.lines().zip(formatted.lines()).position(|(a, b)| a != b).unwrap_or_else(|| original.lines().count().min(formatted.lines().count()));
    let get = |t: &str| t.lines().nth(line).unwrap_or("<end of file>").to_string();
    format!("  first difference at line {}:\n  - {}\n  + {}\n", line + 1, get(original), get(formatted))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_rules() {
        let src = "format: 1\nobjects:\n- index: 0x1000\n  subs:\n      - {sub: 0,   name: 'it''s'}\n  tags: [a,b]\nname:    \"q\\\"x\"\n";
        let want = "format: 1\n\nobjects:\n  - index: 0x1000\n    subs:\n      - { sub: 0, name: 'it''s' }\n    tags: [a, b]\n\nname: \"q\\\"x\"\n";
        assert_eq!(format(src).as_deref(), Ok(want));
        assert_eq!(format(want).as_deref(), Ok(want), "formatting is idempotent");
    }

    #[test]
    fn sections_are_put_in_canonical_order() {
        let src = "format: 1\nobjects: []\nnode:\n  auto_save: true\n  bootup_object: 0x2110\nunknown: 1\ndevice: { name: x }\n";
        let want = "format: 1\n\ndevice: { name: x }\n\nnode:\n  auto_save: true\n  bootup_object: 0x2110\n\nobjects: []\n\nunknown: 1\n";
        assert_eq!(format(src).as_deref(), Ok(want));
        assert_eq!(format(want).as_deref(), Ok(want), "formatting is idempotent");
    }

    #[test]
    fn folded_text_is_rewrapped_without_changing_its_value() {
        let long = "word ".repeat(40).trim_end().to_string();
        let src = format!("d: >\n  {long}\n\n  second paragraph\n");
        let out = format(&src).unwrap_or_default();
        assert!(out.lines().all(|l| l.len() <= WIDTH), "{out}");
        let value = |t: &str| {
            let v: std::collections::BTreeMap<String, String> = serde_saphyr::from_str(t).unwrap_or_default();
            v.get("d").cloned()
        };
        assert_eq!(value(&out), value(&src));
        assert!(value(&src).is_some());
    }

    #[test]
    fn comments_anchors_and_tags_are_refused() {
        for bad in ["a: 1 # c\n", "a: &x 1\nb: *x\n", "a: !!str 1\n", "- 1\n"] {
            assert!(format(bad).is_err(), "{bad}");
        }
    }
}
