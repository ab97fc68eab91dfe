//! `specchio.Scene`: a scene file, loaded and checked.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::errors;

/// A scene loaded from its TOML file (docs/scene-format.md). Loading checks everything: a
/// mistake raises `SpecchioError` naming the file, line and field.
#[pyclass(module = "specchio", frozen)]
pub struct Scene {
    pub scene: specchio::scene::Scene,
    pub path: PathBuf,
}

#[pymethods]
impl Scene {
    /// `imaging`, a dict of `[sensor.imaging]`'s keys (`{"exposure_s": 0.004, "gain_db": 6}`;
    /// docs/scene-format.md), replaces the file's camera, checked as the file's would be; `{}`
    /// is the datasheet camera.
    #[new]
    #[pyo3(signature = (path, imaging=None))]
    fn new(
        py: Python<'_>,
        path: crate::args::Given<PathBuf>,
        imaging: Option<crate::args::Given<Bound<'_, pyo3::types::PyDict>>>,
    ) -> PyResult<Self> {
        let path = path.named("path")?;
        let imaging = crate::args::maybe("imaging", imaging)?;
        let mut scene = py
            .detach(|| specchio::scene::load(&path))
            .map_err(errors::to_py)?;
        if let Some(table) = imaging {
            scene.sensor.imaging = Some(camera(&path, &table)?);
        }
        Ok(Scene { scene, path })
    }

    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The sensor camera's image size: (width, height) in pixels.
    #[getter]
    fn sensor_size(&self) -> (u32, u32) {
        let [w, h] = self.scene.sensor.resolution;
        (w, h)
    }

    /// The observer camera's image size: (width, height) in pixels.
    #[getter]
    fn observer_size(&self) -> (u32, u32) {
        let [w, h] = self.scene.observer.resolution;
        (w, h)
    }

    /// The mirror's shape (`sphere`, `hyperboloid`, `paraboloid`, `cone`).
    #[getter]
    fn mirror_shape(&self) -> &'static str {
        self.scene.mirror.shape.kind.name
    }

    /// The mirror's viewpoint at time 0 in the file's coordinates (metres, +Y up).
    #[getter]
    fn mirror_position(&self) -> (f64, f64, f64) {
        let p = self.scene.origin + self.scene.mirror.center.as_dvec3();
        (p.x, p.y, p.z)
    }

    /// The scene frame's origin in the file's coordinates: ray origins and point positions
    /// the renderer returns are relative to it (file = origin + local), as in the files.
    #[getter]
    fn origin(&self) -> (f64, f64, f64) {
        let o = self.scene.origin;
        (o.x, o.y, o.z)
    }

    /// The objects' names, in id order: object `i` has id `6 + i` in the `ids` layer (ids 0
    /// to 5 are the walls +X, -X, +Y, -Y, +Z, -Z).
    #[getter]
    fn objects(&self) -> Vec<String> {
        self.scene.objects.iter().map(|o| o.name.clone()).collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}: {} mirror, {} objects, sensor {}x{})",
            self.path.display().to_string(),
            self.scene.mirror.shape.kind.name,
            self.scene.objects.len(),
            self.scene.sensor.resolution[0],
            self.scene.sensor.resolution[1]
        )
    }
}

/// The imaging chain `table` states (its keys `[sensor.imaging]`'s), checked as a scene
/// file's table is; an error names `imaging` and the key.
fn camera(
    path: &std::path::Path,
    table: &Bound<'_, pyo3::types::PyDict>,
) -> PyResult<specchio::scene::imaging::Imaging> {
    let said = |why: String| errors::error(format!("{}: imaging: {why}", path.display()));
    let mut imaging = toml::Table::new();
    for (key, value) in table.iter() {
        let key: String = (key.extract()).map_err(|_| {
            said(format!(
                "{}: a key must be a str",
                key.repr().map_or("?".into(), |r| r.to_string())
            ))
        })?;
        let value = toml_value(&value).map_err(|why| said(format!("{key}: {why}")))?;
        imaging.insert(key, value);
    }
    let mut sensor = toml::Table::new();
    sensor.insert("imaging".into(), toml::Value::Table(imaging));
    let mut root = toml::Table::new();
    root.insert("sensor".into(), toml::Value::Table(sensor));
    let text = toml::to_string(&root).map_err(|e| said(e.to_string()))?;
    specchio::scene::imaging_str(&text, std::path::Path::new("imaging")).map_err(|e| {
        // The generated text's lines mean nothing to the caller: the key and the message.
        let full = e.to_string();
        match e.field() {
            Some(field) => said(
                full.split_once(&format!("{field}: "))
                    .map_or(full.clone(), |(_, m)| {
                        format!("{}: {m}", field.trim_start_matches("sensor.imaging."))
                    }),
            ),
            None => said(full.trim_start_matches("imaging: ").to_owned()),
        }
    })
}

/// A Python value as the TOML value a scene file would hold: a bool, an int, a finite float,
/// a str, or a list of them; numpy's scalars and arrays as their Python values (`tolist`).
fn toml_value(value: &Bound<'_, PyAny>) -> Result<toml::Value, String> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};
    let shown = || value.repr().map_or("?".to_owned(), |r| r.to_string());
    if value.is_instance_of::<PyBool>() {
        let b = value.extract::<bool>().map_err(|e| e.to_string())?;
        return Ok(toml::Value::Boolean(b));
    }
    if value.is_instance_of::<PyInt>() {
        // Its size, not its digits: 10**300 would print 301 of them.
        let n: i64 = (value.extract()).map_err(|_| {
            let bits = (value
                .call_method0("bit_length")
                .and_then(|b| b.extract::<u64>()))
            .map_or("?".to_owned(), |b| b.to_string());
            format!("an int of {bits} bits is beyond a 64-bit integer")
        })?;
        return Ok(toml::Value::Integer(n));
    }
    if value.is_instance_of::<PyFloat>() {
        let x = value.extract::<f64>().map_err(|e| e.to_string())?;
        return match x.is_finite() {
            true => Ok(toml::Value::Float(x)),
            false => Err(format!("must be a finite number, got {}", shown())),
        };
    }
    if value.is_instance_of::<PyString>() {
        let text = value.extract::<String>().map_err(|e| e.to_string())?;
        return Ok(toml::Value::String(text));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Result<Vec<toml::Value>, String> =
            (value.try_iter().map_err(|e| e.to_string())?)
                .map(|item| toml_value(&item.map_err(|e| e.to_string())?))
                .collect();
        return Ok(toml::Value::Array(items?));
    }
    // numpy's scalars and arrays (and anything else with `tolist`) as Python values: once,
    // so a `tolist` that gives back its own kind is refused, not followed for ever.
    if let Ok(plain) = value.call_method0("tolist") {
        let builtin = plain.is_instance_of::<PyBool>()
            || plain.is_instance_of::<PyInt>()
            || plain.is_instance_of::<PyFloat>()
            || plain.is_instance_of::<PyString>()
            || plain.is_instance_of::<PyList>();
        if builtin {
            return toml_value(&plain);
        }
    }
    Err(format!("{} is not a number, a str or a list", shown()))
}

impl Scene {
    /// `errors::error` with the scene's file named first.
    pub fn error(&self, text: impl std::fmt::Display) -> PyErr {
        errors::error(format!("{}: {text}", self.path.display()))
    }
}
