//! specchio: a catadioptric (camera + spherical mirror) sensor simulator on Vulkan.
//!
//! Module map (details in `docs/architecture.md`):
//! - [`scene`]: the TOML scene format, its validation, the resolved scene the renderer draws,
//!   its state at a time and its cameras (no Vulkan);
//! - [`files`]: the one reader of input files (regular files only, each within a budget) and
//!   the record of what was read, by identity, which no output may replace;
//! - [`memory`]: the host-memory budget every command's estimate is checked against before
//!   it starts;
//! - [`image`]: the CPU image type shared by the renderer's readback, the reference and the
//!   metrics;
//! - [`vk`]: the Vulkan layer, one module per concept (instance, device, memory, image,
//!   descriptors, pipeline, commands, queries), each owning its handles;
//! - [`shaders`]: SPIR-V compiled from `shaders/` at build time;
//! - [`lookup_registry`]: the mirror lookups, one entry each, which the scene and the
//!   renderer both read;
//! - [`render`]: the renderer: GPU structs, the cube fill methods (plug-ins, see
//!   [`render::methods`]) and the observer / sensor views with the analytic mirror;
//! - [`reference`]: the exact CPU ray-traced mirror (BVH, watertight triangles, analytic sphere);
//! - [`bvh`]: the scene's two-level BVH in the layout the `bvh` lookup's shader traverses, and
//!   the same traversal on the CPU (no Vulkan);
//! - [`sensor`]: the sensor's exact ray map (the non-central ground truth) and what derives
//!   from it;
//! - [`metrics`]: image-error metrics (RMSE, PSNR, relMSE, FLIP) and the FLIP heatmap;
//! - [`output`]: EXR, PNG and JSON files, written atomically;
//! - [`process`]: what the programs on top share (signals, the validation verdict);
//! - [`stdout`]: standard output that never panics (`say!`), below everything;
//! - [`random`]: the one seeded random sequence (SplitMix64).

pub mod bvh;
pub mod files;
pub mod image;
pub mod lookup_registry;
pub mod memory;
pub mod metrics;
pub mod mirror;
pub mod output;
pub mod process;
pub mod random;
pub mod reference;
pub mod render;
pub mod scene;
pub mod sensor;
pub mod shaders;
pub mod stdout;
pub mod text;
pub mod trees;
pub mod vk;

/// The module arrows of docs/architecture.md, checked on the source.
#[cfg(test)]
mod module_arrows;
