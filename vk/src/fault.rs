//! Faults on demand for tests: a lost device, a lost surface, and a frame held on the GPU.
//!
//! A lost device on demand, for the tests of what no CPU driver does when asked: lose its
//! device (a GPU reset, a driver crash, an unplugged eGPU). With
//! `SPECCHIO_FAULT_DEVICE_LOST=N` set, every fence wait after the first N answers
//! `VK_ERROR_DEVICE_LOST`, as a lost device's waits do; the wait itself still happens, so the
//! work submitted has really finished and tearing it down is as safe as on a lost device,
//! where nothing runs any more. Unset (always, outside tests), it changes nothing.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::thread::JoinHandle;
use std::time::Duration;

use ash::vk;

use super::device::Device;
use super::{GpuError, VkContext};

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

/// The variable that loses the surface: with `SPECCHIO_FAULT_SURFACE_LOST=N`, every present
/// after the first N answers `VK_ERROR_SURFACE_LOST_KHR` (after the real present), as when the
/// window system takes the surface away; no CPU driver's surface can be lost on demand.
pub const SURFACE_LOST_VAR: &str = "SPECCHIO_FAULT_SURFACE_LOST";

/// The presents answered so far.
static PRESENTS: AtomicU64 = AtomicU64::new(0);

/// A present's result as the surface gives it, or `ERROR_SURFACE_LOST_KHR` once the fault is
/// due.
pub fn present(result: Result<bool, vk::Result>) -> Result<bool, vk::Result> {
    static AFTER: OnceLock<Option<u64>> = OnceLock::new();
    let after = *AFTER.get_or_init(|| std::env::var(SURFACE_LOST_VAR).ok()?.trim().parse().ok());
    match after {
        Some(n) if PRESENTS.fetch_add(1, Ordering::SeqCst) >= n => {
            result.and(Err(vk::Result::ERROR_SURFACE_LOST_KHR))
        }
        _ => result,
    }
}

/// The variable that holds a frame: with `SPECCHIO_FAULT_HOLD_FRAME=N`, the first renderer's
/// N-th frame (counting from 1) waits on the GPU until the program lets it go
/// ([`release_held_frames`]) or [`HOLD_LIMIT`] passes: a frame as slow as the test needs,
/// made slow where a slow frame is (the queue), to show that nothing waits for it that
/// should not (the viewer's event loop).
pub const HOLD_FRAME_VAR: &str = "SPECCHIO_FAULT_HOLD_FRAME";

/// The longest a frame is held: a program that never lets go still ends, and says so.
pub const HOLD_LIMIT: Duration = Duration::from_secs(60);

/// Whether a hold was handed out (only the first renderer's frame is held).
static HOLD_TAKEN: AtomicBool = AtomicBool::new(false);
/// Set by [`release_held_frames`]; the hold's thread waits on it.
static RELEASED: (Mutex<bool>, Condvar) = (Mutex::new(false), Condvar::new());

/// Lets every held frame go on (at once if none is held yet: none will be).
pub fn release_held_frames() {
    let (released, changed) = &RELEASED;
    *released.lock().unwrap_or_else(|p| p.into_inner()) = true;
    changed.notify_all();
}

/// A held frame: a timeline semaphore its submission waits on, and the thread that signals
/// it once the frame is let go. Its owner releases it before waiting for that frame
/// ([`Hold::release`]); dropped after the frame finished.
pub struct Hold {
    /// Which frame of its renderer is held (1: the first).
    frame: u64,
    semaphore: vk::Semaphore,
    signaller: Option<JoinHandle<()>>,
    device: Arc<Device>,
}

impl Hold {
    /// The hold the variable asks for, once per process; `None` when not asked.
    pub fn asked(device: &Arc<Device>) -> Result<Option<Hold>, GpuError> {
        let Some(frame) = std::env::var(HOLD_FRAME_VAR)
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
            .filter(|&n| n > 0)
        else {
            return Ok(None);
        };
        if HOLD_TAKEN.swap(true, Ordering::SeqCst) {
            return Ok(None);
        }
        let mut timeline = vk::SemaphoreTypeCreateInfo::default()
            .semaphore_type(vk::SemaphoreType::TIMELINE)
            .initial_value(0);
        let info = vk::SemaphoreCreateInfo::default().push_next(&mut timeline);
        // SAFETY: valid create info on a live device (timelineSemaphore is enabled).
        let semaphore =
            unsafe { device.raw.create_semaphore(&info, None) }.vk("vkCreateSemaphore")?;
        device.set_name(semaphore, &format!("frame {frame} held (test)"));
        let raw = device.raw.clone();
        let signaller = std::thread::spawn(move || {
            let (released, changed) = &RELEASED;
            let guard = released.lock().unwrap_or_else(|p| p.into_inner());
            let (guard, waited) = changed
                .wait_timeout_while(guard, HOLD_LIMIT, |released| !*released)
                .unwrap_or_else(|p| p.into_inner());
            drop(guard);
            match waited.timed_out() {
                true => announce(format_args!(
                    "fault: frame {frame} let go by its time limit"
                )),
                false => announce(format_args!("fault: frame {frame} let go")),
            }
            let signal = vk::SemaphoreSignalInfo::default()
                .semaphore(semaphore)
                .value(1);
            // SAFETY: the semaphore lives until this thread is joined ([`Hold::release`]).
            let _ = unsafe { raw.signal_semaphore(&signal) };
        });
        Ok(Some(Hold {
            frame,
            semaphore,
            signaller: Some(signaller),
            device: Arc::clone(device),
        }))
    }

    /// The wait to add to frame `frame`'s submission (1: the renderer's first), if it is
    /// the one held.
    pub fn wait_for(&self, frame: u64) -> Option<vk::SemaphoreSubmitInfo<'static>> {
        (frame == self.frame).then(|| {
            announce(format_args!("fault: frame {frame} held until let go"));
            vk::SemaphoreSubmitInfo::default()
                .semaphore(self.semaphore)
                .value(1)
                .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        })
    }

    /// Lets the frame go and waits until its semaphore is signalled (before its owner waits
    /// for the frame).
    pub fn release(&mut self) {
        release_held_frames();
        if let Some(thread) = self.signaller.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for Hold {
    fn drop(&mut self) {
        self.release();
        // SAFETY: signalled (above), and the owner drops the hold after the frame that waited
        // on it finished.
        unsafe { self.device.raw.destroy_semaphore(self.semaphore, None) };
    }
}

/// A fault's line on stdout, for the test that waits for it. Not through the core's `say!`:
/// the Vulkan layer is a crate below the core's, which depends on none of the workspace. A line
/// that cannot be written is dropped (a fault's only reader is the test that set it), and no
/// write panics.
fn announce(line: std::fmt::Arguments) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}").and_then(|()| out.flush());
}
