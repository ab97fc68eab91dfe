//! Positions of fields in the source text: a dotted field path (`objects[2].size`) is looked
//! up in toml's spanned document tree to find its line and column, and a serde error's byte
//! offset is turned back into the path of the value it falls in.

use std::ops::Range;
use std::path::Path;

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::scene::error::{Location, SceneError};

pub(super) struct Locator<'a> {
    pub(super) file: &'a Path,
    pub(super) text: &'a str,
    pub(super) root: Spanned<DeTable<'a>>,
}

enum Segment<'p> {
    Key(&'p str),
    Index(usize),
}

/// `objects[2].animation.positions[0]` -> Key(objects) Index(2) Key(animation) ...
fn segments(path: &str) -> Vec<Segment<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if !name.is_empty() {
            out.push(Segment::Key(name));
        }
        while let Some(close) = rest.find(']') {
            if let Ok(i) = rest[1..close].parse() {
                out.push(Segment::Index(i));
            }
            rest = &rest[close + 1..];
        }
    }
    out
}

fn contains(span: &Range<usize>, offset: usize) -> bool {
    span.start <= offset && (offset < span.end || span.start == span.end)
}

impl<'a> Locator<'a> {
    /// The span of the value at `path`, or of the deepest part of it that exists (the table
    /// that lacks a missing field). `None` if not even the first key exists.
    pub(super) fn span(&self, path: &str) -> Option<Range<usize>> {
        let mut best: Option<Range<usize>> = None;
        let mut table: Option<&DeTable<'a>> = Some(self.root.get_ref());
        let mut value: Option<&Spanned<DeValue<'a>>> = None;
        for seg in segments(path) {
            let next = match seg {
                Segment::Key(k) => {
                    let t = match value {
                        None => table,
                        Some(v) => v.get_ref().as_table(),
                    };
                    let Some((key, v)) =
                        t.and_then(|t| t.iter().find(|(key, _)| key.get_ref() == k))
                    else {
                        break;
                    };
                    // A `[table]`'s own span is its header; an inline value's is the value.
                    best = Some(if v.get_ref().is_table() && v.span().is_empty() {
                        key.span()
                    } else {
                        v.span()
                    });
                    v
                }
                Segment::Index(i) => {
                    let Some(v) = value
                        .and_then(|v| v.get_ref().as_array())
                        .and_then(|a| a.get(i))
                    else {
                        break;
                    };
                    best = Some(v.span());
                    v
                }
            };
            value = Some(next);
            table = None;
        }
        best
    }

    pub(super) fn location(&self, path: &str) -> Location {
        match self.span(path) {
            Some(span) => Location::at_offset(self.file, self.text, span.start),
            None => Location::file_only(self.file),
        }
    }

    /// The dotted path of the deepest key or value whose span contains `offset`.
    pub(super) fn path_at(&self, offset: usize) -> Option<String> {
        fn in_value(v: &Spanned<DeValue<'_>>, path: String, offset: usize) -> Option<String> {
            match v.get_ref() {
                DeValue::Table(t) => {
                    if let Some(p) = in_table(t, &path, offset) {
                        return Some(p);
                    }
                }
                DeValue::Array(a) => {
                    for (i, e) in a.iter().enumerate() {
                        if let Some(p) = in_value(e, format!("{path}[{i}]"), offset) {
                            return Some(p);
                        }
                    }
                }
                _ => {}
            }
            contains(&v.span(), offset).then_some(path)
        }
        fn in_table(t: &DeTable<'_>, prefix: &str, offset: usize) -> Option<String> {
            for (k, v) in t.iter() {
                let path = if prefix.is_empty() {
                    k.get_ref().to_string()
                } else {
                    format!("{prefix}.{}", k.get_ref())
                };
                if contains(&k.span(), offset) {
                    return Some(path);
                }
                if let Some(p) = in_value(v, path, offset) {
                    return Some(p);
                }
            }
            None
        }
        in_table(self.root.get_ref(), "", offset)
    }

    /// Turns a serde error (unknown field, wrong type, missing field) into a located error.
    pub(super) fn serde_error(&self, e: &toml::de::Error) -> SceneError {
        let message = e.message().trim().to_string();
        let (location, mut field) = match e.span() {
            Some(span) => (
                Location::at_offset(self.file, self.text, span.start),
                self.path_at(span.start).unwrap_or_default(),
            ),
            None => (Location::file_only(self.file), String::new()),
        };
        // serde names the offending key in backticks; make sure the path ends with it.
        let named = |prefix: &str| {
            message
                .strip_prefix(prefix)
                .and_then(|rest| rest.split('`').next())
                .map(str::to_string)
        };
        let key = named("unknown field `").or_else(|| named("missing field `"));
        if let Some(key) = &key {
            if !(field == *key || field.ends_with(&format!(".{key}"))) {
                field = if field.is_empty() {
                    key.clone()
                } else {
                    format!("{field}.{key}")
                };
            }
        }
        if field.is_empty() {
            field = "(top level)".into();
        }
        if message.starts_with("unknown field") {
            SceneError::UnknownField {
                location,
                field,
                message,
            }
        } else if message.starts_with("missing field") {
            SceneError::Invalid {
                location,
                field,
                message: "required field is missing".into(),
            }
        } else {
            SceneError::WrongType {
                location,
                field,
                message: plain_words(&message),
            }
        }
    }
}

/// serde's message in the words a scene is written in: its Rust types (`expected i64`) said
/// as what a user writes, and an integer beyond what any count holds said as out of range
/// (serde reads it as a wider type first: "integer `1e20` as i128").
fn plain_words(message: &str) -> String {
    const WHOLE: &str = "a whole number";
    let words = [
        ("i64", WHOLE),
        ("u64", WHOLE),
        ("i32", WHOLE),
        ("u32", WHOLE),
        ("u16", WHOLE),
        ("u8", WHOLE),
        ("usize", WHOLE),
        ("f64", "a number"),
        ("f32", "a number"),
        ("a boolean", "true or false"),
    ];
    let Some((said, rust)) = message.rsplit_once(", expected ") else {
        return message.to_owned();
    };
    let Some(&(_, plain)) = words.iter().find(|(r, _)| *r == rust) else {
        return message.to_owned();
    };
    let integer = (said.strip_prefix("invalid type: integer `"))
        .or_else(|| said.strip_prefix("invalid value: integer `"))
        .and_then(|rest| rest.split_once('`'))
        .filter(|(_, after)| after.is_empty() || *after == " as i128" || *after == " as u128");
    match integer {
        // What the format reads as i64 (every count): past it, out of range.
        Some((n, _)) if rust == "i64" => {
            format!(
                "{n} is out of range: expected {plain} of at most {}",
                i64::MAX
            )
        }
        _ => format!("{said}, expected {plain}"),
    }
}

#[cfg(test)]
mod tests {
    use super::plain_words;

    /// A Rust type is said as what a scene holds; an integer past any count as out of range;
    /// other messages are kept.
    #[test]
    fn serde_types_are_said_as_a_scene_is_written() {
        let said = |m: &str| plain_words(m);
        assert_eq!(
            said("invalid type: floating point `32.0`, expected i64"),
            "invalid type: floating point `32.0`, expected a whole number"
        );
        assert_eq!(
            said("invalid type: integer `99999999999999999999` as i128, expected i64"),
            "99999999999999999999 is out of range: expected a whole number of at most 9223372036854775807"
        );
        assert_eq!(
            said("invalid value: integer `18446744073709551615`, expected i64"),
            "18446744073709551615 is out of range: expected a whole number of at most 9223372036854775807"
        );
        assert_eq!(
            said("invalid type: string \"x\", expected f64"),
            "invalid type: string \"x\", expected a number"
        );
        let kept = "invalid type: integer `5`, expected a material name for all six walls";
        assert_eq!(said(kept), kept);
    }
}
