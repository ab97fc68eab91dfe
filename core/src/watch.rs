//! Long CPU work row by row, watched: each row done is reported, and the watcher may stop the
//! work before its next part. The reference's cameras and the FLIP of a large comparison are
//! such work; `process::Progress` (in the engine) is the watcher that says an estimate and
//! honours Ctrl-C, and this module is below both, so neither imports the other.

/// What long work reports to: rows done (as each part ends, all its rows at once, so that a
/// rate is the rate of the work), and whether to stop before the next part.
pub trait Watch: Sync {
    /// The work is `rows` rows of `width` pixels, said as it begins where it is known only
    /// then (the images a comparison reads, from their headers).
    fn begin(&self, _rows: u64, _width: u32) {}
    fn rows_done(&self, rows: u32);
    fn stop(&self) -> bool;
}

/// A progress callback for work that says the fraction of it done (0 to 1: the EXR codec's),
/// telling `watch` the rows of `rows` it has passed, each once.
pub fn rows_of_fraction(watch: &dyn Watch, rows: u64) -> impl FnMut(f64) + '_ {
    let mut said = 0;
    move |done: f64| {
        let now = ((done.clamp(0.0, 1.0) * rows as f64) as u64).min(rows);
        if now > said {
            watch.rows_done((now - said) as u32);
            said = now;
        }
    }
}

/// Watched work that its [`Watch`] stopped: nothing of it is kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stopped;

/// No one watching: every row is done.
pub struct Unwatched;

impl Watch for Unwatched {
    fn rows_done(&self, _: u32) {}

    fn stop(&self) -> bool {
        false
    }
}
