//! The sensor's per-pixel layers as EXR files with named channels: floats for rays and
//! ranges, 32-bit unsigned integers for object ids (an id is a name, not a quantity: no
//! filter or tone map should ever blend two of them). The codec is `image::exr`'s; the
//! readers are re-exported here for the tools and tests that check the files.

pub use crate::image::exr::{f32_channel, read_channels, u32_channel as read_u32_channel, Samples};
