//! The one error type of scene loading.
//!
//! Every error names the scene file; every error that comes from a value in the file also names
//! the 1-based line and column of that value and its dotted field path, so that the message
//! `scenes/x.toml:12:5: mirror.radius: must be positive, got -1` can be pasted into an editor's
//! "go to" box and points at the culprit.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a scene file an error was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The scene file (as given to [`super::load`]).
    pub file: PathBuf,
    /// 1-based line, when the error can be tied to a place in the file.
    pub line: Option<u32>,
    /// 1-based column (in characters), when `line` is known.
    pub column: Option<u32>,
}

impl Location {
    /// A location that names only the file (e.g. "the file is empty").
    pub fn file_only(file: &Path) -> Self {
        Self {
            file: file.to_path_buf(),
            line: None,
            column: None,
        }
    }

    /// The location of byte offset `offset` in `text`.
    pub fn at_offset(file: &Path, text: &str, offset: usize) -> Self {
        let (line, column) = line_column(text, offset);
        // Saturate rather than wrap on absurdly long files.
        let clamp = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        Self {
            file: file.to_path_buf(),
            line: Some(clamp(line)),
            column: Some(clamp(column)),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        Ok(())
    }
}

/// 1-based (line, column) of byte `offset` in `text`; offsets past the end land on the last line.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    // Never split a UTF-8 sequence: step back to a character boundary.
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file itself could not be read (missing, unreadable). The reason is the
    /// `source` error, not part of this message: error reporters that print the chain
    /// (anyhow's `{:#}`) would print it twice.
    #[error("{}: cannot read scene file", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// The file is not UTF-8 text; `location` is the first byte that is not.
    #[error("{location}: {message}")]
    Encoding { location: Location, message: String },

    /// The file has no tables or keys at all (empty, or only comments).
    #[error("{}: scene is empty: expected at least [room] and [mirror]", file.display())]
    Empty { file: PathBuf },

    /// The file is not valid TOML.
    #[error("{location}: TOML syntax error: {message}")]
    Syntax { location: Location, message: String },

    /// A key the format does not know (often a typo); `field` is the path of the unknown key.
    #[error("{location}: {field}: {message}")]
    UnknownField {
        location: Location,
        field: String,
        message: String,
    },

    /// A value of the wrong TOML type or shape (a string where a number belongs, an array of the
    /// wrong length, an unknown enum word).
    #[error("{location}: {field}: {message}")]
    WrongType {
        location: Location,
        field: String,
        message: String,
    },

    /// A value of the right type that breaks a rule (range, finiteness, reference, geometry),
    /// or a required field that is missing.
    #[error("{location}: {field}: {message}")]
    Invalid {
        location: Location,
        field: String,
        message: String,
    },

    /// Something outside the file made loading it fail: an environment variable the loader
    /// reads (`SPECCHIO_MEMORY_BUDGET`), named rather than blamed on a field of the file.
    #[error("{}: {message}", file.display())]
    Environment { file: PathBuf, message: String },

    /// A mesh or texture file that a field refers to could not be loaded. `location` is the line
    /// of the referring field in the scene file.
    #[error("{location}: {field}: cannot load {}: {message}", asset.display())]
    Asset {
        location: Location,
        field: String,
        asset: PathBuf,
        message: String,
    },
}

impl SceneError {
    /// The scene file the error is about.
    pub fn file(&self) -> &Path {
        match self {
            SceneError::Io { file, .. }
            | SceneError::Empty { file }
            | SceneError::Environment { file, .. } => file,
            SceneError::Encoding { location, .. }
            | SceneError::Syntax { location, .. }
            | SceneError::UnknownField { location, .. }
            | SceneError::WrongType { location, .. }
            | SceneError::Invalid { location, .. }
            | SceneError::Asset { location, .. } => &location.file,
        }
    }

    /// The 1-based line of the offending value, when known.
    pub fn line(&self) -> Option<u32> {
        self.location().and_then(|l| l.line)
    }

    /// The 1-based column of the offending value, when known.
    pub fn column(&self) -> Option<u32> {
        self.location().and_then(|l| l.column)
    }

    /// The dotted field path (`objects[2].size`), when the error is about a field.
    pub fn field(&self) -> Option<&str> {
        match self {
            SceneError::Io { .. }
            | SceneError::Empty { .. }
            | SceneError::Environment { .. }
            | SceneError::Encoding { .. }
            | SceneError::Syntax { .. } => None,
            SceneError::UnknownField { field, .. }
            | SceneError::WrongType { field, .. }
            | SceneError::Invalid { field, .. }
            | SceneError::Asset { field, .. } => Some(field),
        }
    }

    fn location(&self) -> Option<&Location> {
        match self {
            SceneError::Io { .. } | SceneError::Empty { .. } | SceneError::Environment { .. } => {
                None
            }
            SceneError::Encoding { location, .. }
            | SceneError::Syntax { location, .. }
            | SceneError::UnknownField { location, .. }
            | SceneError::WrongType { location, .. }
            | SceneError::Invalid { location, .. }
            | SceneError::Asset { location, .. } => Some(location),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_is_one_based_and_counts_characters() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        // 'é' is two bytes but one column.
        assert_eq!(line_column(text, 9), (2, 3));
        assert_eq!(line_column(text, 1000), (3, 1));
    }

    #[test]
    fn display_has_file_line_column_field_message() {
        let e = SceneError::Invalid {
            location: Location {
                file: PathBuf::from("scenes/x.toml"),
                line: Some(12),
                column: Some(5),
            },
            field: "mirror.radius".into(),
            message: "must be positive, got -1".into(),
        };
        assert_eq!(
            e.to_string(),
            "scenes/x.toml:12:5: mirror.radius: must be positive, got -1"
        );
    }
}
