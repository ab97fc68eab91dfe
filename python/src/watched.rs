//! A calibration from Python, said as it goes and stopped by Ctrl-C between its parts. The
//! parts run with the GIL released on the calling thread, where Python runs its signal
//! handlers, so a check there sees a Ctrl-C at once; the `KeyboardInterrupt` is kept for the
//! caller to raise once the call is back.

use std::sync::Mutex;

use pyo3::prelude::*;
use specchio::process::progress::Progress;
use specchio::sensor::central::{Part, Watch};

/// A calibration's estimate on stderr (as the command says it) and Python's signals between
/// its parts; what Python raised goes into `stopped`.
pub(crate) struct Watched<'s> {
    pub progress: Progress,
    pub stopped: &'s Mutex<Option<PyErr>>,
}

impl Watch for Watched<'_> {
    fn part_done(&self, part: Part) {
        self.progress.add(part.share());
    }

    fn stop(&self) -> bool {
        let Err(e) = Python::attach(|py| py.check_signals()) else {
            return false;
        };
        *self.stopped.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
        true
    }
}

/// What Python raised in `stopped` (a `KeyboardInterrupt`), to raise in its place.
pub(crate) fn raised(stopped: Mutex<Option<PyErr>>) -> Option<PyErr> {
    stopped.into_inner().unwrap_or_else(|p| p.into_inner())
}
