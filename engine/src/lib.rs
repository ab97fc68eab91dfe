//! specchio: a catadioptric (camera + mirror) sensor simulator on Vulkan.
//!
//! The CPU half (scene, mirror shapes, reference, sensor models, metrics, files) is the crate
//! `specchio-core` (`core/`), re-exported here module by module, so that `specchio::scene` is
//! the one name users and the renderer write. This crate adds what needs a GPU. Module map
//! (details in `docs/architecture.md`):
//! - [`vk`]: the Vulkan layer, one module per concept (instance, device, memory, image,
//!   descriptors, pipeline, commands, queries), each owning its handles: the crate
//!   `specchio-vk` (`vk/`), which knows nothing of the scene or the renderer;
//! - [`shaders`]: SPIR-V compiled from `shaders/` at build time;
//! - [`render`]: the renderer: GPU structs, the cube fill methods (plug-ins, see
//!   [`render::methods`]) and the observer / sensor views with the analytic mirror;
//! - [`process`]: what the programs on top share (signals, the validation verdict).

pub use specchio_core::{
    bvh, files, image, lookup_registry, memory, metrics, mirror, output, random, reference, scene,
    sensor, stdout, text, trees, warnings, watch,
};
pub use specchio_core::{say, say_err, say_part};
pub use specchio_vk as vk;

pub mod process;
pub mod render;
pub mod shaders;

/// The module arrows of docs/architecture.md, checked on the source.
#[cfg(test)]
mod module_arrows;

/// The crates' arrows and shared features, checked on their manifests.
#[cfg(test)]
mod crate_arrows;
