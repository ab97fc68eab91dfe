//! specchio: a catadioptric (camera + spherical mirror) sensor simulator on Vulkan.
//!
//! Module map (details in `docs/architecture.md`):
//! - [`scene`]: the TOML scene format, its validation, and the resolved scene the renderer draws;
//! - [`vk`]: the Vulkan layer, one module per concept (instance, device, memory, image,
//!   descriptors, pipeline, commands, queries), each owning its handles;
//! - [`shaders`]: SPIR-V compiled from `shaders/` at build time;
//! - [`render`]: cameras and cube-face conventions, GPU structs, the six-pass cube fill and the
//!   observer / sensor views with the analytic mirror;
//! - [`reference`]: the exact CPU ray-traced mirror (BVH, watertight triangles, analytic sphere);
//! - [`metrics`]: image-error metrics (RMSE, PSNR, relMSE, FLIP) and the FLIP heatmap;
//! - [`output`]: EXR, PNG and JSON files, written atomically.

pub mod metrics;
pub mod output;
pub mod reference;
pub mod render;
pub mod scene;
pub mod shaders;
pub mod vk;
