//! TEMPORARY stub.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct SceneError {
    pub message: String,
}
