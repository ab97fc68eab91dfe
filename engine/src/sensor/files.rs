//! The sensor's per-pixel layers as EXR files with named channels: floats for rays and
//! ranges, 32-bit unsigned integers for object ids (an id is a name, not a quantity: no
//! filter or tone map should ever blend two of them).

use std::path::Path;

use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, Image, SmallVec, WritableImage};

use crate::output::{exr_error, OutputError, Transaction, EXR_ENCODING};

/// One channel's samples, row 0 at the top.
pub enum Samples {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

/// Writes `channels` (name, samples of `width * height`) as one EXR layer at `path`, staged in
/// `out`. The file lists the channels alphabetically, as EXR requires.
pub fn write_channels(
    out: &Transaction,
    path: &Path,
    (width, height): (u32, u32),
    channels: Vec<(&str, Samples)>,
) -> Result<(), OutputError> {
    let file = out.create(path)?;
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, samples)| {
            let flat = match samples {
                Samples::F32(v) => FlatSamples::F32(v),
                Samples::U32(v) => FlatSamples::U32(v),
            };
            AnyChannel::new(name, flat)
        })
        .collect();
    Image::from_encoded_channels(
        (width as usize, height as usize),
        EXR_ENCODING,
        AnyChannels::sort(list),
    )
    .write()
    .to_buffered(std::io::BufWriter::new(file))
    .map_err(|e| exr_error(path, e))
}

/// Reads every channel of the first layer of the EXR file at `path`, by name (for tests and
/// tools that check the files): floats as f32 (ids widened exactly only below 2^24, so ids
/// come back through [`read_u32_channel`]).
pub fn read_channels(path: &Path) -> Result<Vec<(String, FlatSamples)>, exr::error::Error> {
    let image = exr::prelude::read_all_flat_layers_from_file(path)?;
    let layer = image
        .layer_data
        .into_iter()
        .next()
        .ok_or_else(|| exr::error::Error::Invalid("no layer".into()))?;
    Ok(layer
        .channel_data
        .list
        .into_iter()
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect())
}

/// The samples of channel `name` of `channels` as f32, if it is a float channel.
pub fn f32_channel<'a>(channels: &'a [(String, FlatSamples)], name: &str) -> Option<&'a [f32]> {
    channels.iter().find_map(|(n, s)| match s {
        FlatSamples::F32(v) if n == name => Some(v.as_slice()),
        _ => None,
    })
}

/// The samples of channel `name` as u32, if it is an integer channel.
pub fn read_u32_channel<'a>(
    channels: &'a [(String, FlatSamples)],
    name: &str,
) -> Option<&'a [u32]> {
    channels.iter().find_map(|(n, s)| match s {
        FlatSamples::U32(v) if n == name => Some(v.as_slice()),
        _ => None,
    })
}
