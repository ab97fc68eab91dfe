//! The native half of the `specchio` Python package: the engine's scenes, renderers, exact
//! reference, calibration, dataset writer and localisation descriptors, with images and layers handed to Python as
//! numpy arrays (docs/python.md). The Python half (python/specchio/) adds the Ray driver and
//! re-exports these under their public names.
//!
//! Every engine error arrives as `specchio.SpecchioError` carrying the engine's message (file,
//! line and field for an input), its causes joined by ": " as the command line prints them.
//! Long work (rendering, tracing, fitting) runs with the GIL released, so that other Python
//! threads (a Ray worker's heartbeat, a data loader) go on meanwhile.

mod args;
mod arrays;
mod dataset;
mod errors;
mod experiment;
mod files;
mod localise;
mod poses;
mod reference;
mod renderer;
mod said;
mod scene;
mod shards;
mod watched;

use pyo3::prelude::*;

pub use errors::SpecchioError;

/// The Vulkan devices the engine can use, best first: each a dict of `index`, `name`,
/// `short_name` (what `device=` accepts), `driver_name`, `driver_info`, `usable`, `default`,
/// and its `features` and `limits`.
#[pyfunction]
fn devices(py: Python<'_>) -> PyResult<Vec<Py<PyAny>>> {
    let infos = py.detach(renderer::device_infos).map_err(errors::to_py)?;
    infos.iter().map(|i| errors::json_to_py(py, i)).collect()
}

#[pymodule]
fn _specchio(m: &Bound<'_, PyModule>) -> PyResult<()> {
    said::hold();
    m.add("SpecchioError", m.py().get_type::<SpecchioError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<renderer::Renderer>()?;
    m.add_class::<shards::DatasetFrames>()?;
    m.add_class::<shards::DatasetOutput>()?;
    m.add_class::<localise::Descriptor>()?;
    m.add_class::<localise::Signature>()?;
    m.add_function(wrap_pyfunction!(devices, m)?)?;
    m.add_function(wrap_pyfunction!(poses::read_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(poses::pose_grid, m)?)?;
    m.add_function(wrap_pyfunction!(reference::reference, m)?)?;
    m.add_function(wrap_pyfunction!(reference::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(dataset::dataset, m)?)?;
    m.add_function(wrap_pyfunction!(experiment::localise, m)?)?;
    m.add_function(wrap_pyfunction!(files::read_exr, m)?)?;
    Ok(())
}
