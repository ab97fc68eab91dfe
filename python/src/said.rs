//! The engine's warnings, said as Python warnings: a notebook never shows the process's
//! standard error, where a command says them (`specchio::warnings`). The module holds them
//! from its import on; a call that ran engine work says them when it returns:
//! - [`say`] where nothing was placed yet (or nothing is written), so that a warning the
//!   caller's filters make an error raises and places nothing;
//! - [`say_unraised`] after an output was placed, where raising would report a failure that
//!   did not happen, and beside the call's own error, which comes first: a warning made an
//!   error is then written as Python writes an exception it cannot raise, and never lost.

use pyo3::prelude::*;

/// From now on the engine's warnings are kept for [`say`] (at the module's import).
pub(crate) fn hold() {
    specchio::warnings::hold();
}

/// `work` without the GIL, as `Python::detach`, then its warnings: for work that places
/// nothing. Its own error comes first (the warnings then unraised); after a success, a warning
/// the caller's filters make an error is raised ([`say`]).
pub(crate) fn detach<T: Send, E: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, E> + Send,
) -> PyResult<Result<T, E>> {
    let done = py.detach(work);
    match done {
        Ok(_) => say(py)?,
        Err(_) => say_unraised(py),
    }
    Ok(done)
}

/// `work` without the GIL, its warnings left for the caller to say when the call's stage
/// allows: before it places an output ([`say`]), or after ([`say_unraised`]).
pub(crate) fn unsaid<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> T {
    py.detach(work)
}

/// Says every warning the engine gave, each a `UserWarning`; the first that the caller's
/// filters make an error is raised once all were said.
pub(crate) fn say(py: Python<'_>) -> PyResult<()> {
    let mut first = None;
    for text in specchio::warnings::take() {
        if let Err(e) = crate::dataset::warn(py, text) {
            first.get_or_insert(e);
        }
    }
    first.map_or(Ok(()), Err)
}

/// Says the warnings, never raised (an output is placed, or the call raises its own error):
/// a warning the filters make an error is written as an unraisable exception.
pub(crate) fn say_unraised(py: Python<'_>) {
    if let Err(e) = say(py) {
        e.write_unraisable(py, None);
    }
}
