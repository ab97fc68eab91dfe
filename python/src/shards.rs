//! Datasets from Python in parts, for a pool of workers (specchio/ray.py): `DatasetFrames`
//! renders shards of poses where a worker runs, `DatasetOutput` writes what they return where
//! the driver runs. Both are the engine's `render::dataset`, as `dataset.rs` is, so a pool
//! writes the same bytes as one process and as `specchio dataset`.

use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::PyBytes;
use specchio::render::dataset::{device_key, gpu_failed, robot_scene, FrameWriter, Plan};
use specchio::scene::Lookup;
use specchio::scene::Scene;
use specchio::sensor::dataset::{check_frame, resume, DatasetError, Folder, Frame};
use specchio::sensor::GroundTruth;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::args::{maybe, Given};
use crate::dataset::{commit, parse_lookup, with_kept_note, Choices, PoseSource};
use crate::errors;
use crate::renderer::check_validation;
use crate::said;

/// The most encoders a caller may ask for.
const MAX_ENCODERS: usize = 16;

/// A worker's half of a dataset: a renderer of the plan's robot that renders the frames it
/// is asked for and returns their files (it writes nothing). Every worker of one dataset
/// must give the same `lookup` and `ground_truth`.
#[pyclass(module = "specchio")]
pub struct DatasetFrames {
    plan: Plan,
    /// Behind a lock, always taken with the GIL released (see `Renderer`).
    frames: Mutex<FrameWriter>,
    lookup: String,
    ground_truth: String,
    log: std::sync::Arc<specchio::vk::instance::ValidationLog>,
    _device: std::sync::Arc<specchio::vk::device::Device>,
}

#[pymethods]
impl DatasetFrames {
    /// `encoders`: frames encoded at the same time while the next render (default: a
    /// quarter of the machine's cores, 1 to 4, within the memory budget; 0: none). A Ray
    /// worker, one of many on its machine, passes 1.
    #[new]
    #[pyo3(signature = (scene, trajectory, lookup=None, device=None, validate=Given::Is(false), encoders=None, grid=None, headings=None, time=None, panorama_frame=Given::text("robot"), outputs=None, geometry_frame=Given::text("scene")), text_signature = "(scene, trajectory, lookup=None, device=None, validate=False, encoders=None, grid=None, headings=None, time=None, panorama_frame=\"robot\", outputs=None, geometry_frame=\"scene\")")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scene: Given<PathBuf>,
        trajectory: Option<Given<PathBuf>>,
        lookup: Option<Given<String>>,
        device: Option<Bound<'_, PyAny>>,
        validate: Given<bool>,
        encoders: Option<crate::args::Whole>,
        grid: Option<Given<f64>>,
        headings: Option<crate::args::Whole>,
        time: Option<Given<f64>>,
        panorama_frame: Given<String>,
        outputs: Option<Bound<'_, PyAny>>,
        geometry_frame: Given<String>,
    ) -> PyResult<Self> {
        let (scene, validate) = (scene.named("scene")?, validate.named("validate")?);
        let source = PoseSource::new(trajectory, grid, headings, time)?;
        // The workers render frames; the bag, if any, is the driver's (`DatasetOutput`).
        let frames = (
            panorama_frame.named("panorama_frame")?,
            geometry_frame.named("geometry_frame")?,
        );
        let choices = Choices::parse(&frames.0, &frames.1, outputs.as_ref(), None)?;
        let device = crate::args::device(device.as_ref())?;
        // At most MAX_ENCODERS: each holds a frame in memory.
        let most = MAX_ENCODERS as u32;
        let encoders = (encoders.map(|n| crate::args::count("encoders", n, 0, most)))
            .transpose()?
            .map(|n| n as usize);
        let asked = parse_lookup(maybe("lookup", lookup)?.as_deref())?;
        // No bag here (its format is the driver's): nothing to stop before the frames.
        let stopped = Mutex::new(None);
        said::detach(py, || -> Result<Self, DatasetError> {
            let plan = source.plan(&scene, &choices, &stopped)?;
            let instance =
                Instance::create(&InstanceDesc::from_env(validate)).map_err(gpu_failed)?;
            let log = instance.validation_log();
            let (dev, _, lookup) = specchio::process::probe::device_for_sensor(
                &instance,
                device.as_deref(),
                asked,
                &plan.scene,
            )?;
            let mut frames = FrameWriter::new(&dev, &plan.scene, lookup).map_err(gpu_failed)?;
            frames.set_panoramas(plan.panoramas);
            frames.set_geometry_frame(plan.geometry);
            frames.set_layers(plan.outputs());
            frames.set_path(&plan.poses);
            if let Some(n) = encoders {
                frames.set_encoders(n);
            }
            Ok(DatasetFrames {
                plan,
                lookup: lookup.to_string(),
                ground_truth: frames.ground_truth().name().to_owned(),
                frames: Mutex::new(frames),
                log,
                _device: dev,
            })
        })?
        .map_err(errors::to_py)
    }

    fn __len__(&self) -> usize {
        self.plan.poses.len()
    }

    #[getter]
    fn lookup(&self) -> String {
        self.lookup.clone()
    }

    #[getter]
    fn ground_truth(&self) -> String {
        self.ground_truth.clone()
    }

    /// The device and its driver, as a resumable dataset's key names them: every worker of
    /// a resumable dataset must have the same.
    #[getter]
    fn device(&self) -> String {
        device_key(&self._device.info)
    }

    /// The frames `indices` (into the trajectory's poses): for each, its files as a list of
    /// (path relative to the dataset folder, bytes) and its index line.
    fn frames<'py>(
        &self,
        py: Python<'py>,
        indices: Bound<'py, PyAny>,
    ) -> PyResult<Vec<FrameFiles<'py>>> {
        let indices = crate::args::indices("indices", &indices, self.plan.poses.len())?;
        // Rendered in order, each frame encoded while the next renders; Python's signals
        // (Ctrl-C) are checked between frames.
        let mut stopped: Option<PyErr> = None;
        let rendered = said::detach(py, || -> PyResult<Vec<Frame>> {
            let mut writer = self.writer()?;
            let mut frames = Vec::with_capacity(indices.len());
            let poses = indices.iter().map(|&i| (i, &self.plan.poses[i]));
            let mut between = |i: usize| {
                Python::attach(|py| py.check_signals()).map_err(|e| {
                    stopped = Some(e);
                    DatasetError::Stopped(format!("stopped before frame {i}"))
                })
            };
            let mut take = |frame| {
                frames.push(frame);
                Ok(())
            };
            let done = writer.frames(poses, &mut between, &mut take);
            done.map_err(errors::to_py)?;
            check_validation(&self.log)?;
            Ok(frames)
        })?;
        if let Some(e) = stopped {
            return Err(e);
        }
        let out = rendered?
            .into_iter()
            .map(|frame| {
                let files = (frame.files.into_iter())
                    .map(|(path, bytes)| (path.display().to_string(), PyBytes::new(py, &bytes)))
                    .collect();
                (files, frame.index_line)
            })
            .collect();
        Ok(out)
    }
}

/// One frame for Python: its files (path relative to the dataset folder, bytes) and its
/// index line.
type FrameFiles<'py> = (Vec<(String, Bound<'py, PyBytes>)>, String);

impl DatasetFrames {
    /// The lock: call it with the GIL released.
    fn writer(&self) -> PyResult<MutexGuard<'_, FrameWriter>> {
        self.frames
            .lock()
            .map_err(|_| errors::error("the dataset's renderer failed in another thread"))
    }
}

/// The driver's half of a dataset: the output folder, staged; frames' files placed as they
/// arrive, the index and summary at `finish`, which places the folder. Dropped unfinished,
/// nothing is written (but the frames a resumable one kept in its work folder).
#[pyclass(module = "specchio")]
pub struct DatasetOutput {
    plan: Plan,
    out: PathBuf,
    resume: bool,
    /// The lookup and ground truth `begin` bound the dataset to: nothing is placed before,
    /// every frame placed must have been made by them, and `finish` names them.
    run: Option<(Lookup, GroundTruth)>,
    /// How the folder was given up, once it was: "finished" or "closed".
    ended: &'static str,
    /// The frames placed, kept once `finish` takes the folder (for `note_kept`).
    placed: usize,
    folder: Option<Folder>,
    /// The plan's robot, made once, which proving each frame's index line places.
    robot: Scene,
}

#[pymethods]
impl DatasetOutput {
    #[new]
    #[pyo3(signature = (scene, trajectory, out, resume=Given::Is(false), grid=None, headings=None, time=None, panorama_frame=Given::text("robot"), outputs=None, format=None, geometry_frame=Given::text("scene")), text_signature = "(scene, trajectory, out, resume=False, grid=None, headings=None, time=None, panorama_frame=\"robot\", outputs=None, format=None, geometry_frame=\"scene\")")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scene: Given<PathBuf>,
        trajectory: Option<Given<PathBuf>>,
        out: Given<PathBuf>,
        resume: Given<bool>,
        grid: Option<Given<f64>>,
        headings: Option<crate::args::Whole>,
        time: Option<Given<f64>>,
        panorama_frame: Given<String>,
        outputs: Option<Bound<'_, PyAny>>,
        format: Option<Bound<'_, PyAny>>,
        geometry_frame: Given<String>,
    ) -> PyResult<Self> {
        let (scene, out) = (scene.named("scene")?, out.named("out")?);
        let resume = resume.named("resume")?;
        let source = PoseSource::new(trajectory, grid, headings, time)?;
        let choices = Choices::parse(
            &panorama_frame.named("panorama_frame")?,
            &geometry_frame.named("geometry_frame")?,
            outputs.as_ref(),
            format.as_ref(),
        )?;
        let stopped = Mutex::new(None);
        let output = said::detach(py, || -> Result<Self, DatasetError> {
            specchio::files::identity::forget();
            let plan = source.plan(&scene, &choices, &stopped)?;
            let folder = Folder::stage(&out, plan.poses.len(), plan.frame_files())?;
            Ok(DatasetOutput {
                robot: robot_scene(&plan.scene),
                plan,
                out,
                resume,
                run: None,
                ended: "finished",
                placed: 0,
                folder: Some(folder),
            })
        })?;
        if let Some(e) = crate::watched::raised(stopped) {
            return Err(e);
        }
        let output = output.map_err(errors::to_py)?;
        if let Some(text) = output.plan.omni_missing() {
            crate::dataset::warn(py, text)?;
        }
        Ok(output)
    }

    fn __len__(&self) -> usize {
        self.plan.poses.len()
    }

    /// Binds the dataset to the workers' `lookup`, `ground_truth` and `device` (as
    /// `DatasetFrames` names them); in a resumable run, takes the work folder of an earlier
    /// run with the same inputs, lookup and device. Returns the frames still to render.
    fn begin(
        &mut self,
        py: Python<'_>,
        lookup: &str,
        ground_truth: &str,
        device: &str,
    ) -> PyResult<Vec<usize>> {
        let (lookup, truth) = parse_run(lookup, ground_truth)?;
        if self.run.is_some() {
            return Err(errors::error("the dataset was begun already"));
        }
        let key = self.plan.run_key(lookup, truth, device);
        if self.resume {
            let ended = self.ended_error();
            let (plan, folder) = (&self.plan, self.folder.as_mut());
            let folder = folder.ok_or(ended)?;
            said::detach(py, || folder.resume(&key, &mut plan.index_lines()))?
                .map_err(errors::to_py)?;
        }
        self.run = Some((lookup, truth));
        Ok(self.folder_mut()?.todo())
    }

    /// The work folder of a resumable run (where the finished frames are kept), else None.
    #[getter]
    fn work_folder(&self) -> Option<String> {
        (self.resume).then(|| resume::work_path(&self.out).display().to_string())
    }

    /// Adds to `error` a note of the frames this resumable output kept, if it kept any: what
    /// a driver raises when its run stops.
    fn note_kept(&self, py: Python<'_>, error: Bound<'_, PyAny>) -> PyResult<()> {
        let placed = self.folder.as_ref().map_or(self.placed, Folder::done);
        let e = PyErr::from_value(error);
        let noted = with_kept_note(py, e, &self.out, self.resume, placed);
        drop(noted);
        Ok(())
    }

    /// Places one frame's files (as `DatasetFrames.frames` gives them: every file of one frame
    /// folder `frames/NNNNNN/NAME` of this dataset) and its index line; each frame once.
    fn place(
        &mut self,
        py: Python<'_>,
        files: Bound<'_, PyAny>,
        index_line: crate::args::Given<String>,
    ) -> PyResult<()> {
        let files = crate::args::frame_files("files", &files)?;
        let index_line = index_line.named("index_line")?;
        let run = self.run.ok_or_else(|| {
            errors::error("place() comes after begin(), which names the run's lookup")
        })?;
        let frame = one_frame(&files, self.plan.poses.len())?;
        let frame = Frame {
            frame,
            files: files
                .into_iter()
                .map(|(p, b)| (PathBuf::from(p), b))
                .collect(),
            index_line,
        };
        // A worker's frame is proven this dataset's, once its files are the run's: another
        // plan's is refused, not placed.
        let (plan, robot) = (&self.plan, &mut self.robot);
        check_frame(&frame, &plan.frame_files()).map_err(errors::error)?;
        said::detach(py, || {
            plan.prove(&frame, run, &mut |i| plan.index_line(robot, i))
        })?
        .map_err(errors::to_py)?;
        let folder = self.folder_mut()?;
        said::detach(py, || folder.place(&frame))?.map_err(errors::to_py)
    }

    /// Gives up the output: its staged files are removed now (a resumable run's work folder
    /// keeps its frames). A driver whose run failed calls it, since the exception's traceback
    /// keeps this object, and with it the hidden staging folder, alive until Python collects
    /// it (in a notebook, for as long as the session lasts). Nothing after it but `note_kept`.
    fn close(&mut self) {
        if let Some(folder) = self.folder.take() {
            self.placed = folder.done();
            self.ended = "closed";
        }
    }

    /// Writes the index and the summary of a dataset rendered with `lookup` and
    /// `ground_truth`, and places the folder. Returns the summary as a dict.
    fn finish(&mut self, py: Python<'_>, lookup: &str, ground_truth: &str) -> PyResult<Py<PyAny>> {
        let (lookup, truth) = parse_run(lookup, ground_truth)?;
        self.folder_mut()?;
        match self.run {
            None => return Err(errors::error("finish() comes after begin()")),
            Some(run) if run != (lookup, truth) => {
                return Err(errors::error(format!(
                    "lookup {:?} and ground_truth {:?}: the frames were made with {:?} and \
                     {:?}, as begin() was told",
                    lookup.to_string(),
                    truth.name(),
                    run.0.to_string(),
                    run.1.name()
                )))
            }
            Some(_) => {}
        }
        if let Some(missing) = self.folder_mut()?.todo().first() {
            return Err(errors::error(format!("frame {missing} was never placed")));
        }
        self.placed = self.folder_mut()?.done();
        let folder = self.folder.take().ok_or_else(|| self.ended_error())?;
        let record = self.plan.record(lookup, truth);
        let summary = errors::json_to_py(py, &record)?;
        let ready = py
            .detach(|| folder.finish(&record, self.plan.omni()))
            .map_err(errors::to_py)?;
        commit(py, ready)?;
        Ok(summary)
    }
}

impl DatasetOutput {
    fn folder_mut(&mut self) -> PyResult<&mut Folder> {
        let ended = self.ended_error();
        self.folder.as_mut().ok_or(ended)
    }

    /// What a call after `finish` or `close` raises.
    fn ended_error(&self) -> PyErr {
        errors::error(format!("the dataset was already {}", self.ended))
    }
}

/// A lookup and a ground truth, as the workers name them.
fn parse_run(lookup: &str, ground_truth: &str) -> PyResult<(Lookup, GroundTruth)> {
    let lookup: Lookup = specchio::process::args::lookup(lookup)
        .map_err(|e| errors::error(format!("lookup: {e}")))?;
    let truth: GroundTruth = serde_json::from_value(ground_truth.into())
        .map_err(|_| errors::error(format!("ground_truth: {ground_truth:?} is not one")))?;
    Ok((lookup, truth))
}

/// The frame whose folder holds every one of `files`: each path relative with plain
/// components only (no `..`, no root), `frames/NNNNNN/NAME` of one of the `n` frames, one
/// frame's files together (`Folder::place` checks the names and the index line).
fn one_frame(files: &[(String, Vec<u8>)], n: usize) -> PyResult<usize> {
    let mut frames = files.iter().map(|(path, _)| frame_of(path, n));
    let first = frames
        .next()
        .ok_or_else(|| errors::error("no files: a frame has files"))??;
    for other in frames {
        let other = other?;
        if other != first {
            return Err(errors::error(format!(
                "files of frames {first} and {other} in one call: place one frame at a time"
            )));
        }
    }
    Ok(first)
}

/// The frame of `path`, a file in one of the `n` frame folders.
fn frame_of(path: &str, n: usize) -> PyResult<usize> {
    let p = Path::new(path);
    let parts: Vec<_> = p.components().collect();
    let plain = parts.iter().all(|c| matches!(c, Component::Normal(_)));
    let frame = match parts.as_slice() {
        [Component::Normal(a), Component::Normal(b), Component::Normal(_)] if *a == "frames" => {
            b.to_str().and_then(|b| b.parse::<usize>().ok())
        }
        _ => None,
    };
    let folder = |f: usize| Path::new(&specchio::sensor::dataset::frame_folder(f)).to_owned();
    match frame {
        Some(f) if plain && f < n && p.parent() == Some(folder(f).as_path()) => Ok(f),
        _ => Err(errors::error(format!(
            "{path:?}: not a file of one of this dataset's {n} frame folders (frames/NNNNNN/NAME)"
        ))),
    }
}
