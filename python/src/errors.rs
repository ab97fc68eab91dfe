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
    error(message(&e))
}

/// A `SpecchioError` with `text`, the command line's options it names said as this package's
/// arguments (`python_words`).
pub fn error(text: impl Into<String>) -> PyErr {
    SpecchioError::new_err(python_words(&text.into(), &[]))
}

/// A `SpecchioError` with `text` as the command line says it: for `specchio.localise`, whose
/// keyword arguments are the command's options.
pub fn command_error(text: impl Into<String>) -> PyErr {
    SpecchioError::new_err(text.into())
}

/// The engine's messages are the command line's, and name its options (`--grid: the spacing
/// must be ...`, `--device "x" names no device`); a Python caller gave an argument, not an
/// option, and would look for `--grid` in vain. Each phrase here is said as the argument or
/// the scene field that sets the same thing; `first` comes before the table (a function whose
/// argument has another name: `pose_grid`'s `spacing` is the command's `--grid`).
pub fn python_words(text: &str, first: &[(&str, &str)]) -> String {
    let mut said = String::with_capacity(text.len());
    let mut rest = text;
    'text: while let Some(at) = rest.find("--") {
        let (before, from) = rest.split_at(at);
        said.push_str(before);
        // An option stands alone: after a space or a parenthesis, or first. Not within a path
        // (`/data/--grid/t.csv`) or a value a user gave, which messages quote in backticks or
        // double quotes. (A file named exactly as an option and said first is the one case
        // taken for an option.)
        let starts_word = (said.chars().last()).is_none_or(|c| c.is_whitespace() || c == '(');
        for (option, argument) in first.iter().chain(ARGUMENTS) {
            let Some(after) = from.strip_prefix(option) else {
                continue;
            };
            let ends_word = option.ends_with(' ')
                || (after.chars().next()).is_none_or(|c| c.is_whitespace() || ":),;".contains(c));
            if starts_word && ends_word {
                said.push_str(argument);
                rest = after;
                continue 'text;
            }
        }
        said.push_str("--");
        rest = &from[2..];
    }
    said.push_str(rest);
    said
}

/// The command line's options in engine messages, and what sets the same thing from Python.
/// A phrase ending in a space takes the value after it (`--device "x"` is `device="x"`).
const ARGUMENTS: &[(&str, &str)] = &[
    ("--device ", "device="),
    ("--format mcap", "format=\"mcap\""),
    ("--grid", "grid"),
    ("--headings", "headings"),
    ("--time", "time"),
    ("--trajectory", "trajectory"),
    ("--out", "out"),
    ("--resume", "resume=True"),
    // The package's renderers take the face size from the scene file alone.
    ("--cube-size", "cube.face_size"),
    // The package's renderers walk where the engine chooses; the command can choose.
    (
        "--trace-in fragment",
        "`specchio render --trace-in fragment`",
    ),
];

/// A serialisable record as the Python object `json.loads` would give.
pub fn json_to_py<T: serde::Serialize>(py: Python<'_>, value: &T) -> PyResult<Py<PyAny>> {
    let text = serde_json::to_string(value).map_err(to_py)?;
    let json = py.import("json")?;
    Ok(json.call_method1("loads", (text,))?.unbind())
}
