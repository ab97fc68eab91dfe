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
