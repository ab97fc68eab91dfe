//! The Vulkan loader: loaded once per process and never unloaded, with anchor instances that
//! keep every driver (and, once validation is asked for, the validation layer) loaded until
//! the process exits.
//!
//! Why: the loader closes a driver's library when the last instance that opened it is
//! destroyed (and opens and closes every driver around each pre-instance enumeration). A
//! driver that keeps per-thread state with a destructor in its library then leaves that
//! destructor pointing at unmapped code, and the next thread that used Vulkan and exits jumps
//! there. Measured on an NVIDIA H200 (driver 580.159.04, loader 1.3.239):
//! `tests/engine/sensor.rs` with eight test threads, where each test creates and destroys its
//! own instances, segfaulted at a thread's exit in 6 and in 7 of 8 runs (two tries; 0 of 8
//! with one thread, 0 of 8 with the driver preloaded, 0 of 16 with the anchor). The
//! backtrace ends in the C library's thread exit, calling an address no library maps. An
//! application with one instance for its whole life never meets this; our tests, the Python
//! package (a renderer per object, on any thread), Ray's workers and the viewer's device
//! changes create and destroy many.
//!
//! An anchor is an instance with no extensions that is never destroyed: while it lives, each
//! driver's library (and, for the anchor made once validation is asked for, the layer's)
//! stays open, so a later instance's destruction only lowers its count. Each costs one
//! `vkCreateInstance` per process and holds no device. The one thing it changes for the
//! caller: a process that forks after using Vulkan hands the child a loaded driver (use
//! `spawn`, not `fork`, for Python worker processes; docs/python.md).

use std::ffi::{c_char, CStr};
use std::sync::{Mutex, OnceLock};

use ash::vk;

use super::GpuError;

/// The Khronos validation layer, which `instance` enables and an anchor holds open.
pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// The loader library, loaded on first use. Statics are never dropped, so it stays open.
static ENTRY: OnceLock<Result<ash::Entry, String>> = OnceLock::new();

/// Which anchors exist. One that could not be made (no driver, no layer yet) is tried again
/// by the next caller; the caller's own `vkCreateInstance` reports why it failed.
static ANCHORS: Mutex<Anchors> = Mutex::new(Anchors {
    drivers: false,
    layer: false,
});

struct Anchors {
    /// The drivers' anchor: an instance with no layer.
    drivers: bool,
    /// The validation layer's: an instance with it, made once validation is asked for.
    layer: bool,
}

/// The process's loader, with the drivers held open, and the validation layer too once
/// `validation` is asked for (it has per-thread state of its own).
pub fn entry(validation: bool) -> Result<&'static ash::Entry, GpuError> {
    // SAFETY: loading libvulkan runs its initialisers; `OnceLock` runs this once, so no two
    // threads load it at the same time.
    let entry = ENTRY
        .get_or_init(|| unsafe { ash::Entry::load() }.map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| GpuError::Loader(e.clone()))?;
    // Nothing inside can panic with the lock held, but a poisoned lock holds valid flags.
    let mut anchors = ANCHORS.lock().unwrap_or_else(|e| e.into_inner());
    if !anchors.drivers {
        anchors.drivers = anchor(entry, &[]);
    }
    if validation && !anchors.layer {
        anchors.layer = anchor(entry, &[VALIDATION_LAYER.as_ptr()]);
    }
    Ok(entry)
}

/// Creates an instance with `layers` and never destroys it; whether that worked.
fn anchor(entry: &ash::Entry, layers: &[*const c_char]) -> bool {
    let app = vk::ApplicationInfo::default()
        .application_name(c"specchio: the loader's anchor")
        .api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(layers);
    // SAFETY: `info` points at locals that outlive the call. The instance is deliberately
    // never destroyed (see the module's comment); it owns no other object.
    unsafe { entry.create_instance(&info, None) }.is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every caller gets the one entry, loaded once.
    #[test]
    fn the_loader_is_loaded_once() {
        let (Ok(a), Ok(b)) = (entry(false), entry(false)) else {
            panic!("the Vulkan loader loads (scripts/setup.sh installs it)");
        };
        assert!(std::ptr::eq(a, b));
        assert!(
            ANCHORS.lock().unwrap().drivers,
            "the drivers' anchor exists"
        );
    }
}
