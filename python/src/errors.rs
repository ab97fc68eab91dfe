//! Engine errors as Python exceptions, and JSON records as Python objects.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    specchio,
    SpecchioError,
    PyException,
    "An error of the specchio engine: a scene, trajectory or argument it cannot use (the \
     message names the file, line and field), a device that lacks what was asked, or an \
     output it could not write."
);

/// `e` and its causes as one message, as the command line prints them (`a: b: c`).
pub fn message(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let more = c.to_string();
        // A transparent wrapper repeats its cause's text: say it once.
        if !text.ends_with(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        cause = c.source();
    }
    specchio::text::bounded_message(&text)
}

/// Any engine error as a `SpecchioError`.
pub fn to_py<E: std::error::Error + 'static>(e: E) -> PyErr {
    SpecchioError::new_err(message(&e))
}

/// A `SpecchioError` with `text`.
pub fn error(text: impl Into<String>) -> PyErr {
    SpecchioError::new_err(text.into())
}

/// A serialisable record as the Python object `json.loads` would give.
pub fn json_to_py<T: serde::Serialize>(py: Python<'_>, value: &T) -> PyResult<Py<PyAny>> {
    let text = serde_json::to_string(value).map_err(to_py)?;
    let json = py.import("json")?;
    Ok(json.call_method1("loads", (text,))?.unbind())
}
