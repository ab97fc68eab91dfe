//! Arguments from Python, taken as Python gives them and checked with their names: `spp=-1`
//! is `SpecchioError("spp: -1; must be a whole number from 1 to 4096")`, not an
//! `OverflowError` that names nothing (as an unsigned parameter gave); `time="0"` is
//! `SpecchioError("time: '0' (a str); give a number ...")`, not PyO3's `TypeError` whose
//! message names no argument ([`Given`]); `device=0` is the
//! first device, as the docs say (an index or part of a name); poses of any numeric dtype
//! are poses, not a "type mismatch".

use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::exceptions::{PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyInt, PyString};

use crate::errors;

/// An argument of type `T` as Python gave it, or what came instead: taken whatever it is and
/// refused by name in [`Given::named`]. PyO3's own refusal of a wrong type ("must be real
/// number, not str") names the argument only in a note, which `str(e)` and Pythons before
/// 3.11 do not show. Every argument a user passes goes through it (or, for the frames and
/// files `specchio.ray` passes between driver and workers, [`indices`] and [`frame_files`]);
/// `DatasetOutput.begin` and `finish` keep PyO3's own types.
#[derive(Debug, Clone)]
pub enum Given<T> {
    Is(T),
    /// What came instead: its value (when short) and its type, `'0' (a str)`.
    Not(String),
    /// A list whose element `at` is not what it holds: that element, and what it takes.
    NotAt {
        at: usize,
        what: String,
        wanted: String,
    },
}

/// What an argument of a Rust type takes, as a message says it, and what Python would convert
/// to it that no one means (a bool as a number).
pub trait Wanted {
    fn wanted() -> String;
    fn refuses(_obj: &Bound<'_, PyAny>) -> bool {
        false
    }
    /// For a list: its first element that is not what it holds, described, and what an
    /// element takes (`database[1]: 1 (an int); give a specchio.Signature`).
    fn wrong_element(_obj: &Bound<'_, PyAny>) -> Option<(usize, String, String)> {
        None
    }
}

/// The first element of a list or tuple `obj` that `fits` refuses, described.
fn first_unfit(
    obj: &Bound<'_, PyAny>,
    fits: impl Fn(&Bound<'_, PyAny>) -> bool,
) -> Option<(usize, String)> {
    // A list or a tuple: a dict or a set would give its keys or no order.
    let sequence =
        obj.is_instance_of::<pyo3::types::PyList>() || obj.is_instance_of::<pyo3::types::PyTuple>();
    if !sequence {
        return None;
    }
    let items = obj.try_iter().ok()?;
    (items.enumerate()).find_map(|(i, item)| {
        item.ok()
            .filter(|item| !fits(item))
            .map(|item| (i, described(&item)))
    })
}

impl Wanted for f64 {
    fn wanted() -> String {
        "a number (an int or a float)".to_owned()
    }
    fn refuses(obj: &Bound<'_, PyAny>) -> bool {
        is_bool(obj)
    }
}

/// Whether `obj` is a bool, Python's or numpy's (`np.True_`, which converts to 1.0 as
/// readily): never a number anyone means.
pub fn is_bool(obj: &Bound<'_, PyAny>) -> bool {
    if obj.is_instance_of::<PyBool>() {
        return true;
    }
    let kind = obj.get_type();
    let named = |attr: &str| kind.getattr(attr).ok().map(|v| v.to_string());
    named("__module__").as_deref() == Some("numpy")
        && matches!(named("__name__").as_deref(), Some("bool" | "bool_"))
}

/// Whether a list or tuple (nested, as an array-like is) holds a bool anywhere: numpy would
/// make `(True, 3, 0, 0)` a row of numbers without a word.
fn holds_bool(obj: &Bound<'_, PyAny>, depth: usize) -> bool {
    let items = match obj.cast::<pyo3::types::PyList>() {
        Ok(list) => list.iter().collect::<Vec<_>>(),
        Err(_) => match obj.cast::<pyo3::types::PyTuple>() {
            Ok(tuple) => tuple.iter().collect(),
            Err(_) => return is_bool(obj),
        },
    };
    depth > 0 && items.iter().any(|item| holds_bool(item, depth - 1))
}

impl Wanted for bool {
    fn wanted() -> String {
        "True or False".to_owned()
    }
}

impl Wanted for String {
    fn wanted() -> String {
        "a str".to_owned()
    }
}

impl Wanted for std::path::PathBuf {
    fn wanted() -> String {
        "a path (a str or an os.PathLike)".to_owned()
    }
}

impl<'py, T: pyo3::PyClass> Wanted for PyRef<'py, T> {
    fn wanted() -> String {
        format!("a specchio.{}", T::NAME)
    }
}

impl<'py, T: pyo3::PyClass> Wanted for Vec<PyRef<'py, T>> {
    fn wanted() -> String {
        format!("a list of specchio.{}", T::NAME)
    }
    fn wrong_element(obj: &Bound<'_, PyAny>) -> Option<(usize, String, String)> {
        let (at, what) = first_unfit(obj, |item| item.is_instance_of::<T>())?;
        Some((at, what, format!("a specchio.{}", T::NAME)))
    }
}

impl<'py> Wanted for Bound<'py, pyo3::types::PyDict> {
    fn wanted() -> String {
        "a dict".to_owned()
    }
}

impl Wanted for Vec<f64> {
    fn wanted() -> String {
        "a list of numbers".to_owned()
    }
    fn refuses(obj: &Bound<'_, PyAny>) -> bool {
        holds_bool(obj, 1)
    }
    fn wrong_element(obj: &Bound<'_, PyAny>) -> Option<(usize, String, String)> {
        let number = |item: &Bound<'_, PyAny>| !is_bool(item) && item.extract::<f64>().is_ok();
        let (at, what) = first_unfit(obj, number)?;
        Some((at, what, f64::wanted()))
    }
}

impl<'a, 'py, T> FromPyObject<'a, 'py> for Given<T>
where
    T: FromPyObject<'a, 'py> + Wanted,
    T::Error: Into<PyErr>,
{
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Some((at, what, wanted)) = T::wrong_element(&obj) {
            return Ok(Given::NotAt { at, what, wanted });
        }
        if T::refuses(&obj) {
            return Ok(Given::Not(described(&obj)));
        }
        let py = obj.py();
        match obj.extract::<T>().map_err(Into::<PyErr>::into) {
            Ok(v) => Ok(Given::Is(v)),
            // Not of the type: said by name in `named`.
            Err(e) if e.is_instance_of::<PyTypeError>(py) => Ok(Given::Not(described(&obj))),
            Err(e) if e.is_instance_of::<PyOverflowError>(py) => {
                Ok(Given::Not(format!("{}, too large for it", described(&obj))))
            }
            // Anything else (Ctrl-C or a MemoryError in a `__float__` or `__fspath__`) is
            // the caller's, as raised.
            Err(e) => Err(e),
        }
    }
}

impl<T: Wanted> Given<T> {
    /// The value, or an error naming the argument `name`, what it was given and what it takes.
    pub fn named(self, name: &str) -> PyResult<T> {
        match self {
            Given::Is(v) => Ok(v),
            Given::Not(what) => Err(errors::error(format!(
                "{name}: {what}; give {}",
                T::wanted()
            ))),
            Given::NotAt { at, what, wanted } => Err(errors::error(format!(
                "{name}[{at}]: {what}; give {wanted}"
            ))),
        }
    }
}

/// An optional argument: `None`, its value, or an error naming it (as [`Given::named`]).
pub fn maybe<T: Wanted>(name: &str, value: Option<Given<T>>) -> PyResult<Option<T>> {
    value.map(|v| v.named(name)).transpose()
}

impl Given<String> {
    /// A default text, for a signature.
    pub fn text(text: &str) -> Self {
        Given::Is(text.to_owned())
    }
}

/// `obj` for a message: its value where its `repr` is short, and its type (`'0' (a str)`,
/// `[1, 2] (a list)`); a long value by its type alone.
fn described(obj: &Bound<'_, PyAny>) -> String {
    let kind = obj
        .get_type()
        .name()
        .map_or("?".to_owned(), |n| n.to_string());
    let article = if kind.starts_with(['a', 'e', 'i', 'o']) {
        "an"
    } else {
        "a"
    };
    match obj.repr().map(|r| r.to_string()) {
        Ok(r) if r.chars().count() <= 40 => format!("{r} ({article} {kind})"),
        _ => format!("{article} {kind}"),
    }
}

/// A Python int as the caller gave it, however large: -1, 2**64 and 2**200 are values to
/// refuse by name ([`count`]), not an `OverflowError` that names nothing, which PyO3 raises
/// for an int that does not fit the parameter's Rust type; anything but an int is refused by
/// name there too.
#[derive(Debug, Clone, PartialEq)]
pub enum Whole {
    /// Within 128 bits.
    Fits(i128),
    /// Beyond them: its sign and its length in bits.
    Beyond { negative: bool, bits: u64 },
    /// A bool, which Python counts as an int and no one means as one.
    Bool(bool),
    /// No int at all: what it was (`1.5 (a float)`).
    Not(String),
}

impl<'a, 'py> FromPyObject<'a, 'py> for Whole {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        // Python's bool is an int (True is 1); `spp=True` is a slip, not a count, refused by
        // name in `count`.
        if is_bool(&obj) {
            return Ok(Whole::Bool(obj.is_truthy()?));
        }
        match obj.extract::<i128>() {
            Ok(v) => Ok(Whole::Fits(v)),
            Err(_) if !obj.is_instance_of::<PyInt>() => Ok(Whole::Not(described(&obj))),
            Err(_) => Ok(Whole::Beyond {
                negative: obj.lt(0)?,
                bits: obj.call_method0("bit_length")?.extract()?,
            }),
        }
    }
}

impl Whole {
    /// The value for a message: its digits where there are at most 20 (2**64 is written
    /// out), else its size (2**200 has 61 digits, which no one reads).
    fn shown(&self) -> String {
        let (negative, bits) = match self {
            Whole::Fits(v) if v.unsigned_abs() < 10u128.pow(20) => return v.to_string(),
            Whole::Fits(v) => (*v < 0, u64::from(128 - v.unsigned_abs().leading_zeros())),
            Whole::Beyond { negative, bits } => (*negative, *bits),
            Whole::Bool(b) => return format!("{} (a bool)", if *b { "True" } else { "False" }),
            Whole::Not(what) => return what.clone(),
        };
        let sign = if negative { "a negative" } else { "an" };
        format!("{sign} int of {bits} bits")
    }
}

/// The whole number `value` of the argument `name`, within `lo..=hi`, or an error naming the
/// argument, the value and the range.
pub fn count(name: &str, value: Whole, lo: u32, hi: u32) -> PyResult<u32> {
    match &value {
        Whole::Fits(v) => match u32::try_from(*v) {
            Ok(v) if (lo..=hi).contains(&v) => return Ok(v),
            _ => {}
        },
        Whole::Beyond { .. } | Whole::Bool(_) | Whole::Not(_) => {}
    }
    Err(errors::error(format!(
        "{name}: {}; must be a whole number from {lo} to {hi}",
        value.shown()
    )))
}

/// A device as `device=` names it: its index (an int, as `specchio.devices()` numbers them)
/// or part of its name (a str), in the form the engine's selector takes.
pub fn device(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(value) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    if value.is_instance_of::<PyString>() {
        return Ok(Some(value.extract()?));
    }
    // An int, or anything that is one by `__index__` (numpy's integers, which `spp` takes
    // too); never a bool, which Python counts as an int and no one means as a device.
    let index = (!is_bool(value))
        .then(|| value.call_method0("__index__").ok())
        .flatten();
    if let Some(index) = index {
        let index: Whole = index.extract()?;
        return Ok(Some(count("device", index, 0, u32::MAX)?.to_string()));
    }
    let shown = value.repr().map_or("?".to_owned(), |r| r.to_string());
    Err(errors::error(format!(
        "device: {shown}; give an index (int) or part of a name (str), as specchio.devices() \
         lists them"
    )))
}

/// `poses` as a (B, 4) float64 array: any array-like of numbers (ints, float32, lists) is
/// converted as numpy converts it; anything else (strings, bools, objects) is refused, naming
/// `poses`.
pub fn poses<'py>(
    py: Python<'py>,
    poses: &Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    let (array, shape) = numbers(py, "poses", poses, "float64")?;
    let array = array.cast_into::<PyArray2<f64>>().map_err(|_| {
        errors::error(format!(
            "poses: an array of shape {shape:?}; give (B, 4) rows of x, y, z, heading"
        ))
    })?;
    Ok(array.readonly())
}

/// One pose, `pose=`: x, y, z, heading as numbers (ints, floats, a list, a numpy array of 4),
/// refused as `render_batch` refuses a batch's (bools, complex numbers, strings) and in any
/// other shape, naming `pose`.
pub fn pose(py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<[f64; 4]> {
    let (array, shape) = numbers(py, "pose", value, "float64")?;
    let wrong = || {
        errors::error(format!(
            "pose: an array of shape {shape:?}; give x, y, z, heading (4 numbers)"
        ))
    };
    if shape != [4] {
        return Err(wrong());
    }
    let values: Vec<f64> = array
        .call_method0("tolist")?
        .extract()
        .map_err(|_| wrong())?;
    values.try_into().map_err(|_| wrong())
}

/// `value` as a numpy array of `dtype` and its shape: any array-like of numbers (signed and
/// unsigned ints, floats: numpy's kinds for numbers, not `b`ool) converted as numpy converts
/// it; anything else refused, naming the argument `name`.
pub fn numbers<'py>(
    py: Python<'py>,
    name: &str,
    value: &Bound<'py, PyAny>,
    dtype: &str,
) -> PyResult<(Bound<'py, PyAny>, Vec<usize>)> {
    let not_numbers =
        |why: String| errors::error(format!("{name}: not an array of numbers ({why})"));
    let given = py
        .import("numpy")?
        .call_method1("asarray", (value,))
        .map_err(|e| not_numbers(e.to_string()))?;
    let kind: String = given.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        let dtype = given.getattr("dtype")?.str()?.to_string();
        return Err(not_numbers(format!("dtype {dtype}")));
    }
    // Bools among numbers in a list become numbers in the array; refused as a bool alone is.
    if holds_bool(value, 2) {
        return Err(not_numbers("a bool among them".to_owned()));
    }
    let shape: Vec<usize> = given.getattr("shape")?.extract()?;
    Ok((given.call_method1("astype", (dtype,))?, shape))
}

/// The items of `value`, an iterable other than a str, or an error naming `name`, what it
/// was given and `wanted` (a str iterates its characters, which no one means as a list).
fn items_of<'py>(
    name: &str,
    value: &Bound<'py, PyAny>,
    wanted: &str,
) -> PyResult<Bound<'py, pyo3::types::PyIterator>> {
    (!value.is_instance_of::<PyString>())
        .then(|| value.try_iter().ok())
        .flatten()
        .ok_or_else(|| errors::error(format!("{name}: {}; give {wanted}", described(value))))
}

/// A list of frame indices, each named `name[k]` when it is not a whole number below `n`
/// (a bool is none); a str, or anything that is not a list of them, is refused by `name`.
pub fn indices(name: &str, value: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<usize>> {
    let items = items_of(name, value, "a list of frame indices")?;
    let mut out = Vec::new();
    for (k, item) in items.enumerate() {
        let whole: Whole = item?.extract()?;
        let fits = match &whole {
            Whole::Fits(v) => usize::try_from(*v).ok().filter(|&i| i < n),
            _ => None,
        };
        let Some(i) = fits else {
            let range = match n {
                0 => "there are no frames".to_owned(),
                n => format!("must be a frame index from 0 to {}", n - 1),
            };
            return Err(errors::error(format!(
                "{name}[{k}]: {}; {range}",
                whole.shown()
            )));
        };
        out.push(i);
    }
    Ok(out)
}

/// A frame's files as `DatasetFrames.frames` gives them: a list of (path, bytes) pairs, each
/// refused by its place in `name` when it is not one.
pub fn frame_files(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<(String, Vec<u8>)>> {
    let items = items_of(name, value, "a list of (path, bytes) pairs")?;
    let mut out = Vec::new();
    for (k, item) in items.enumerate() {
        let item = item?;
        let pair = item
            .extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>()
            .map_err(|_| {
                errors::error(format!(
                    "{name}[{k}]: {}; give a (path, bytes) pair",
                    described(&item)
                ))
            })?;
        let path: String = pair.0.extract().map_err(|_| {
            errors::error(format!(
                "{name}[{k}][0]: {}; give the path as a str",
                described(&pair.0)
            ))
        })?;
        let bytes = pair
            .1
            .cast::<pyo3::types::PyBytes>()
            .map(|b| b.as_bytes().to_vec())
            .map_err(|_| {
                errors::error(format!(
                    "{name}[{k}][1]: {}; give the file's bytes",
                    described(&pair.1)
                ))
            })?;
        out.push((path, bytes));
    }
    Ok(out)
}

/// Names given as one comma-separated str (`example`) or a list of str, as that str; a list
/// element that is not a str is named by its place (`outputs[1]: None (a NoneType)`).
pub fn names_text(name: &str, value: &Bound<'_, PyAny>, example: &str) -> PyResult<String> {
    if let Ok(text) = value.extract::<String>() {
        return Ok(text);
    }
    let wanted = format!("a str ({example}) or a list of names");
    let items = items_of(name, value, &wanted)?;
    let mut names = Vec::new();
    for (i, item) in items.enumerate() {
        let item = item?;
        let text = item.extract::<String>().map_err(|_| {
            errors::error(format!(
                "{name}[{i}]: {}; give a name (a str)",
                described(&item)
            ))
        })?;
        names.push(text);
    }
    Ok(names.join(","))
}
