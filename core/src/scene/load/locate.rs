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
                message,
            }
        }
    }
}
