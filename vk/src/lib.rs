//! The Vulkan layer: one module per Vulkan concept, each owning its handles.
//!
//! Ownership is the teardown order. Every resource ([`memory::Buffer`], [`image::Image`],
//! [`pipeline::Pipeline`], ...) holds an `Arc<device::Device>`, so the device (and the
//! allocator inside it) outlives everything created from it, and the device holds an
//! `Arc<instance::Instance>`. Dropping the last handle destroys the object; nothing is
//! destroyed by hand. What the GPU may still use is dropped only after the fence of the last
//! submission that used it (see `commands::Submitter`): the renderer keeps what it replaces
//! while frames are in flight until they finish (its `render/retired.rs`), and the live
//! viewer hands such objects to `frames::FrameRing::defer`, the deletion queue.
//!
//! One thing outlives every handle on purpose: the loader ([`loader`]), loaded once per
//! process with an instance that is never destroyed, so that no driver's library is closed
//! while a thread that used it still has per-thread state in it (a crash at that thread's
//! exit, measured on NVIDIA's driver).

pub mod acceleration;
pub mod commands;
pub mod descriptors;
pub mod device;
pub mod fault;
pub mod features;
pub mod frames;
pub mod image;
pub mod instance;
pub mod loader;
pub mod memory;
pub mod physical;
pub mod pipeline;
pub mod queries;
pub mod surface;
pub mod swapchain;
pub mod uploads;
#[cfg(test)]
mod validation_tests;

use ash::vk;

/// Errors from the GPU layer. `anyhow` is for the CLI; the engine returns these.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}; install `libvulkan1` and a driver such as `mesa-vulkan-drivers`")]
    Loader(String),
    #[error("{call} failed: {result}")]
    Vk {
        call: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation for `{name}` failed: {source}")]
    Alloc {
        name: String,
        source: gpu_allocator::AllocationError,
    },
    #[error("no usable Vulkan device:\n{0}")]
    NoDevice(String),
    #[error("the Khronos validation layer was requested but is not installed (Debian: `apt-get install vulkan-validationlayers`)")]
    NoValidationLayer,
    #[error("the installed Khronos validation layer does not offer VK_EXT_validation_features, which turns on its synchronization checks; install a newer `vulkan-validationlayers`")]
    NoSynchronizationValidation,
    /// A resource larger than the device can hold, found before anything was allocated.
    #[error("too large for this device: {0}")]
    TooLarge(String),
    /// The host-memory budget (`SPECCHIO_MEMORY_BUDGET`) refused the run (an estimate over
    /// it, or a budget that is no size), said as the budget says it: not the device's limit.
    #[error("{0}")]
    OverBudget(String),
    #[error("unsupported: {0}")]
    Unsupported(String),
}

/// Attaches the name of the failing Vulkan call to a raw `vk::Result`.
pub trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T, GpuError>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T, GpuError> {
        self.map_err(|result| GpuError::Vk { call, result })
    }
}
