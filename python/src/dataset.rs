//! Datasets from Python in one process (`dataset`); in parts for a pool of workers, see
//! `shards.rs`. Both are the engine's `render::dataset`, so both write the same bytes as
//! `specchio dataset`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use pyo3::prelude::*;
use specchio::process::progress;
use specchio::render::dataset::{self as writer, gpu_failed, FrameWriter, Plan, Poses};
use specchio::scene::Lookup;
use specchio::sensor::dataset::DatasetRecord;
use specchio::sensor::dataset::{resume, DatasetError, Folder, Format, GeometryFrame, Ready};
use specchio::sensor::layers::Layers;
use specchio::sensor::panorama::PanoramaFrame;
use specchio::vk::device::Device;
use specchio::vk::instance::{Instance, InstanceDesc, ValidationLog};

use crate::args::{maybe, Given};
use crate::errors;
use crate::renderer::check_validation;
use crate::said;
use crate::watched::Watched;

/// Where a dataset's poses come from, as Python names them: a trajectory file, or a grid
/// (`specchio dataset --grid SPACING --headings N --time T`).
pub enum PoseSource {
    File(PathBuf),
    Grid {
        spacing_m: f64,
        headings: u32,
        time_s: f64,
    },
}

impl PoseSource {
    /// Exactly one of `trajectory` and `grid`; `headings` and `time` only with a grid.
    pub fn new(
        trajectory: Option<Given<PathBuf>>,
        grid: Option<Given<f64>>,
        headings: Option<crate::args::Whole>,
        time: Option<Given<f64>>,
    ) -> PyResult<Self> {
        let (trajectory, grid) = (maybe("trajectory", trajectory)?, maybe("grid", grid)?);
        let time = maybe("time", time)?;
        let headings = (headings.map(|h| {
            crate::args::count(
                "headings",
                h,
                1,
                specchio::sensor::dataset::grid::MAX_HEADINGS,
            )
        }))
        .transpose()?;
        match (trajectory, grid) {
            (Some(_), Some(_)) => Err(errors::error(
                "trajectory and grid: give one of them, not both",
            )),
            (None, None) => Err(errors::error(
                "give the poses: a trajectory file, or grid=SPACING (metres)",
            )),
            (Some(_), None) if headings.is_some() || time.is_some() => Err(errors::error(
                "headings and time are a grid's (grid=SPACING); a trajectory has its own",
            )),
            (Some(path), None) => Ok(PoseSource::File(path)),
            (None, Some(spacing_m)) => Ok(PoseSource::Grid {
                spacing_m,
                headings: headings.unwrap_or(1),
                time_s: time.unwrap_or(0.0),
            }),
        }
    }

    /// The plan of a dataset of `scene` from these poses; a bag's unified model fitted here
    /// stops at Ctrl-C, what Python raised kept in `stopped`.
    pub(crate) fn plan(
        &self,
        scene: &Path,
        choices: &Choices,
        stopped: &Mutex<Option<PyErr>>,
    ) -> Result<Plan, DatasetError> {
        let poses = match self {
            PoseSource::File(path) => Poses::Trajectory(path),
            &PoseSource::Grid {
                spacing_m,
                headings,
                time_s,
            } => Poses::Grid {
                spacing_m,
                headings,
                time_s,
            },
        };
        let mut plan = Plan::new(scene, poses)?;
        plan.panoramas = choices.panoramas;
        plan.geometry = choices.geometry;
        if let Some(chosen) = choices.outputs {
            plan.choose(chosen)?;
        }
        let resolution = plan.scene.sensor.resolution;
        let bag_model = Watched {
            progress: progress::calibration("dataset: the bag's unified model", resolution, false),
            stopped,
        };
        plan.set_format(choices.format, &bag_model)?;
        plan.frames_apply()?;
        Ok(plan)
    }
}

/// What a dataset's caller chose beside its poses (`dataset`'s arguments of those names).
pub(crate) struct Choices {
    pub panoramas: PanoramaFrame,
    pub geometry: GeometryFrame,
    pub outputs: Option<Layers>,
    pub format: Format,
}

impl Choices {
    /// Python's `panorama_frame`, `geometry_frame`, `outputs` and `format`, checked.
    pub(crate) fn parse(
        panorama_frame: &str,
        geometry_frame: &str,
        outputs: Option<&Bound<'_, PyAny>>,
        format: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        Ok(Choices {
            panoramas: parse_panorama_frame(panorama_frame)?,
            geometry: (geometry_frame.parse())
                .map_err(|e| errors::error(format!("geometry_frame: {e}")))?,
            outputs: parse_outputs(outputs)?,
            format: format.map(parse_format).transpose()?.unwrap_or_default(),
        })
    }
}

/// The panoramas' frame as Python names it: `"robot"` or `"world"`.
pub(crate) fn parse_panorama_frame(frame: &str) -> PyResult<PanoramaFrame> {
    frame
        .parse()
        .map_err(|e| errors::error(format!("panorama_frame: {e}")))
}

/// The layers as Python names them: `"all"`, `"image,range"` or `["image", "range"]`;
/// None (every layer the scene has) when not given.
pub(crate) fn parse_outputs(outputs: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Layers>> {
    let Some(given) = outputs else {
        return Ok(None);
    };
    let text = crate::args::names_text("outputs", given, "\"image,range\"")?;
    text.parse()
        .map(Some)
        .map_err(|e| errors::error(format!("outputs: {e}")))
}

/// The dataset's form as Python names it: `"files"`, `"mcap"` or `"files,mcap"`, or a list.
pub(crate) fn parse_format(format: &Bound<'_, PyAny>) -> PyResult<Format> {
    let text = crate::args::names_text("format", format, "\"files,mcap\"")?;
    text.parse()
        .map_err(|e| errors::error(format!("format: {e}")))
}

pub(crate) fn parse_lookup(lookup: Option<&str>) -> PyResult<Option<Lookup>> {
    lookup
        .map(|l| {
            specchio::process::args::lookup(l).map_err(|e| errors::error(format!("lookup: {e}")))
        })
        .transpose()
}

/// Renders the dataset of `scene` along `trajectory` into the folder `out` in this process
/// (what `specchio dataset` does), all or nothing: every pose is checked before anything is
/// rendered, and the folder appears only when every frame is written. Ctrl-C between frames
/// stops it with nothing written. `progress(done, total)` is called after each frame. With
/// `resume`, finished frames are kept in `out.partial` and a stopped run goes on from them
/// (`specchio dataset --resume`). Returns the summary (`dataset.json`) as a dict.
#[pyfunction]
#[pyo3(signature = (scene, trajectory, out, lookup=None, device=None, validate=Given::Is(false), progress=None, resume=Given::Is(false), grid=None, headings=None, time=None, panorama_frame=Given::text("robot"), outputs=None, format=None, geometry_frame=Given::text("scene")), text_signature = "(scene, trajectory, out, lookup=None, device=None, validate=False, progress=None, resume=False, grid=None, headings=None, time=None, panorama_frame=\"robot\", outputs=None, format=None, geometry_frame=\"scene\")")]
#[allow(clippy::too_many_arguments)]
pub fn dataset(
    py: Python<'_>,
    scene: Given<PathBuf>,
    trajectory: Option<Given<PathBuf>>,
    out: Given<PathBuf>,
    lookup: Option<Given<String>>,
    device: Option<Bound<'_, PyAny>>,
    validate: Given<bool>,
    progress: Option<Py<PyAny>>,
    resume: Given<bool>,
    grid: Option<Given<f64>>,
    headings: Option<crate::args::Whole>,
    time: Option<Given<f64>>,
    panorama_frame: Given<String>,
    outputs: Option<Bound<'_, PyAny>>,
    format: Option<Bound<'_, PyAny>>,
    geometry_frame: Given<String>,
) -> PyResult<Py<PyAny>> {
    let (scene, out) = (scene.named("scene")?, out.named("out")?);
    let resume = resume.named("resume")?;
    let device = crate::args::device(device.as_ref())?;
    let job = Job {
        choices: Choices::parse(
            &panorama_frame.named("panorama_frame")?,
            &geometry_frame.named("geometry_frame")?,
            outputs.as_ref(),
            format.as_ref(),
        )?,
        asked: parse_lookup(maybe("lookup", lookup)?.as_deref())?,
        source: PoseSource::new(trajectory, grid, headings, time)?,
        scene: &scene,
        out: &out,
        device: device.as_deref(),
        validate: validate.named("validate")?,
        resume,
        progress: progress.as_ref(),
    };
    let stopped: Mutex<Option<PyErr>> = Mutex::new(None);
    // The frames placed when the run stopped (a resumable run keeps them).
    let placed = AtomicUsize::new(0);
    let result = said::unsaid(py, || render(&job, &stopped, &placed));
    let placed = placed.load(Ordering::Relaxed);
    place_finished(py, result, stopped, job.progress)
        .map_err(|e| with_kept_note(py, e, &out, resume, placed))
}

/// What `dataset` renders: its arguments, checked.
struct Job<'a> {
    choices: Choices,
    asked: Option<Lookup>,
    source: PoseSource,
    scene: &'a Path,
    out: &'a Path,
    device: Option<&'a str>,
    validate: bool,
    resume: bool,
    progress: Option<&'a Py<PyAny>>,
}

/// A dataset rendered, not placed yet: the folder ready to place, its summary, and the
/// validation log.
type Finished = (Ready, DatasetRecord, Arc<ValidationLog>, Option<String>);

/// Renders `job`'s frames into its staged folder (with the GIL released), keeping the error
/// from Python that stopped it in `stopped` and the frames placed in `placed`.
fn render(
    job: &Job,
    stopped: &Mutex<Option<PyErr>>,
    placed: &AtomicUsize,
) -> Result<Finished, DatasetError> {
    // What this call may not replace is what it reads (docs/python.md).
    specchio::files::identity::forget();
    let plan = (job.source).plan(job.scene, &job.choices, stopped)?;
    let n = plan.poses.len();
    let mut folder = Folder::stage(job.out, n, plan.frame_files())?;
    let (log, dev, lookup) = open_device(job, &plan)?;
    let mut frames = FrameWriter::new(&dev, &plan.scene, lookup).map_err(gpu_failed)?;
    frames.set_panoramas(plan.panoramas);
    frames.set_geometry_frame(plan.geometry);
    frames.set_layers(plan.outputs());
    frames.set_path(&plan.poses);
    let truth = frames.ground_truth();
    if job.resume {
        let key = plan.run_key(lookup, truth, &writer::device_key(&dev.info));
        folder.resume(&key, &mut plan.index_lines())?;
    }
    // Without a callback of the caller's, the estimate the command says, on stderr.
    let todo = (n - folder.done()) as u64;
    let what = || format!("dataset {}", job.out.display());
    let hooks = Hooks {
        stopped,
        progress: job.progress,
        estimate: job
            .progress
            .is_none()
            .then(|| progress::Progress::new(what(), todo, "frames")),
        n,
        nothing: if job.resume {
            ""
        } else {
            ": nothing was written"
        },
    };
    let wrote = writer::write_frames(
        &mut folder,
        &plan,
        &mut frames,
        &mut |i| hooks.between(i),
        &mut |done| hooks.written(done),
    );
    placed.store(folder.done(), Ordering::Relaxed);
    wrote?;
    drop(frames);
    drop(dev);
    let record = plan.record(lookup, truth);
    let ready = folder.finish(&record, plan.omni())?;
    Ok((ready, record, log, plan.omni_missing()))
}

/// The validation log, the device `job` asks for that can render `plan`'s scene, and the
/// lookup it runs (the instance is let go once the device is made).
fn open_device(
    job: &Job,
    plan: &Plan,
) -> Result<(Arc<ValidationLog>, Arc<Device>, Lookup), DatasetError> {
    let instance = Instance::create(&InstanceDesc::from_env(job.validate)).map_err(gpu_failed)?;
    let log = instance.validation_log();
    let (dev, _, lookup) =
        specchio::process::probe::device_for_sensor(&instance, job.device, job.asked, &plan.scene)?;
    drop(instance);
    Ok((log, dev, lookup))
}

/// Before each frame, Python's signals (Ctrl-C); after each frame written but the last
/// (which the caller hears of once the folder is placed), the caller's progress, or without
/// one the estimate on stderr. What Python raised is kept in `stopped`.
struct Hooks<'a> {
    stopped: &'a Mutex<Option<PyErr>>,
    progress: Option<&'a Py<PyAny>>,
    /// Where the caller gave no `progress`: the run's estimate, said on stderr past its first
    /// 1.5 s as `specchio dataset` says it (a long run was silent).
    estimate: Option<progress::Progress>,
    /// The frames in all.
    n: usize,
    /// The end of a stop's message: `": nothing was written"` unless the run is resumable.
    nothing: &'static str,
}

impl Hooks<'_> {
    /// Keeps `e`, the error Python raised, for the caller.
    fn keep(&self, e: PyErr) {
        *self.stopped.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
    }

    /// Before frame `i`: stops on Python's signals (Ctrl-C).
    fn between(&self, i: usize) -> Result<(), DatasetError> {
        let (n, nothing) = (self.n, self.nothing);
        Python::attach(|py| py.check_signals()).map_err(|e| {
            self.keep(e);
            DatasetError::Stopped(format!("stopped before frame {i} of {n}{nothing}"))
        })
    }

    /// After `done` frames: the caller's progress, but after the last.
    fn written(&self, done: usize) -> Result<(), DatasetError> {
        let (n, nothing) = (self.n, self.nothing);
        self.estimate.as_ref().inspect(|e| e.add(1));
        match (self.progress, done < n) {
            (Some(f), true) => Python::attach(|py| f.call1(py, (done, n)).map(drop)).map_err(|e| {
                self.keep(e);
                DatasetError::Stopped(format!("stopped after {done} of {n} frames{nothing}"))
            }),
            _ => Ok(()),
        }
    }
}

/// Places the rendered dataset (with the GIL held) and returns its summary as a dict; the
/// error Python raised, if one stopped the run, comes first.
fn place_finished(
    py: Python<'_>,
    result: Result<Finished, DatasetError>,
    stopped: Mutex<Option<PyErr>>,
    progress: Option<&Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    // The run's own error first: its warnings then said, never raised in its stead.
    let stopped = stopped.into_inner().unwrap_or_else(|p| p.into_inner());
    let result = match (stopped, result) {
        (Some(e), _) => Err(e),
        (None, result) => result.map_err(errors::to_py),
    };
    if result.is_err() {
        said::say_unraised(py);
    }
    let (ready, record, log, omni_missing) = result?;
    check_validation(&log).inspect_err(|_| said::say_unraised(py))?;
    // Said before the folder is placed, so that warnings made errors place nothing.
    said::say(py)?;
    if let Some(text) = omni_missing {
        warn(py, text)?;
    }
    // Everything that can fail runs before the folder is placed: nothing after it.
    if let Some(f) = progress {
        f.call1(py, (record.frames, record.frames))?;
    }
    py.check_signals()?;
    let summary = errors::json_to_py(py, &record)?;
    commit(py, ready)?;
    Ok(summary)
}

/// `e`, with a note of the frames a resumable run kept and how to go on (where it kept any:
/// none when the output was placed, or was never begun).
pub(crate) fn with_kept_note(
    py: Python<'_>,
    e: PyErr,
    out: &Path,
    resume: bool,
    placed: usize,
) -> PyErr {
    let work = resume::work_path(out);
    if resume && placed > 0 && work.join(resume::JOURNAL).exists() {
        let note = format!(
            "{placed} frame(s) are kept in {}: the same call with resume=True goes on from there",
            work.display()
        );
        // Python 3.11 and later show notes under the message; earlier ones have none.
        let _ = e.value(py).call_method1("add_note", (note,));
    }
    e
}

/// Places a finished dataset; what of its work folder could not be removed is a warning.
pub(crate) fn commit(py: Python<'_>, ready: Ready) -> PyResult<()> {
    let placed = said::unsaid(py, || ready.commit());
    said::say_unraised(py);
    let left = placed.map_err(errors::to_py)?;
    if !left.is_empty() {
        let text = format!(
            "the work folder is not removed entirely: {}",
            left.join("; ")
        );
        warn(py, text)?;
    }
    Ok(())
}

/// A `UserWarning` with `text` (an error where the caller's warning filters say so).
pub(crate) fn warn(py: Python<'_>, text: String) -> PyResult<()> {
    let warning = py.get_type::<pyo3::exceptions::PyUserWarning>();
    PyErr::warn(
        py,
        &warning,
        // A NUL would end the C string early; said as the escape it is.
        &std::ffi::CString::new(text.replace('\0', "\\0")).unwrap_or_default(),
        1,
    )
}
