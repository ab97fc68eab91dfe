//! A frame's images and layers as numpy arrays: one frame as (H, W, C) arrays, a batch as
//! (B, H, W, C), written into the caller's arrays where `out=` gives them.
//!
//! | key | shape | dtype | what |
//! |---|---|---|---|
//! | `sensor` | (H, W, 3) | float32 | the sensor camera's linear RGB |
//! | `observer` | (Ho, Wo, 3) | float32 | the observer camera's linear RGB |
//! | `ray_origin` | (H, W, 3) | float32 | where each pixel's ray leaves the mirror (scene frame, m) |
//! | `ray_direction` | (H, W, 3) | float32 | its unit direction (0 off the mirror) |
//! | `mask` | (H, W) | bool | the pixel sees the mirror |
//! | `range` | (H, W) | float32 | metres along the ray to what it meets (0 off the mirror) |
//! | `ids` | (H, W) | uint32 | what it meets: walls 0..5, object i at 6 + i, 2³² − 1 none |
//! | `classes` | (H, W) | uint32 | the class of what it meets (`sensor.id.json`'s `classes`), 2³² − 1 none |
//! | `camera` | (H, W, 3) | uint16 | only where the scene has `[sensor.imaging]`: the camera's codes (0..2^bit_depth), noise and all |
//! | NAME | (H, W, 4) | float32 | each ray-map quantity beyond the two the rows above decode (`specchio::sensor::quantities`): a plug-in reaches Python with no line here |

use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use specchio::image::RgbaImage;
use specchio::sensor::SensorOutputs;

use crate::errors;

/// One layer's samples, row-major, channels last.
pub enum Data {
    F32(Vec<f32>),
    U32(Vec<u32>),
    U16(Vec<u16>),
    Bool(Vec<bool>),
}

impl Data {
    fn dtype(&self) -> &'static str {
        match self {
            Data::F32(_) => "float32",
            Data::U32(_) => "uint32",
            Data::U16(_) => "uint16",
            Data::Bool(_) => "bool",
        }
    }

    fn sample_bytes(&self) -> usize {
        match self {
            Data::F32(_) | Data::U32(_) => 4,
            Data::U16(_) => 2,
            Data::Bool(_) => 1,
        }
    }
}

/// One frame's layers: (key, samples, (height, width, channels); channels 0 for a plane).
pub struct Layers(pub Vec<(&'static str, Data, [usize; 3])>);

fn rgb(image: &RgbaImage) -> Vec<f32> {
    image
        .pixels
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

impl Layers {
    pub fn new(o: SensorOutputs, observer: &RgbaImage) -> Self {
        let (w, h) = (o.rays.width as usize, o.rays.height as usize);
        let (ow, oh) = (observer.width as usize, observer.height as usize);
        let rays = &o.rays.rays;
        let origin = rays
            .iter()
            .flat_map(|r| r.map_or([0.0; 3], |r| r.origin.to_array()))
            .collect();
        let direction = rays
            .iter()
            .flat_map(|r| r.map_or([0.0; 3], |r| r.direction.to_array()))
            .collect();
        let mask = rays.iter().map(Option::is_some).collect();
        let classes = o.class_ids();
        let quantities: Vec<_> = further_quantities(&o)
            .map(|(name, image)| {
                let samples = image.pixels.iter().flatten().copied().collect();
                (name, Data::F32(samples), [h, w, 4])
            })
            .collect();
        let camera = (o.camera).map(|c| ("camera", Data::U16(c.dn), [h, w, 3]));
        let mut layers = vec![
            ("sensor", Data::F32(rgb(&o.image)), [h, w, 3]),
            ("observer", Data::F32(rgb(observer)), [oh, ow, 3]),
            ("ray_origin", Data::F32(origin), [h, w, 3]),
            ("ray_direction", Data::F32(direction), [h, w, 3]),
            ("mask", Data::Bool(mask), [h, w, 0]),
            ("range", Data::F32(o.range), [h, w, 0]),
            ("ids", Data::U32(o.ids), [h, w, 0]),
            ("classes", Data::U32(classes), [h, w, 0]),
        ];
        layers.extend(camera);
        layers.extend(quantities);
        Layers(layers)
    }
}

/// Every registered ray-map quantity but the ray map's own two, which the arrays above already
/// hold decoded (`ray_origin`, `range`, `ray_direction`, `ids`): its name and image.
fn further_quantities(o: &SensorOutputs) -> impl Iterator<Item = (&'static str, RgbaImage)> + '_ {
    use specchio::sensor::quantities::{Quantity, ALL, DIRECTION_ID, ORIGIN_RANGE};
    let own = [ORIGIN_RANGE.name(), DIRECTION_ID.name()];
    (ALL.iter())
        .filter(move |q| !own.contains(&q.name()))
        .map(|q| (q.name(), o.quantity(*q).into_owned()))
}

/// The array shape of a layer of `dims`, after the `batch` dimension if any.
fn shape(batch: Option<usize>, [h, w, c]: [usize; 3]) -> Vec<usize> {
    let mut s: Vec<usize> = batch.into_iter().collect();
    s.extend([h, w]);
    if c > 0 {
        s.push(c);
    }
    s
}

/// One frame as a dict of arrays; each array takes over its samples without a copy.
pub fn frame_dict<'py>(py: Python<'py>, layers: Layers) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (key, data, dims) in layers.0 {
        let s = shape(None, dims);
        let array = match data {
            Data::F32(v) => PyArray1::from_vec(py, v).reshape(s)?.into_any(),
            Data::U32(v) => PyArray1::from_vec(py, v).reshape(s)?.into_any(),
            Data::U16(v) => PyArray1::from_vec(py, v).reshape(s)?.into_any(),
            Data::Bool(v) => PyArray1::from_vec(py, v).reshape(s)?.into_any(),
        };
        dict.set_item(key, array)?;
    }
    Ok(dict)
}

/// The arrays of a batch of `batch` frames shaped as `first`: the caller's from `out` where
/// it has the key (checked: shape, dtype, C-contiguous, writeable), new ones for the rest.
pub fn batch_dict<'py>(
    py: Python<'py>,
    batch: usize,
    first: &Layers,
    out: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if let Some(out) = out {
        check_out_keys(out, first)?;
    }
    check_batch_memory(batch, first, out)?;
    let numpy = py.import("numpy")?;
    let dict = PyDict::new(py);
    for (key, data, dims) in &first.0 {
        let s = shape(Some(batch), *dims);
        let given = match out {
            Some(out) => out.get_item(key)?,
            None => None,
        };
        let array = match (given, data) {
            (Some(a), Data::F32(_)) => checked::<f32>(key, a, &s, "float32")?,
            (Some(a), Data::U32(_)) => checked::<u32>(key, a, &s, "uint32")?,
            (Some(a), Data::U16(_)) => checked::<u16>(key, a, &s, "uint16")?,
            (Some(a), Data::Bool(_)) => checked::<bool>(key, a, &s, "bool")?,
            // Through numpy itself: an allocation it cannot make is its MemoryError.
            (None, data) => numpy.call_method1("zeros", (s, data.dtype()))?,
        };
        // Any overlap, not only the same object: a view or reshape of another layer's array
        // was filled by both, one over the other. The arrays are C-contiguous (checked), so
        // overlapping bounds are shared memory.
        for (other, array_b) in dict.iter() {
            let shared = numpy.call_method1("may_share_memory", (&array_b, &array))?;
            if shared.is_truthy()? {
                return Err(errors::error(format!(
                    "out[{key:?}]: shares memory with out[{other}] (the same array, or a view \
                     of it); each layer needs an array of its own"
                )));
            }
        }
        dict.set_item(key, array)?;
    }
    Ok(dict)
}

/// Refuses a key of `out` that names no layer of the batch: a misspelt one (`"sensors"`) was
/// ignored, and the array the caller meant to be filled never was.
fn check_out_keys(out: &Bound<'_, PyDict>, first: &Layers) -> PyResult<()> {
    let layers: Vec<&str> = first.0.iter().map(|(key, _, _)| *key).collect();
    for key in out.keys() {
        let name: Option<String> = key.extract().ok();
        if !name.as_deref().is_some_and(|n| layers.contains(&n)) {
            let quoted: Vec<String> = layers.iter().map(|l| format!("{l:?}")).collect();
            return Err(errors::error(format!(
                "out[{}]: no such layer; the batch's layers are {}",
                key.repr()?,
                quoted.join(", ")
            )));
        }
    }
    Ok(())
}

/// Refuses a batch whose new arrays would not fit the memory budget (as every command's
/// estimate does: `SPECCHIO_MEMORY_BUDGET`, else 3/4 of the machine's memory), naming it.
fn check_batch_memory(
    batch: usize,
    first: &Layers,
    out: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let mut estimate = specchio::memory::Estimate::new();
    for (key, data, [h, w, c]) in &first.0 {
        let given = out.map(|o| o.contains(key)).transpose()?.unwrap_or(false);
        if !given {
            let bytes = (h * w * c.max(&1) * data.sample_bytes()) as u64;
            estimate.add_many(format!("the batch's {key:?} arrays"), batch as u64, bytes);
        }
    }
    let budget = specchio::memory::Budget::from_env().map_err(errors::to_py)?;
    estimate
        .check(&budget, "fewer poses per batch, or out= arrays made once")
        .map_err(|e| errors::error(format!("poses: {} poses: {}", batch, errors::message(&e))))
}

/// `array` if it is a C-contiguous, writeable `dtype` array of `shape`; else an error naming
/// `out[key]` and what it should be.
fn checked<'py, T: Element>(
    key: &str,
    array: Bound<'py, PyAny>,
    shape: &[usize],
    dtype: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let wrong = || {
        errors::error(format!(
            "out[{key:?}]: must be a C-contiguous, writeable numpy array of dtype {dtype} and \
             shape ({})",
            dims.join(", ")
        ))
    };
    let typed = array.cast::<PyArrayDyn<T>>().map_err(|_| wrong())?;
    if typed.shape() != shape || !typed.is_c_contiguous() || typed.try_readwrite().is_err() {
        return Err(wrong());
    }
    Ok(array)
}

/// Copies frame `b`'s layers into the batch's arrays.
pub fn fill(dict: &Bound<'_, PyDict>, b: usize, layers: Layers) -> PyResult<()> {
    for (key, data, _) in layers.0 {
        let array = dict
            .get_item(key)?
            .ok_or_else(|| errors::error(format!("the batch has no {key:?} array (a bug)")))?;
        match data {
            Data::F32(v) => copy_into(&array, b, &v)?,
            Data::U32(v) => copy_into(&array, b, &v)?,
            Data::U16(v) => copy_into(&array, b, &v)?,
            Data::Bool(v) => copy_into(&array, b, &v)?,
        }
    }
    Ok(())
}

fn copy_into<T: Element + Copy>(array: &Bound<'_, PyAny>, b: usize, v: &[T]) -> PyResult<()> {
    let typed = array
        .cast::<PyArrayDyn<T>>()
        .map_err(|e| errors::error(e.to_string()))?;
    let mut rw = typed
        .try_readwrite()
        .map_err(|e| errors::error(e.to_string()))?;
    let all = rw
        .as_slice_mut()
        .map_err(|e| errors::error(e.to_string()))?;
    let frame = all.len() / typed.shape()[0];
    if frame != v.len() {
        return Err(errors::error(format!(
            "a frame of {} samples for {frame} (the scene changed size?)",
            v.len()
        )));
    }
    all[b * frame..(b + 1) * frame].copy_from_slice(v);
    Ok(())
}
