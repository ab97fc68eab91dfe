//! Datasets from Python: in one process (`dataset`), or in parts for a pool of workers
//! (`DatasetFrames` renders shards of poses where a worker runs, `DatasetOutput` writes what
//! they return where the driver runs: specchio/ray.py). Both are the engine's
//! `render::dataset`, so both write the same bytes as `specchio dataset`.

use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::PyBytes;
use specchio::output::Transaction;
use specchio::render::dataset::{self as writer, DatasetError, Frame, FrameWriter, Plan};
use specchio::scene::Lookup;
use specchio::sensor::GroundTruth;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::errors;
use crate::renderer::check_validation;

fn parse_lookup(lookup: Option<&str>) -> PyResult<Option<Lookup>> {
    lookup
        .map(|l| {
            specchio::process::args::lookup(l).map_err(|e| errors::error(format!("lookup: {e}")))
        })
        .transpose()
}

fn name_of<T: serde::Serialize>(value: T) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

/// Renders the dataset of `scene` along `trajectory` into the folder `out` in this process
/// (what `specchio dataset` does), all or nothing: every pose is checked before anything is
/// rendered, and the folder appears only when every frame is written. Ctrl-C between frames
/// stops it with nothing written. `progress(done, total)` is called after each frame. Returns
/// the summary (`dataset.json`) as a dict.
#[pyfunction]
#[pyo3(signature = (scene, trajectory, out, lookup=None, device=None, validate=false, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn dataset(
    py: Python<'_>,
    scene: PathBuf,
    trajectory: PathBuf,
    out: PathBuf,
    lookup: Option<&str>,
    device: Option<&str>,
    validate: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    let asked = parse_lookup(lookup)?;
    let mut stopped: Option<PyErr> = None;
    let result = py.detach(|| -> Result<_, DatasetError> {
        let plan = Plan::read(&scene, &trajectory)?;
        let mut staged = Transaction::new();
        staged.folder(&out, writer::SUMMARY_FILE)?;
        let instance = Instance::create(&InstanceDesc::from_env(validate))?;
        let log = instance.validation_log();
        let (dev, _, lookup) =
            specchio::process::probe::device_for_sensor(&instance, device, asked, &plan.scene)?;
        drop(instance);
        let mut frames = FrameWriter::new(&dev, &plan.scene, lookup)?;
        let truth = frames.ground_truth();
        let n = plan.poses.len();
        let index = writer::write_frames(&staged, &out, &plan, &mut frames, &mut |i| {
            // Between frames: Python's signals (Ctrl-C) and the caller's progress.
            Python::attach(|py| {
                let called = match (&progress, i) {
                    (Some(f), i) if i > 0 => f.call1(py, (i, n)).map(drop),
                    _ => Ok(()),
                };
                called.and_then(|()| py.check_signals())
            })
            .map_err(|e| {
                stopped = Some(e);
                DatasetError::Stopped(format!(
                    "stopped after {i} of {n} frames: nothing was written"
                ))
            })
        })?;
        drop(frames);
        drop(dev);
        let record = plan.record(lookup, truth);
        writer::finish(&staged, &out, &index, &record)?;
        Ok((staged, record, log))
    });
    if let Some(e) = stopped {
        return Err(e);
    }
    let (staged, record, log) = result.map_err(errors::to_py)?;
    check_validation(&log)?;
    py.detach(|| staged.commit()).map_err(errors::to_py)?;
    if let Some(f) = &progress {
        f.call1(py, (record.frames, record.frames))?;
    }
    errors::json_to_py(py, &record)
}

/// A worker's half of a dataset: a renderer of the plan's robot that renders the frames it
/// is asked for and returns their files (it writes nothing). Every worker of one dataset
/// must give the same `lookup` and `ground_truth`.
#[pyclass(module = "specchio")]
pub struct DatasetFrames {
    plan: Plan,
    /// Behind a lock: Python objects may be shared between threads.
    frames: Mutex<FrameWriter>,
    log: std::sync::Arc<specchio::vk::instance::ValidationLog>,
    _device: std::sync::Arc<specchio::vk::device::Device>,
}

#[pymethods]
impl DatasetFrames {
    #[new]
    #[pyo3(signature = (scene, trajectory, lookup=None, device=None, validate=false))]
    fn new(
        py: Python<'_>,
        scene: PathBuf,
        trajectory: PathBuf,
        lookup: Option<&str>,
        device: Option<&str>,
        validate: bool,
    ) -> PyResult<Self> {
        let asked = parse_lookup(lookup)?;
        py.detach(|| -> Result<Self, DatasetError> {
            let plan = Plan::read(&scene, &trajectory)?;
            let instance = Instance::create(&InstanceDesc::from_env(validate))?;
            let log = instance.validation_log();
            let (dev, _, lookup) =
                specchio::process::probe::device_for_sensor(&instance, device, asked, &plan.scene)?;
            let frames = FrameWriter::new(&dev, &plan.scene, lookup)?;
            Ok(DatasetFrames {
                plan,
                frames: Mutex::new(frames),
                log,
                _device: dev,
            })
        })
        .map_err(errors::to_py)
    }

    fn __len__(&self) -> usize {
        self.plan.poses.len()
    }

    #[getter]
    fn lookup(&self) -> PyResult<String> {
        Ok(self.writer()?.lookup().to_string())
    }

    #[getter]
    fn ground_truth(&self) -> PyResult<String> {
        Ok(name_of(self.writer()?.ground_truth()))
    }

    /// The frames `indices` (into the trajectory's poses): for each, its files as a list of
    /// (path relative to the dataset folder, bytes) and its index line.
    fn frames<'py>(&self, py: Python<'py>, indices: Vec<usize>) -> PyResult<Vec<FrameFiles<'py>>> {
        let n = self.plan.poses.len();
        if let Some(bad) = indices.iter().find(|&&i| i >= n) {
            return Err(errors::error(format!(
                "frame {bad}: the trajectory has {n} poses"
            )));
        }
        let mut out = Vec::with_capacity(indices.len());
        for i in indices {
            let plan = &self.plan;
            let mut writer = self.writer()?;
            let frames = &mut *writer;
            let frame: Frame = py
                .detach(|| frames.frame(i, &plan.poses[i]))
                .map_err(errors::to_py)?;
            check_validation(&self.log)?;
            let files = frame
                .files
                .into_iter()
                .map(|(path, bytes)| (path.display().to_string(), PyBytes::new(py, &bytes)))
                .collect();
            out.push((files, frame.index_line));
        }
        Ok(out)
    }
}

/// One frame for Python: its files (path relative to the dataset folder, bytes) and its
/// index line.
type FrameFiles<'py> = (Vec<(String, Bound<'py, PyBytes>)>, String);

impl DatasetFrames {
    fn writer(&self) -> PyResult<MutexGuard<'_, FrameWriter>> {
        self.frames
            .lock()
            .map_err(|_| errors::error("the dataset's renderer failed in another thread"))
    }
}

/// The driver's half of a dataset: the output folder, staged; frames' files placed as they
/// arrive, the index and summary at `finish`, which places the folder. Dropped unfinished,
/// nothing is written.
#[pyclass(module = "specchio")]
pub struct DatasetOutput {
    plan: Plan,
    out: PathBuf,
    staged: Option<Transaction>,
}

#[pymethods]
impl DatasetOutput {
    #[new]
    fn new(py: Python<'_>, scene: PathBuf, trajectory: PathBuf, out: PathBuf) -> PyResult<Self> {
        py.detach(|| -> Result<Self, DatasetError> {
            let plan = Plan::read(&scene, &trajectory)?;
            let mut staged = Transaction::new();
            staged.folder(&out, writer::SUMMARY_FILE)?;
            Ok(DatasetOutput {
                plan,
                out,
                staged: Some(staged),
            })
        })
        .map_err(errors::to_py)
    }

    fn __len__(&self) -> usize {
        self.plan.poses.len()
    }

    /// Places one frame's files (as `DatasetFrames.frames` gives them): each path must lie
    /// in a frame folder (`frames/NNNNNN/...`) of this dataset.
    fn place(&self, py: Python<'_>, files: Vec<(String, Vec<u8>)>) -> PyResult<()> {
        let staged = self.staged()?;
        for (path, _) in &files {
            frame_file_path(path, self.plan.poses.len())?;
        }
        let frame = Frame {
            files: files
                .into_iter()
                .map(|(p, b)| (PathBuf::from(p), b))
                .collect(),
            index_line: String::new(),
        };
        py.detach(|| writer::place_frame(staged, &self.out, &frame))
            .map_err(errors::to_py)
    }

    /// Writes the index (`index_lines`, one per frame, in frame order) and the summary of a
    /// dataset rendered with `lookup` and `ground_truth`, and places the folder. Returns the
    /// summary as a dict.
    fn finish(
        &mut self,
        py: Python<'_>,
        index_lines: Vec<String>,
        lookup: &str,
        ground_truth: &str,
    ) -> PyResult<Py<PyAny>> {
        let n = self.plan.poses.len();
        if index_lines.len() != n {
            return Err(errors::error(format!(
                "{} index lines for {n} frames",
                index_lines.len()
            )));
        }
        let lookup: Lookup = specchio::process::args::lookup(lookup)
            .map_err(|e| errors::error(format!("lookup: {e}")))?;
        let truth: GroundTruth = serde_json::from_value(ground_truth.into())
            .map_err(|_| errors::error(format!("ground_truth: {ground_truth:?} is not one")))?;
        let staged = self
            .staged
            .take()
            .ok_or_else(|| errors::error("the dataset was already finished"))?;
        let record = self.plan.record(lookup, truth);
        py.detach(|| -> Result<(), specchio::output::OutputError> {
            writer::finish(&staged, &self.out, &index_lines, &record)?;
            staged.commit()
        })
        .map_err(errors::to_py)?;
        errors::json_to_py(py, &record)
    }
}

impl DatasetOutput {
    fn staged(&self) -> PyResult<&Transaction> {
        self.staged
            .as_ref()
            .ok_or_else(|| errors::error("the dataset was already finished"))
    }
}

/// Checks that `path` names a file in the folder of one of the `n` frames: relative, plain
/// components only (no `..`, no root), `frames/NNNNNN/NAME`.
fn frame_file_path(path: &str, n: usize) -> PyResult<()> {
    let p = Path::new(path);
    let parts: Vec<_> = p.components().collect();
    let plain = parts.iter().all(|c| matches!(c, Component::Normal(_)));
    let frame = match parts.as_slice() {
        [Component::Normal(a), Component::Normal(b), Component::Normal(_)] if *a == "frames" => {
            b.to_str().and_then(|b| b.parse::<usize>().ok())
        }
        _ => None,
    };
    match frame {
        Some(f) if plain && f < n && writer_folder_matches(p, f) => Ok(()),
        _ => Err(errors::error(format!(
            "{path:?}: not a file of one of this dataset's {n} frame folders (frames/NNNNNN/NAME)"
        ))),
    }
}

fn writer_folder_matches(p: &Path, frame: usize) -> bool {
    p.parent() == Some(Path::new(&specchio::sensor::dataset::frame_folder(frame)))
}
