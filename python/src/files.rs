//! The files specchio writes, read back as numpy arrays.

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use specchio::image::exr::Channel;

use crate::errors;

/// Every channel of an OpenEXR file specchio writes (the first layer), by name, as a
/// (H, W) array: float32 for colour, rays and range (`R`, `G`, `B`, `A`; `origin.X`, ...,
/// `direction.Z`, `mask`; `range`), uint32 for ids (`id`), half floats widened to float32.
/// The file is read with the same limits as `specchio compare`'s inputs (16384 px a side).
#[pyfunction]
pub fn read_exr<'py>(
    py: Python<'py>,
    path: crate::args::Given<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let path = path.named("path")?;
    let specchio::image::exr::Layer {
        size: (w, h),
        channels,
    } = py
        .detach(|| specchio::metrics::read_exr_channels(&path))
        .map_err(errors::to_py)?;
    let dict = PyDict::new(py);
    for (name, samples) in channels {
        let array = match samples {
            Channel::F16(v) => {
                let v: Vec<f32> = v.iter().map(|x| x.to_f32()).collect();
                PyArray1::from_vec(py, v).reshape([h, w])?.into_any()
            }
            Channel::F32(v) => PyArray1::from_vec(py, v).reshape([h, w])?.into_any(),
            Channel::U32(v) => PyArray1::from_vec(py, v).reshape([h, w])?.into_any(),
        };
        dict.set_item(name, array)?;
    }
    Ok(dict)
}
