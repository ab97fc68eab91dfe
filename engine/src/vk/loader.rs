//! The Vulkan loader: loaded once per process and never unloaded, with anchor instances that
//! keep every driver (and, once validation is asked for, the validation layer) loaded until
//! the process exits.
//!
//! Why: the loader closes a driver's library when the last instance that opened it is
//! destroyed (and opens and closes every driver around each pre-instance enumeration). A
//! driver that registered a per-thread destructor then leaves it pointing at unmapped code,
//! and the next thread that used Vulkan and exits jumps there. Measured on an NVIDIA H200
//! (driver 580.159.04, loader 1.3.239): `tests/engine/sensor.rs` with eight test threads,
//! where each test creates and destroys its own instances, segfaulted at a thread's exit in 6
//! of 8 runs (0 of 8 with one thread); the backtrace ends in the C library's thread exit,
//! calling an address no library maps. An application with one instance for its whole life
//! never meets this; our tests, the Python package (a renderer per object, on any thread),
//! Ray's workers and the viewer's device changes create and destroy many.
//!
//! An anchor is an instance with no extensions that is never destroyed: while it lives, each
//! driver's library (and the layer's) stays open, so a later instance's destruction only
//! lowers its count. It costs one `vkCreateInstance` per process and holds no device.

use std::ffi::CStr;
use std::sync::OnceLock;

use ash::vk;

use super::GpuError;

/// The loader library, loaded on first use. Statics are never dropped, so it stays open.
static ENTRY: OnceLock<Result<ash::Entry, String>> = OnceLock::new();

/// Whether the drivers' anchor was made (`false`: it could not be, which the caller's own
/// `vkCreateInstance` then reports with its reason).
static DRIVERS: OnceLock<bool> = OnceLock::new();

/// The same for the anchor that also holds `layer`, the validation layer, open.
static LAYER: OnceLock<bool> = OnceLock::new();

/// The process's loader, with the drivers held open, and `layer` too when it is `Some` (the
/// validation layer, which has per-thread state of its own).
pub fn entry(layer: Option<&CStr>) -> Result<&'static ash::Entry, GpuError> {
    // SAFETY: loading libvulkan runs its initialisers; `OnceLock` runs this once, so no two
    // threads load it at the same time.
    let entry = ENTRY
        .get_or_init(|| unsafe { ash::Entry::load() }.map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| GpuError::Loader(e.clone()))?;
    DRIVERS.get_or_init(|| anchor(entry, &[]));
    if let Some(layer) = layer {
        LAYER.get_or_init(|| anchor(entry, &[layer.as_ptr()]));
    }
    Ok(entry)
}

/// Creates an instance with `layers` and never destroys it; whether that worked.
fn anchor(entry: &ash::Entry, layers: &[*const i8]) -> bool {
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
        let (Ok(a), Ok(b)) = (entry(None), entry(None)) else {
            panic!("the Vulkan loader loads (scripts/setup.sh installs it)");
        };
        assert!(std::ptr::eq(a, b));
        assert_eq!(DRIVERS.get(), Some(&true), "the drivers' anchor exists");
    }
}
