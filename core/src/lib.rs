//! specchio-core: the CPU half of specchio, a catadioptric (camera + mirror) sensor simulator.
//!
//! Everything here runs without a GPU, and this crate cannot reach one: its manifest names no
//! Vulkan crate and it depends on no other crate of the workspace. The renderer (`specchio`,
//! in `engine/`) builds on it and re-exports every module under the same name, so users write
//! `specchio::scene` as before. Module map (details in `docs/architecture.md`):
//! - [`scene`]: the TOML scene format, its validation, the resolved scene the renderer draws,
//!   its state at a time and its cameras;
//! - [`mirror`]: the mirror shapes (sphere and the central quadrics), one plug-in each;
//! - [`files`]: the one reader of input files (regular files only, each within a budget) and
//!   the record of what was read, by identity, which no output may replace;
//! - [`memory`]: the host-memory budget every command's estimate is checked against before
//!   it starts;
//! - [`image`]: the CPU image type shared by the renderer's readback, the reference and the
//!   metrics;
//! - [`lookup_registry`]: the mirror lookups, one entry each, which the scene and the
//!   renderer both read;
//! - [`trees`]: the wide BVHs both tracers build (obvhs), with their depth bound;
//! - [`reference`]: the exact CPU ray-traced mirror (two-level BVH, watertight triangles,
//!   analytic mirrors);
//! - [`bvh`]: the scene's two-level BVH in the layout the `bvh` lookup's shader traverses, and
//!   the same traversal on the CPU;
//! - [`sensor`]: the sensor's exact ray map (the non-central ground truth) and what derives
//!   from it;
//! - [`metrics`]: image-error metrics (RMSE, PSNR, relMSE, FLIP) and the FLIP heatmap;
//! - [`output`]: EXR, PNG and JSON files, written atomically;
//! - [`stdout`]: standard output that never panics (`say!`), below everything;
//! - [`text`]: numbers and times written for people;
//! - [`random`]: the one seeded random sequence (SplitMix64);
//! - [`watch`]: long CPU work reported row by row and stopped between parts.

pub mod bvh;
pub mod files;
pub mod image;
pub mod lookup_registry;
pub mod memory;
pub mod metrics;
pub mod mirror;
pub mod output;
pub mod random;
pub mod reference;
pub mod scene;
pub mod sensor;
pub mod stdout;
pub mod text;
pub mod trees;
pub mod warnings;
pub mod watch;
