//! Appearance-based localisation's descriptors from Python (docs/python.md, "The API"):
//! describe a cylindrical panorama, compare two descriptions, and recover the turn between
//! them. These are the parts `specchio localise` is made of, offered for a user's own
//! panoramas (a dataset frame's `sensor.panorama.cylindrical.exr`, read with `read_exr`), so
//! that a database of places can be built and queried from Python with the engine's own
//! arithmetic.

use numpy::{PyArray1, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use specchio::image::RgbaImage;
use specchio::sensor::localise::{self, DescriptorKind};

use crate::args::Given;
use crate::errors;

/// The largest `k` a descriptor takes (as `specchio localise --k`).
const MAX_K: u32 = 256;

/// One panorama's description, made by [`Descriptor::describe`]: the descriptor that made it,
/// its `columns` (the heading's resolution) and its `values`.
#[pyclass(module = "specchio", frozen)]
pub struct Signature {
    made_by: (DescriptorKind, u32),
    inner: localise::Signature,
}

#[pymethods]
impl Signature {
    /// Columns of the description: a turn is a shift of this many.
    #[getter]
    fn columns(&self) -> u32 {
        self.inner.columns
    }

    /// The numbers, as a 1-D float32 array (a copy).
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.inner.values)
    }

    fn __repr__(&self) -> String {
        format!(
            "Signature({} k={}, {} columns, {} values)",
            self.made_by.0.name(),
            self.made_by.1,
            self.inner.columns,
            self.inner.values.len()
        )
    }
}

/// A panorama descriptor of `specchio localise`: `"column-shift"` (the default) or
/// `"fourier"`, with its size `k` (1 to 256; column-shift: 16 k columns, fourier: k
/// coefficients per row).
#[pyclass(module = "specchio", frozen)]
pub struct Descriptor {
    kind: DescriptorKind,
    k: u32,
}

impl Descriptor {
    /// The signature `s`, checked to be this descriptor's (another's numbers compared here
    /// would give a distance that means nothing).
    fn own<'a>(&self, s: &'a Signature, name: &str) -> PyResult<&'a localise::Signature> {
        if s.made_by != (self.kind, self.k) {
            return Err(errors::error(format!(
                "{name}: a {} k={} signature, given to {} k={}",
                s.made_by.0.name(),
                s.made_by.1,
                self.kind.name(),
                self.k
            )));
        }
        Ok(&s.inner)
    }

    /// `a` and `b`, checked to be this descriptor's and of one shape (one panorama size).
    fn pair<'a>(
        &self,
        a: &'a Signature,
        b: &'a Signature,
        names: [&str; 2],
    ) -> PyResult<(&'a localise::Signature, &'a localise::Signature)> {
        let (x, y) = (self.own(a, names[0])?, self.own(b, names[1])?);
        if (x.columns, x.values.len()) != (y.columns, y.values.len()) {
            return Err(errors::error(format!(
                "{} and {}: signatures of panoramas of different sizes ({} columns, {} values \
                 against {} columns, {} values)",
                names[0],
                names[1],
                x.columns,
                x.values.len(),
                y.columns,
                y.values.len()
            )));
        }
        Ok((x, y))
    }

    /// `then` of the two signatures the arguments `names` gave, each checked to be a
    /// signature and the pair checked as [`Self::pair`] checks it.
    fn with_pair<R>(
        &self,
        [a, b]: [Given<PyRef<'_, Signature>>; 2],
        names: [&str; 2],
        then: impl FnOnce(&localise::Signature, &localise::Signature) -> R,
    ) -> PyResult<R> {
        let (a, b) = (a.named(names[0])?, b.named(names[1])?);
        let (x, y) = self.pair(&a, &b, names)?;
        Ok(then(x, y))
    }
}

#[pymethods]
impl Descriptor {
    #[new]
    #[pyo3(signature = (name=crate::args::Given::text("column-shift"), k=crate::args::Whole::Fits(8)), text_signature = "(name=\"column-shift\", k=8)")]
    fn new(name: crate::args::Given<String>, k: crate::args::Whole) -> PyResult<Self> {
        let name = name.named("name")?;
        let name = name.as_str();
        let kind = DescriptorKind::parse(name).ok_or_else(|| {
            errors::error(format!(
                "name: {name:?} is not a descriptor; one of {}",
                DescriptorKind::names()
            ))
        })?;
        let k = crate::args::count("k", k, 1, MAX_K)?;
        Ok(Self { kind, k })
    }

    #[getter]
    fn name(&self) -> &'static str {
        self.kind.name()
    }

    #[getter]
    fn k(&self) -> u32 {
        self.k
    }

    /// The description of `panorama`: an (H, W, 3) or (H, W, 4) array of linear RGB(A)
    /// numbers whose W columns span 360 degrees of azimuth (a dataset frame's
    /// `sensor.panorama.cylindrical.exr`).
    fn describe(&self, py: Python<'_>, panorama: &Bound<'_, PyAny>) -> PyResult<Signature> {
        let image = panorama_image(py, panorama)?;
        if let Some(why) = self.kind.k_fault(self.k, image.width) {
            let k = self.k;
            return Err(errors::error(format!(
                "k={k}: {why}; a smaller k or a wider panorama"
            )));
        }
        let descriptor = self.kind.build(self.k);
        let inner = py.detach(|| descriptor.describe(&image));
        Ok(Signature {
            made_by: (self.kind, self.k),
            inner,
        })
    }

    /// How unalike two places are (0 for the same view, whatever the heading).
    fn distance(
        &self,
        a: Given<PyRef<'_, Signature>>,
        b: Given<PyRef<'_, Signature>>,
    ) -> PyResult<f64> {
        self.with_pair([a, b], ["a", "b"], |a, b| {
            self.kind.build(self.k).distance(a, b)
        })
    }

    /// The distance of `query` to each signature of `database`, as a float64 array (the
    /// GIL released meanwhile).
    fn distances<'py>(
        &self,
        py: Python<'py>,
        database: Given<Vec<PyRef<'py, Signature>>>,
        query: Given<PyRef<'py, Signature>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (database, query) = (database.named("database")?, query.named("query")?);
        let query = &*query;
        let mut landmarks = Vec::with_capacity(database.len());
        for (i, s) in database.iter().enumerate() {
            landmarks.push(self.pair(s, query, [&format!("database[{i}]"), "query"])?.0);
        }
        let descriptor = self.kind.build(self.k);
        let d = py.detach(|| {
            landmarks
                .iter()
                .map(|l| descriptor.distance(l, &query.inner))
                .collect::<Vec<f64>>()
        });
        Ok(PyArray1::from_vec(py, d))
    }

    /// The turn in radians, in [0, 2 pi), that maps `landmark`'s panorama onto `query`'s:
    /// the query's column at azimuth a shows what the landmark's shows at a - turn.
    fn turn(
        &self,
        landmark: Given<PyRef<'_, Signature>>,
        query: Given<PyRef<'_, Signature>>,
    ) -> PyResult<f64> {
        self.with_pair([landmark, query], ["landmark", "query"], |l, q| {
            self.kind.build(self.k).turn(l, q)
        })
    }

    fn __repr__(&self) -> String {
        format!("Descriptor({:?}, k={})", self.kind.name(), self.k)
    }
}

/// `panorama` as an image: an array-like of finite numbers of shape (H, W, 3) or (H, W, 4),
/// converted as numpy converts it; anything else is refused naming `panorama`.
fn panorama_image(py: Python<'_>, panorama: &Bound<'_, PyAny>) -> PyResult<RgbaImage> {
    let refuse = |why: String| errors::error(format!("panorama: {why}"));
    // Its copies' size before any is made: a broadcast view of 100,000² pixels costs nothing
    // to pass and 112 GiB to copy.
    let given: Vec<usize> = py
        .import("numpy")?
        .call_method1("shape", (panorama,))
        .and_then(|s| s.extract())
        .unwrap_or_default();
    let values = given.iter().fold(1u64, |n, &d| n.saturating_mul(d as u64));
    let pixels = given
        .iter()
        .take(2)
        .fold(1u64, |n, &d| n.saturating_mul(d as u64));
    let mut copies = specchio::memory::Estimate::new();
    copies.add_many("the panorama as float32, twice", values, 8);
    copies.add_many("its pixels as RGBA", pixels, 16);
    let budget = specchio::memory::Budget::from_env().map_err(|e| refuse(errors::message(&e)))?;
    copies
        .check(&budget, "give a smaller panorama")
        .map_err(|e| refuse(errors::message(&e)))?;
    let (array, shape) = crate::args::numbers(py, "panorama", panorama, "float32")?;
    let array = array
        .cast_into::<PyArray3<f32>>()
        .ok()
        .filter(|a| matches!(a.shape(), [h, w, 3 | 4] if *h > 0 && *w > 0))
        .ok_or_else(|| {
            refuse(format!(
                "an array of shape {shape:?}; give (H, W, 3) or (H, W, 4) linear RGB(A), H and \
                 W at least 1"
            ))
        })?;
    let (h, w, c) = (array.shape()[0], array.shape()[1], array.shape()[2]);
    let values = array
        .readonly()
        .as_array()
        .iter()
        .copied()
        .collect::<Vec<f32>>();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let (pixel, channel) = (i / c, i % c);
        return Err(refuse(format!(
            "[{}, {}, {channel}] is {}; a panorama's values must be finite",
            pixel / w,
            pixel % w,
            values[i]
        )));
    }
    let pixels = values
        .chunks_exact(c)
        .map(|p| [p[0], p[1], p[2], 1.0])
        .collect();
    Ok(RgbaImage {
        width: u32::try_from(w).map_err(|_| refuse(format!("{w} columns are too many")))?,
        height: u32::try_from(h).map_err(|_| refuse(format!("{h} rows are too many")))?,
        pixels,
    })
}
