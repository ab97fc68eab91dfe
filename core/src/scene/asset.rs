//! Why a mesh or texture file could not be loaded.
//!
//! Each variant says where inside the asset the problem is, in the asset's own terms: a line
//! for OBJ, a JSON path such as `accessors[2].count` for glTF. The scene loader wraps these in
//! [`super::SceneError::Asset`], which adds the scene file, line and field that named the asset.

use crate::files::FileError;

#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    /// The asset file itself could not be read (missing, not a regular file, too large).
    #[error(transparent)]
    File(#[from] FileError),

    /// A Wavefront OBJ statement is malformed; `line` is 1-based.
    #[error("line {line}: {message}")]
    Obj { line: usize, message: String },

    /// A glTF value breaks a rule; `at` is its path in the JSON (`accessors[2].count`), or a
    /// part of the container (`GLB header`).
    #[error("{at}: {message}")]
    Gltf { at: String, message: String },

    /// The PNG stream is malformed or breaks a budget.
    #[error("{0}")]
    Png(String),

    /// The mesh as a whole breaks a rule (no triangles, too many, non-finite data).
    #[error("{0}")]
    Mesh(String),

    /// The process was asked to stop while the asset was read (`output::stop_asked`: a
    /// signal, which the command then reports itself).
    #[error("interrupted while reading it")]
    Stopped,
}

impl AssetError {
    /// A glTF error at JSON path `at`.
    pub(crate) fn gltf(at: impl Into<String>, message: impl Into<String>) -> Self {
        AssetError::Gltf {
            at: at.into(),
            message: message.into(),
        }
    }
}
