//! Long work from Python, said as it goes and stopped by Ctrl-C. Python runs its signal
//! handlers on the thread that called, so that thread asks for them: between a calibration's
//! parts, which run there with the GIL released ([`Watched`]), or every [`POLL`] while a
//! reference traces on threads of its own ([`polled`]). The `KeyboardInterrupt` is kept for
//! the caller to raise once the call is back.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Mutex;
use std::time::Duration;

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

/// How often [`polled`] asks Python for signals: a Ctrl-C is seen within this, and a pixel.
const POLL: Duration = Duration::from_millis(50);

/// `work` on a thread of its own while this one, without the GIL, asks Python for signals
/// every [`POLL`]: what a signal raised (a `KeyboardInterrupt`) goes into `stopped`, and from
/// then on the `stop` given to `work` says true, so it stops at its next check.
pub(crate) fn polled<T: Send>(
    stopped: &Mutex<Option<PyErr>>,
    work: impl FnOnce(&(dyn Fn() -> bool + Sync)) -> T + Send,
) -> T {
    let flag = AtomicBool::new(false);
    let stop = || flag.load(Ordering::Relaxed);
    let (done, finished) = mpsc::channel::<()>();
    std::thread::scope(|s| {
        let stop = &stop;
        let worker = s.spawn(move || {
            let result = work(stop);
            let _ = done.send(());
            result
        });
        // Disconnected: the work panicked before saying it was done; the join says so.
        while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(POLL) {
            if flag.load(Ordering::Relaxed) {
                continue;
            }
            if let Err(e) = Python::attach(|py| py.check_signals()) {
                *stopped.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                flag.store(true, Ordering::Relaxed);
            }
        }
        worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// Adds `text` to `e`'s notes (PEP 678): `add_note` from Python 3.11 on, the `__notes__` list
/// itself before (which the traceback shows only from 3.11; the attribute is there to read):
/// a `KeyboardInterrupt` that says where the work stopped.
pub(crate) fn note(py: Python<'_>, e: &PyErr, text: &str) {
    let value = e.value(py);
    if value.hasattr("add_note").unwrap_or(false) {
        let _ = value.call_method1("add_note", (text,));
        return;
    }
    let notes = match value.getattr("__notes__") {
        Ok(notes) => notes,
        Err(_) => pyo3::types::PyList::empty(py).into_any(),
    };
    if notes.call_method1("append", (text,)).is_ok() {
        let _ = value.setattr("__notes__", notes);
    }
}
