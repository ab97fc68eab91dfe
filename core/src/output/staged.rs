//! One staged output, as the transaction and the placing both see it.

use std::path::{Path, PathBuf};

use super::stage::Stage;
use super::OutputError;

#[derive(Debug)]
pub enum Kind {
    File,
    /// A folder, replaceable when it holds this marker file (or is empty).
    Folder {
        marker: String,
    },
}

#[derive(Debug)]
pub struct Staged {
    /// The target as the user spelled it: what writes are addressed to and errors name.
    pub given: PathBuf,
    /// The target the staged output is renamed to (`given`, or its real path for `.`, `..`).
    pub target: PathBuf,
    /// The target's final name: the staged output's name inside `stage`.
    pub name: String,
    /// This run's staging folder for it.
    pub stage: Stage,
    pub kind: Kind,
}

impl Staged {
    /// The staged output: the file or folder that becomes `target`.
    pub fn item(&self) -> PathBuf {
        self.stage.dir().join(&self.name)
    }
}

/// An I/O error, naming the user's `path`.
pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_owned(),
        source,
    }
}
