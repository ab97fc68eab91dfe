//! The engine's warnings, said as Python warnings: a notebook never shows the process's
//! standard error, where a command says them (`specchio::warnings`). The module holds them
//! from its import on; each call that runs engine work says those its work gave, after it.

use pyo3::prelude::*;

/// From now on the engine's warnings are kept for [`detach`] to say (at the module's import).
pub(crate) fn hold() {
    specchio::warnings::hold();
}

/// `work` without the GIL, as `Python::detach`, then each warning the engine gave meanwhile
/// as a `UserWarning`: an exception instead where the caller's warning filters say so.
pub(crate) fn detach<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let done = py.detach(work);
    say(py)?;
    Ok(done)
}

/// Says the engine's warnings kept so far.
pub(crate) fn say(py: Python<'_>) -> PyResult<()> {
    for text in specchio::warnings::take() {
        crate::dataset::warn(py, text)?;
    }
    Ok(())
}
