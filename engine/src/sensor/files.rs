//! The sensor's per-pixel layers as EXR files with named channels: floats for rays and
//! ranges, 32-bit unsigned integers for object ids (an id is a name, not a quantity: no
//! filter or tone map should ever blend two of them). The codec is `image::exr`'s; the
//! readers are re-exported here for the tools and tests that check the files.

use std::path::Path;

use crate::image::exr;
use crate::output::{exr_error, OutputError, Transaction};

pub use crate::image::exr::{f32_channel, read_channels, u32_channel as read_u32_channel, Samples};

/// Writes `channels` (name, samples of `width * height`) as one EXR layer at `path`, staged in
/// `out`. The file lists the channels alphabetically, as EXR requires.
pub fn write_channels(
    out: &Transaction,
    path: &Path,
    size: (u32, u32),
    channels: Vec<(&str, Samples)>,
) -> Result<(), OutputError> {
    let file = out.create(path)?;
    exr::encode_channels(std::io::BufWriter::new(file), size, channels)
        .map_err(|e| exr_error(path, e))
}
