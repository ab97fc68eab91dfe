//! The heap setting of a timed run. glibc hands freed heap above 128 KiB back to the OS, so
//! lavapipe's large per-draw allocations page-fault again every frame (measured: ~1,400
//! faults, ~4 ms per amplified cube fill). Keeping up to [`MALLOC_TRIM_THRESHOLD_BYTES`] of
//! freed heap removes that noise; the one setting applies to every method and is recorded in
//! render.json and the benchmark's record.

use std::sync::OnceLock;

/// The freed heap glibc keeps before it trims.
pub const MALLOC_TRIM_THRESHOLD_BYTES: i32 = 512 << 20;

/// The setting in force, once [`tune`] ran (None where the platform has no such setting).
static TRIM_THRESHOLD: OnceLock<Option<i32>> = OnceLock::new();

/// Applies [`MALLOC_TRIM_THRESHOLD_BYTES`] (call it first thing in `main`, before other
/// threads start); returns the value set.
pub fn tune() -> Option<i32> {
    *TRIM_THRESHOLD.get_or_init(|| {
        #[cfg(all(target_os = "linux", target_env = "gnu"))]
        {
            // SAFETY: mallopt only changes glibc's trimming policy.
            let ok = unsafe { libc::mallopt(libc::M_TRIM_THRESHOLD, MALLOC_TRIM_THRESHOLD_BYTES) };
            if ok == 1 {
                return Some(MALLOC_TRIM_THRESHOLD_BYTES);
            }
        }
        None
    })
}

/// The setting in force, for the records (None before [`tune`] or where it could not be set).
pub fn trim_threshold() -> Option<i32> {
    TRIM_THRESHOLD.get().copied().flatten()
}
