//! `specchio.Renderer`: the robot's sensor on a Vulkan device, rendered at poses.

use std::sync::{Arc, Mutex, MutexGuard};

use pyo3::prelude::*;
use pyo3::types::PyDict;
use specchio::render::dataset::FrameWriter;
use specchio::scene::Lookup;
use specchio::sensor::dataset::trajectory::{Place, Pose};
use specchio::sensor::dataset::{self, ObjectBounds};
use specchio::vk::device::{self, Device, DeviceInfo};
use specchio::vk::instance::{Instance, InstanceDesc, ValidationLog};

use crate::args::{maybe, Given};
use crate::arrays::{self, Layers};
use crate::errors;
use crate::poses::{self, Naming};
use crate::said;
use crate::scene::Scene;

/// Every device the engine sees (usable or not, with why not).
pub fn device_infos() -> Result<Vec<serde_json::Value>, specchio::vk::GpuError> {
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let default = device::choose(&instance, None).ok().map(|d| d.index);
    let candidates = device::enumerate(&instance)?;
    Ok(candidates
        .into_iter()
        .map(|c| {
            let mut v = serde_json::to_value(&c.info).unwrap_or_default();
            v["usable"] = serde_json::Value::Bool(c.rejected.is_none());
            v["default"] = serde_json::Value::Bool(default == Some(c.info.index));
            v["rejected_because"] = c.rejected.map_or(serde_json::Value::Null, Into::into);
            v
        })
        .collect())
}

/// A device opened for `lookup` (or the dataset's default lookup for `scene`): the device,
/// its description, the lookup chosen and the validation log.
pub fn open(
    scene: &specchio::scene::Scene,
    lookup: Option<&str>,
    selector: Option<&str>,
    validate: bool,
) -> PyResult<(Arc<Device>, DeviceInfo, Lookup, Arc<ValidationLog>)> {
    let lookup: Option<Lookup> = lookup
        .map(|l| {
            specchio::process::args::lookup(l).map_err(|e| errors::error(format!("lookup: {e}")))
        })
        .transpose()?;
    let instance = Instance::create(&InstanceDesc::from_env(validate)).map_err(errors::to_py)?;
    let log = instance.validation_log();
    let (device, chosen, lookup) =
        specchio::process::probe::device_for_sensor(&instance, selector, lookup, scene)
            .map_err(errors::to_py)?;
    Ok((device, chosen, lookup, log))
}

/// Raises the validation layer's first message, if it said anything.
pub fn check_validation(log: &ValidationLog) -> PyResult<()> {
    specchio::process::validation::verdict(&log.messages()).map_err(errors::to_py)
}

/// The robot's sensor: a renderer of `scene` whose mirror stands at each pose it is given.
///
/// `lookup`: the mirror lookup of the colour image (`plain`, `box`, `distance`, `ray-query`,
/// `distance-exact`, `bvh`); by default one that traces, so that colour, range and ids follow
/// one light path: bvh on CPU drivers, ray-query on a GPU that has ray queries, bvh on any
/// other. `device`: an index or part of a name (see
/// `specchio.devices()`). `validate`: the Khronos validation layer on; any message raises.
#[pyclass(module = "specchio")]
pub struct Renderer {
    /// None once closed. Behind a lock, always taken with the GIL released (a thread that
    /// waited for it holding the GIL would keep the thread that holds it from ever returning).
    inner: Mutex<Option<Inner>>,
    /// What never changes, read without the lock.
    scene: specchio::scene::Scene,
    objects: ObjectBounds,
    device_name: String,
    lookup: String,
    ground_truth: String,
}

struct Inner {
    frames: FrameWriter,
    log: Arc<ValidationLog>,
    next_frame: usize,
    // Last: the device outlives the renderer made on it.
    _device: Arc<Device>,
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (scene, lookup=None, device=None, validate=Given::Is(false)), text_signature = "(scene, lookup=None, device=None, validate=False)")]
    fn new(
        py: Python<'_>,
        scene: Given<PyRef<'_, Scene>>,
        lookup: Option<Given<String>>,
        device: Option<Bound<'_, PyAny>>,
        validate: Given<bool>,
    ) -> PyResult<Self> {
        let (scene, validate) = (scene.named("scene")?, validate.named("validate")?);
        let lookup = maybe("lookup", lookup)?;
        let lookup = lookup.as_deref();
        let device = crate::args::device(device.as_ref())?;
        let path = scene.path.clone();
        let scene = scene.scene.clone();
        // No cube counted yet: the default lookup is a traced one, which makes none; the frame
        // writer counts it once the lookup is chosen.
        specchio::memory::estimates::render(&scene, 0, false, true)
            .map_err(|e| errors::error(format!("{}: {}", path.display(), errors::message(&e))))?;
        let (inner, device_name) = said::detach(py, || -> PyResult<(Inner, String)> {
            let (dev, info, lookup, log) = open(&scene, lookup, device.as_deref(), validate)?;
            let frames = FrameWriter::new(&dev, &scene, lookup).map_err(errors::to_py)?;
            check_validation(&log)?;
            let inner = Inner {
                frames,
                log,
                next_frame: 0,
                _device: dev,
            };
            Ok((inner, info.name))
        })??;
        Ok(Renderer {
            lookup: inner.frames.lookup().to_string(),
            ground_truth: inner.frames.ground_truth().name().to_owned(),
            inner: Mutex::new(Some(inner)),
            objects: ObjectBounds::of(&scene),
            scene,
            device_name,
        })
    }

    /// The device it renders on.
    #[getter]
    fn device(&self) -> String {
        self.device_name.clone()
    }

    /// The colour image's mirror lookup.
    #[getter]
    fn lookup(&self) -> String {
        self.lookup.clone()
    }

    /// Where range and ids come from: `traced` (exact, the colour's light path), or `cube`
    /// (the cube path's search; see docs/sensor.md "Ground truth").
    #[getter]
    fn ground_truth(&self) -> String {
        self.ground_truth.clone()
    }

    /// One frame at `pose` (x, y, z, heading: the mirror's viewpoint in the scene file's
    /// coordinates, metres, and the heading in degrees about +Y; default: the mirror where the
    /// scene puts it at `time`, heading 0) and `time` (s): a dict of numpy arrays (see the
    /// module's docs: `sensor`, `observer`, `ray_origin`, `ray_direction`, `mask`, `range`,
    /// `ids`, `classes`, and `camera` where the scene has `[sensor.imaging]`).
    #[pyo3(signature = (pose=None, time=Given::Is(0.0)), text_signature = "($self, pose=None, time=0.0)")]
    fn render<'py>(
        &self,
        py: Python<'py>,
        pose: Option<Bound<'py, PyAny>>,
        time: Given<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let time = time.named("time")?;
        let pose = pose.map(|p| crate::args::pose(py, &p)).transpose()?;
        let pose = match pose {
            Some(pose) => poses::one(pose, time)?,
            None => self.scene_pose(time)?,
        };
        let layers = said::detach(py, || self.layers(&pose, Naming::One))??;
        arrays::frame_dict(py, layers)
    }

    /// A batch of frames: `poses` a (B, 4) array of x, y, z, heading rows (as `render`), at
    /// `times` (one per pose, or one for all). A dict of (B, H, W, C) arrays; with `out` (a
    /// dict of arrays of those shapes and dtypes, e.g. the last call's result), the frames
    /// are written into its arrays instead of new ones.
    #[pyo3(signature = (poses, times=None, out=None))]
    fn render_batch<'py>(
        &self,
        py: Python<'py>,
        poses: Bound<'py, PyAny>,
        times: Option<Given<Vec<f64>>>,
        out: Option<Given<Bound<'py, PyDict>>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (times, out) = (maybe("times", times)?, maybe("out", out)?);
        let poses = crate::args::poses(py, &poses)?;
        let poses = poses::from_array(poses.as_array(), times, Naming::Batch)?;
        let Some(first) = poses.first() else {
            return Err(errors::error(
                "poses: an empty batch (give at least one pose)",
            ));
        };
        // Every pose checked before the first is rendered.
        for pose in &poses {
            self.check(pose, Naming::Batch)?;
        }
        let layers = said::detach(py, || self.layers(first, Naming::Batch))??;
        let batch = arrays::batch_dict(py, poses.len(), &layers, out.as_ref())?;
        arrays::fill(&batch, 0, layers)?;
        for (b, pose) in poses.iter().enumerate().skip(1) {
            // Ctrl-C between frames.
            py.check_signals()?;
            let layers = said::detach(py, || self.layers(pose, Naming::Batch))??;
            arrays::fill(&batch, b, layers)?;
        }
        Ok(batch)
    }

    /// Releases the device now (also done when the renderer is garbage-collected).
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        said::detach(py, || {
            *self.lock()? = None;
            Ok(())
        })?
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        py: Python<'_>,
        _kind: Option<Bound<'_, PyAny>>,
        _value: Option<Bound<'_, PyAny>>,
        _traceback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }
}

impl Renderer {
    /// The lock: call it with the GIL released.
    fn lock(&self) -> PyResult<MutexGuard<'_, Option<Inner>>> {
        self.inner.lock().map_err(|_| {
            errors::error("a render of this renderer failed unexpectedly; make a new renderer")
        })
    }

    /// The scene's own mirror at `time`, heading 0.
    fn scene_pose(&self, time: f64) -> PyResult<Pose> {
        if !specchio::scene::is_scene_time(time) {
            let rule = specchio::scene::SCENE_TIME_RULE;
            return Err(errors::error(format!("time: {rule}")));
        }
        let state = specchio::scene::state::SceneState::at(&self.scene, time);
        Ok(Pose {
            at: Place::Entry(0),
            time_s: time,
            position: self.scene.origin + state.mirror_center.as_dvec3(),
            heading_deg: 0.0,
        })
    }

    /// Whether the robot can stand at `pose`, as a dataset's poses are checked.
    fn check(&self, pose: &Pose, naming: Naming) -> PyResult<()> {
        dataset::pose_fits(&self.scene, &self.objects, pose).map_err(|(field, why)| {
            let at = match pose.at {
                Place::Entry(i) => naming.pose(i),
                Place::Line(n) => format!("line {n}"),
            };
            errors::error(format!("{at}: {field}: {why}"))
        })
    }

    /// The layers of the next frame, at `pose` (checked first). Called with the GIL released.
    fn layers(&self, pose: &Pose, naming: Naming) -> PyResult<Layers> {
        self.check(pose, naming)?;
        let mut guard = self.lock()?;
        let inner = guard
            .as_mut()
            .ok_or_else(|| errors::error("the renderer was closed"))?;
        let frame = inner.next_frame;
        inner.next_frame += 1;
        let (outputs, observer) = inner.frames.outputs(frame, pose).map_err(errors::to_py)?;
        check_validation(&inner.log)?;
        Ok(Layers::new(outputs, &observer))
    }
}
