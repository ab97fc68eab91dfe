//! The exact CPU reference and the calibration, from Python.

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use specchio::output::Transaction;
use specchio::process::progress;
use specchio::process::traced::{self, StoppedAt};
use specchio::render::dataset as writer;
use specchio::sensor::central::{folder, Calibration, Watch};
use specchio::sensor::dataset;
use specchio::sensor::SensorOutputs;

use crate::args::Given;
use crate::arrays::{self, Layers};
use crate::errors;
use crate::said;
use crate::scene::Scene;
use crate::watched::{self, Watched};

/// The exact reference of the sensor and observer views (CPU ray tracing, no GPU): the same
/// dict of arrays as `Renderer.render`, every layer exact. `pose` (x, y, z, heading) stands
/// the robot there as `Renderer.render` does; without it the scene is traced as written at
/// `time`. `spp`: samples per pixel of the colour images (1 traces pixel centres). A long
/// trace says its estimate on stderr as the command does; Ctrl-C stops it within a pixel
/// (`KeyboardInterrupt`).
#[pyfunction]
#[pyo3(signature = (scene, pose=None, time=Given::Is(0.0), spp=crate::args::Whole::Fits(1)), text_signature = "(scene, pose=None, time=0.0, spp=1)")]
pub fn reference<'py>(
    py: Python<'py>,
    scene: Given<PyRef<'py, Scene>>,
    pose: Option<Bound<'py, PyAny>>,
    time: Given<f64>,
    spp: crate::args::Whole,
) -> PyResult<Bound<'py, PyDict>> {
    let (scene, time) = (scene.named("scene")?, time.named("time")?);
    let scene = &*scene;
    let pose = pose.map(|p| crate::args::pose(py, &p)).transpose()?;
    let spp = crate::args::count("spp", spp, 1, specchio::reference::MAX_SPP)?;
    if !specchio::scene::is_scene_time(time) {
        let rule = specchio::scene::SCENE_TIME_RULE;
        return Err(errors::error(format!("time: {rule}")));
    }
    let instants = specchio::sensor::imaging::exposure_renders(&scene.scene);
    if let Some(why) = specchio::reference::too_many_paths(&scene.scene, spp, instants) {
        return Err(scene.error(why));
    }
    specchio::memory::estimates::reference(&scene.scene, true)
        .map_err(|e| scene.error(errors::message(&e)))?;
    let traced = match pose {
        None => scene.scene.clone(),
        Some(pose) => {
            let pose = crate::poses::one(pose, time)?;
            let objects = dataset::ObjectBounds::of(&scene.scene);
            dataset::pose_fits(&scene.scene, &objects, &pose)
                .map_err(|(field, why)| errors::error(format!("pose: {field}: {why}")))?;
            let mut robot = writer::robot_scene(&scene.scene);
            writer::place_robot(&mut robot, &scene.scene, &pose);
            robot
        }
    };
    let stopped = Mutex::new(None);
    let layers = said::unsaid(py, || {
        watched::polled(&stopped, |stop| {
            let run = traced::trace((&traced, time, spp), true, "reference", stop)?;
            let mut outputs = SensorOutputs::from_reference(&traced, time, &run.sensor.0);
            outputs.expose(&traced, 0, run.light.as_ref());
            Ok::<_, StoppedAt>(Layers::new(outputs, &run.observer.0.color))
        })
    });
    // The Ctrl-C first, its warnings unraised beside it: Python has already taken the signal,
    // so a warning raised in its place would lose it.
    if let Some(e) = watched::raised(stopped) {
        if let Err(StoppedAt(at)) = &layers {
            watched::note(py, &e, &format!("specchio.reference stopped {at}"));
        }
        said::say_unraised(py);
        return Err(e);
    }
    let layers = match layers {
        Ok(layers) => layers,
        Err(StoppedAt(at)) => {
            said::say_unraised(py);
            return Err(errors::error(format!("stopped {at}")));
        }
    };
    said::say(py)?;
    arrays::frame_dict(py, layers)
}

/// Fits the central models robotics tools calibrate (OpenCV omnidir, Kalibr omni, OCamCalib)
/// to the sensor's exact ray map at `time` and writes their exports into the folder `out`
/// (as `specchio calibrate`, docs/sensor-models.md), all or nothing. Returns the summary
/// (`calibration.json`) as a dict. A large sensor says its estimate on stderr as the command
/// does; Ctrl-C stops it between parts (`KeyboardInterrupt`), with nothing written.
#[pyfunction]
#[pyo3(signature = (scene, out, time=Given::Is(0.0)), text_signature = "(scene, out, time=0.0)")]
pub fn calibrate<'py>(
    py: Python<'py>,
    scene: Given<PyRef<'py, Scene>>,
    out: Given<PathBuf>,
    time: Given<f64>,
) -> PyResult<Py<PyAny>> {
    let (scene, out) = (scene.named("scene")?, out.named("out")?);
    let (scene, time) = (&*scene, time.named("time")?);
    if !specchio::scene::is_scene_time(time) {
        let rule = specchio::scene::SCENE_TIME_RULE;
        return Err(errors::error(format!("time: {rule}")));
    }
    if let Some(why) = Calibration::too_large(&scene.scene) {
        return Err(scene.error(why));
    }
    specchio::memory::estimates::calibrate(&scene.scene)
        .map_err(|e| scene.error(errors::message(&e)))?;
    let stopped = Mutex::new(None);
    let watch = Watched {
        progress: progress::calibration("calibrate", scene.scene.sensor.resolution, true),
        stopped: &stopped,
    };
    let record = said::unsaid(py, || -> Result<_, String> {
        // What this call may not replace is what it reads (docs/python.md).
        specchio::files::identity::forget();
        let mut staged = Transaction::new();
        staged
            .folder(&out, folder::RECORD)
            .map_err(|e| errors::message(&e))?;
        let (cal, map) =
            Calibration::of_scene_watched(&scene.scene, time, &watch).map_err(|e| {
                format!(
                    "{}: cannot fit the central models: {}",
                    scene.path.display(),
                    errors::message(&e)
                )
            })?;
        let topic = specchio::sensor::bag::kalibr_image_topic(scene.scene.sensor.imaging.is_some());
        let record = folder::write(&staged, &out, (&cal, &map), (&scene.path, topic), time)
            .map_err(|e| errors::message(&e))?;
        if watch.stop() {
            return Err("stopped before placing the output: nothing was written".into());
        }
        staged.commit().map_err(|e| errors::message(&e))?;
        Ok(record)
    });
    // Placed, or nothing was: said, never raised.
    said::say_unraised(py);
    if let Some(e) = watched::raised(stopped) {
        return Err(e);
    }
    let record = record.map_err(errors::error)?;
    errors::json_to_py(py, &record)
}
