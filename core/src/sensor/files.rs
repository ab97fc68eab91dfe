//! The sensor's per-pixel layers as EXR files with named channels: floats for rays and
//! ranges, 32-bit unsigned integers for object ids (an id is a name, not a quantity: no
//! filter or tone map should ever blend two of them). The codec is `image::exr`'s; the
//! readers are re-exported here for the tools and tests that check the files. And the range
//! as integers (layer `range16`), for tools that take a 16-bit depth image.

pub use crate::image::exr::{
    f32_channel, float_channel, read_channels, u32_channel as read_u32_channel, Samples,
};

/// What a `range16` sample is.
pub const RANGE16_UNIT: &str = "whole millimetres (16-bit greyscale), rounded to nearest; 0 for \
     no return: off the mirror, or beyond 65.535 m";

/// The range in whole millimetres, 0 where there is none or it is beyond 65.535 m (ROS's
/// integer depth convention, REP-117: 0 is no return).
pub fn range_mm(range_m: &[f32]) -> Vec<u16> {
    (range_m.iter())
        .map(|&r| {
            let mm = (f64::from(r) * 1000.0).round();
            match mm >= 1.0 && mm <= f64::from(u16::MAX) {
                true => mm as u16,
                false => 0,
            }
        })
        .collect()
}
