//! SPIR-V compiled from `shaders/` at build time (see `engine/build.rs`).
//!
//! Each `shaders/NAME.STAGE.glsl` becomes a constant `NAME_STAGE: &[u32]`.
#![allow(clippy::unreadable_literal)]

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
