//! Why a dataset could not be made: one error for every part of a run, from reading its inputs
//! to placing its last file.

use std::path::PathBuf;

use crate::memory::MemoryError;
use crate::output::OutputError;
use crate::scene::{Lookup, SceneError};

use super::grid::GridError;
use super::trajectory::TrajectoryError;

/// Why a dataset could not be made. Each names its file (and line and field, where the input
/// has them) or the device.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    #[error("{path}: {source}")]
    Memory { path: PathBuf, source: MemoryError },
    #[error("{path}: {source}")]
    Grid { path: PathBuf, source: GridError },
    #[error("lookup {lookup} cannot run on {device}: {why}")]
    Lookup {
        lookup: Lookup,
        device: String,
        why: String,
    },
    /// The device failed (a `GpuError` of the engine, which converts into this).
    #[error(transparent)]
    Gpu(Box<dyn std::error::Error + Send + Sync>),
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The ROS 2 bag could not be made from the frames.
    #[error(transparent)]
    Bag(#[from] crate::sensor::bag::BagError),
    /// The run was stopped between frames (a signal, Python's KeyboardInterrupt); the text
    /// says how far it got.
    #[error("{0}")]
    Stopped(String),
    /// A frame or an index line that is not what a frame folder holds.
    #[error("{0}")]
    Invalid(String),
    /// A resumable run's work folder cannot be taken: not a folder, not ours, another run's.
    #[error("{path} {why}")]
    Resume { path: PathBuf, why: String },
    #[error("frame {frame}: its sensor layers were not read back (a bug)")]
    NotReadBack { frame: usize },
}
