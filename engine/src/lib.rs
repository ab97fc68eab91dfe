//! specchio: a catadioptric (camera + spherical mirror) sensor simulator on Vulkan.
//!
//! Module map (see `docs/architecture.md`):
//! - [`scene`]: the TOML scene format and the validated scene the renderer draws.

pub mod output;
pub mod render;
pub mod scene;
pub mod shaders;
pub mod vk;
