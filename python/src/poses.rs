//! Poses from Python: the robot's position (the mirror's viewpoint, in the scene file's
//! coordinates) and heading, as a trajectory file gives them (docs/sensor.md, "Datasets").

use std::path::PathBuf;

use glam::DVec3;
use numpy::ndarray::ArrayView2;
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use specchio::sensor::dataset::trajectory::{self, Place, Pose};

use crate::args::Given;
use crate::errors;

/// The poses of a trajectory file (CSV or JSON, docs/sensor.md): a list of dicts with
/// `time` (s), `position` ([x, y, z], m, the file's coordinates) and `heading` (degrees about
/// +Y). A mistake raises `SpecchioError` naming the file, line or entry, and field.
#[pyfunction]
pub fn read_trajectory(py: Python<'_>, path: Given<PathBuf>) -> PyResult<Vec<Py<PyAny>>> {
    let path = path.named("path")?;
    let poses = py
        .detach(|| trajectory::read(&path))
        .map_err(errors::to_py)?;
    poses
        .iter()
        .map(|p| {
            let d = pyo3::types::PyDict::new(py);
            d.set_item("time", p.time_s)?;
            d.set_item("position", p.position.to_array().to_vec())?;
            d.set_item("heading", p.heading_deg)?;
            Ok(d.into_any().unbind())
        })
        .collect()
}

/// The pose grid of `specchio dataset --grid`: the robot at every place of a square grid of
/// `spacing` metres over the floor where it fits (at the mirror's height in the file), each
/// turned to `headings` evenly spaced headings from 0 degrees, at `time`. A (B, 4) float64
/// array of x, y, z, heading rows (the scene file's coordinates, degrees), in grid order: what
/// `Renderer.render_batch` takes, or a trajectory's rows (`time,x,y,z,heading` with the time).
#[pyfunction]
#[pyo3(signature = (scene, spacing, headings=crate::args::Whole::Fits(1), time=crate::args::Given::Is(0.0)), text_signature = "(scene, spacing, headings=1, time=0.0)")]
pub fn pose_grid<'py>(
    py: Python<'py>,
    scene: Given<PyRef<'py, crate::scene::Scene>>,
    spacing: Given<f64>,
    headings: crate::args::Whole,
    time: Given<f64>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let (scene, spacing) = (scene.named("scene")?, spacing.named("spacing")?);
    let (scene, time) = (&*scene, time.named("time")?);
    let headings = crate::args::count(
        "headings",
        headings,
        1,
        specchio::sensor::dataset::grid::MAX_HEADINGS,
    )?;
    let poses = specchio::sensor::dataset::grid::grid(&scene.scene, spacing, headings, time)
        .map_err(|e| {
            scene.error(errors::python_words(
                &e.to_string(),
                &[("--grid", "spacing")],
            ))
        })?;
    let rows: Vec<f64> = poses
        .iter()
        .flat_map(|p| [p.position.x, p.position.y, p.position.z, p.heading_deg])
        .collect();
    numpy::PyArray1::from_vec(py, rows).reshape([poses.len(), 4])
}

/// How a message names the pose a call was given: `pose` and `time` of one frame (`render`,
/// `reference`), or `poses[i]` and `times` (`times[i]` when there is one a pose) of a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Naming {
    One,
    Batch,
}

impl Naming {
    /// What a message calls pose `i`.
    pub fn pose(self, i: usize) -> String {
        match self {
            Naming::One => "pose".to_owned(),
            Naming::Batch => format!("poses[{i}]"),
        }
    }
}

/// The pose `x, y, z, heading` at `time`, named as one frame's.
pub fn one(pose: [f64; 4], time: f64) -> PyResult<Pose> {
    let array = numpy::ndarray::arr2(&[pose]);
    Ok(from_array(array.view(), Some(vec![time]), Naming::One)?.remove(0))
}

/// The poses of a (B, 4) array of `x, y, z, heading` rows at `times` (one per row, or one
/// for all), named in errors as `naming` says.
pub fn from_array(
    rows: ArrayView2<'_, f64>,
    times: Option<Vec<f64>>,
    naming: Naming,
) -> PyResult<Vec<Pose>> {
    if rows.ncols() != 4 {
        return Err(errors::error(format!(
            "poses: {} columns; each row is x, y, z, heading (4)",
            rows.ncols()
        )));
    }
    let n = rows.nrows();
    // One time for every pose is named `times`, one a pose `times[i]`.
    let one_time = naming == Naming::One || times.as_ref().is_some_and(|t| t.len() == 1);
    let times = match times {
        None => vec![0.0; n],
        Some(t) if t.len() == 1 => vec![t[0]; n],
        Some(t) if t.len() == n => t,
        Some(t) => {
            return Err(errors::error(format!(
                "times: {} values for {n} poses; give one per pose or one for all",
                t.len()
            )))
        }
    };
    let mut out = Vec::with_capacity(n);
    for (i, (row, &time_s)) in rows.outer_iter().zip(&times).enumerate() {
        let at = naming.pose(i);
        let named = |field: &str, why: &str| errors::error(format!("{at}: {field}: {why}"));
        if !row.iter().take(3).all(|v| v.is_finite()) {
            return Err(named("position", "every value must be a finite number"));
        }
        if !specchio::scene::is_heading(row[3]) {
            return Err(named("heading", specchio::scene::HEADING_RULE));
        }
        if !specchio::scene::is_scene_time(time_s) {
            let time = match (naming, one_time) {
                (Naming::One, _) => "time".to_owned(),
                (Naming::Batch, true) => "times".to_owned(),
                (Naming::Batch, false) => format!("times[{i}]"),
            };
            let why = specchio::scene::SCENE_TIME_RULE;
            return Err(errors::error(format!("{time}: {why}")));
        }
        out.push(Pose {
            at: Place::Entry(i),
            time_s,
            position: DVec3::new(row[0], row[1], row[2]),
            heading_deg: row[3].rem_euclid(360.0),
        });
    }
    Ok(out)
}
