//! A lost device on demand, for the tests of what no CPU driver does when asked: lose its
//! device (a GPU reset, a driver crash, an unplugged eGPU). With
//! `SPECCHIO_FAULT_DEVICE_LOST=N` set, every fence wait after the first N answers
//! `VK_ERROR_DEVICE_LOST`, as a lost device's waits do; the wait itself still happens, so the
//! work submitted has really finished and tearing it down is as safe as on a lost device,
//! where nothing runs any more. Unset (always, outside tests), it changes nothing.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use ash::vk;

/// The variable that asks for the fault.
pub const DEVICE_LOST_VAR: &str = "SPECCHIO_FAULT_DEVICE_LOST";

/// The fence waits answered so far.
static WAITS: AtomicU64 = AtomicU64::new(0);

/// How many waits succeed before the device is "lost": None when not asked.
fn after() -> Option<u64> {
    static AFTER: OnceLock<Option<u64>> = OnceLock::new();
    *AFTER.get_or_init(|| std::env::var(DEVICE_LOST_VAR).ok()?.trim().parse().ok())
}

/// A fence wait's result as the device gives it, or `ERROR_DEVICE_LOST` once the fault is due.
pub fn fence_wait(result: Result<(), vk::Result>) -> Result<(), vk::Result> {
    match after() {
        Some(n) if WAITS.fetch_add(1, Ordering::SeqCst) >= n => {
            result.and(Err(vk::Result::ERROR_DEVICE_LOST))
        }
        _ => result,
    }
}
