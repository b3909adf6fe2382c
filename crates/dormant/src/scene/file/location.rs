//! Where things are in a scene file's text: the line of a field path such as
//! `spawners[1].count`, and the file, line, column and field of a TOML syntax error.

use std::ops::Range;
use std::path::Path;

use super::SceneError;

/// The 1-based line where the field at `path` (e.g. `spawners[1].count`) is written, or the
/// deepest part of it that is; `None` when nothing of it is written.
pub(super) fn line_of(source: &str, path: &str) -> Option<usize> {
    let span = locate(source, path)?;
    Some(line_of_offset(source, span.start))
}

/// A [`SceneError::Syntax`] for a TOML error in `source` read from `path`.
pub(super) fn syntax_error(path: &Path, source: &str, e: &toml::de::Error) -> SceneError {
    let (line, column, field) = match e.span() {
        Some(span) => {
            let line = line_of_offset(source, span.start);
            let column = span.start - source[..span.start].rfind('\n').map_or(0, |i| i + 1) + 1;
            (line, column, field_at(source, span))
        }
        None => (1, 1, String::from("(document)")),
    };
    SceneError::Syntax {
        file: path.to_path_buf(),
        line,
        column,
        field,
        message: e.message().trim().to_string(),
    }
}

/// A readable name for what sits at `span`: the enclosing table header plus the key on that
/// line, e.g. `spawners.count`.
fn field_at(source: &str, span: Range<usize>) -> String {
    let start = span.start.min(source.len());
    let line_start = source[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = source[start..].find('\n').map_or(source.len(), |i| start + i);
    let line = source[line_start..line_end].trim();
    let header = source[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim().to_string());
    if line.starts_with('[') {
        return line.trim_matches(|c| c == '[' || c == ']').trim().to_string();
    }
    let key = line.split('=').next().unwrap_or("").trim().trim_matches('"');
    match (header, key.is_empty()) {
        (Some(h), false) => format!("{h}.{key}"),
        (Some(h), true) => h,
        (None, false) => key.to_string(),
        (None, true) => String::from("(document)"),
    }
}

fn line_of_offset(source: &str, offset: usize) -> usize {
    source.as_bytes()[..offset.min(source.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Path segments of `a.b[2].c`.
enum Segment<'a> {
    Key(&'a str),
    Index(usize),
}

fn segments(path: &str) -> Vec<Segment<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if !key.is_empty() {
            out.push(Segment::Key(key));
        }
        for index in rest.split('[').filter(|s| !s.is_empty()) {
            if let Ok(i) = index.trim_end_matches(']').parse() {
                out.push(Segment::Index(i));
            }
        }
    }
    out
}

/// A place in a parsed TOML document while a field path is followed.
#[derive(Clone, Copy)]
enum Node<'a> {
    Item(&'a toml_edit::Item),
    Value(&'a toml_edit::Value),
    Table(&'a toml_edit::Table),
}

/// The byte span of the deepest part of `path` that is written in `source`.
fn locate(source: &str, path: &str) -> Option<Range<usize>> {
    let doc = toml_edit::ImDocument::parse(source).ok()?;
    let mut best = None;
    let mut node = Node::Table(doc.as_table());
    for seg in segments(path) {
        let Some(next) = step(&node, seg, &mut best) else {
            break;
        };
        if let Node::Item(toml_edit::Item::Value(v)) = &next {
            best = v.span().or(best);
        }
        node = next;
    }
    best
}

/// The node `seg` leads to from `node`, with `best` moved to the span of the key or element
/// written for it.
fn step<'a>(node: &Node<'a>, seg: Segment<'_>, best: &mut Option<Range<usize>>) -> Option<Node<'a>> {
    use toml_edit::{Item, TableLike, Value};
    let mut key = |t: &dyn TableLike, k: &str| {
        if let Some(s) = t.get_key_value(k).and_then(|(key, _)| key.span()) {
            *best = Some(s);
        }
    };
    if let Segment::Key(k) = seg {
        return match *node {
            Node::Table(t) | Node::Item(Item::Table(t)) => {
                key(t, k);
                t.get(k).map(Node::Item)
            }
            Node::Item(Item::Value(Value::InlineTable(t))) | Node::Value(Value::InlineTable(t)) => {
                key(t, k);
                t.get(k).map(Node::Value)
            }
            _ => None,
        };
    }
    match (*node, seg) {
        (Node::Item(Item::ArrayOfTables(a)), Segment::Index(i)) => a.get(i).map(|t| {
            *best = t.span().or(best.take());
            Node::Table(t)
        }),
        (Node::Item(Item::Value(Value::Array(a))), Segment::Index(i))
        | (Node::Value(Value::Array(a)), Segment::Index(i)) => a.get(i).map(|v| {
            *best = v.span().or(best.take());
            Node::Value(v)
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_finds_array_of_tables_fields() {
        let src = "[scene]\nname = \"x\"\n\n[[spawners]]\ncount = 1\n\n[[spawners]]\ncount = 0\n";
        let span = locate(src, "spawners[1].count").unwrap();
        assert_eq!(line_of_offset(src, span.start), 8);
        let span = locate(src, "scene.name").unwrap();
        assert_eq!(line_of_offset(src, span.start), 2);
    }

    #[test]
    fn locate_falls_back_to_the_deepest_written_part() {
        let src = "[scene]\nname = \"x\"\n";
        let span = locate(src, "scene.frames").unwrap();
        assert_eq!(line_of_offset(src, span.start), 1);
    }
}
