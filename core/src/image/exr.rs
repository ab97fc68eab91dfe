//! OpenEXR: linear RGBA images (the views, the cube faces, the reference) and layers of named
//! channels (the sensor's rays, ranges and ids), written byte-identically from run to run.

use std::io::{Seek, Write};
use std::path::Path;

use ::exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, LineOrder, SmallVec, SpecificChannels,
    Vec2, WritableImage,
};

use super::RgbaImage;

pub use ::exr::error::Error;
pub use ::exr::prelude::FlatSamples as Channel;

/// The layout: ZIP in blocks of 16 scan lines, the chunks in increasing order. ZIP, not the
/// crate's default RLE: a dataset frame of the thesis room at 512² is 7.6 MB with it and 25 MB
/// with RLE (the panoramas 1.1 MB each instead of 6.6 and 9.0; the colour 0.12 MB instead of
/// 3.7), and every OpenEXR reader reads it. The increasing order, because with the crate's
/// unspecified one it writes chunks as its parallel compressors finish, so the same image gave
/// different bytes from run to run; a fixed order makes the files byte-identical, so checksums
/// can compare them.
pub const ENCODING: Encoding = Encoding {
    line_order: LineOrder::Increasing,
    ..Encoding::SMALL_LOSSLESS
};

/// Linear RGBA, 32-bit float.
pub fn encode_rgba(to: impl Write + Seek, image: &RgbaImage) -> Result<(), Error> {
    encode_rgba_watched(to, image, |_| {})
}

/// [`encode_rgba`], its progress (0 to 1) said to `progress` as its chunks are written (an
/// 8192² image encodes for seconds); the same bytes.
pub fn encode_rgba_watched(
    to: impl Write + Seek,
    image: &RgbaImage,
    progress: impl FnMut(f64),
) -> Result<(), Error> {
    let w = image.width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y)| {
        let p: [f32; 4] = image.pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    });
    Image::from_encoded_channels((w, image.height as usize), ENCODING, channels)
        .write()
        .on_progress(progress)
        .to_buffered(to)
}

/// Linear RGBA, 16-bit ("half") float: for an image resampled from one the GPU renders in
/// half floats (the views are RGBA16F), where 32 bits would store rounding noise at twice the
/// size. Half floats keep 11 significant bits (3 decimal digits) up to 65504.
pub fn encode_rgba_half(to: impl Write + Seek, image: &RgbaImage) -> Result<(), Error> {
    use ::exr::prelude::f16;
    let w = image.width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y)| {
        let p: [f32; 4] = image.pixels[y * w + x];
        (
            f16::from_f32(p[0]),
            f16::from_f32(p[1]),
            f16::from_f32(p[2]),
            f16::from_f32(p[3]),
        )
    });
    Image::from_encoded_channels((w, image.height as usize), ENCODING, channels)
        .write()
        .to_buffered(to)
}

/// One channel's samples, row 0 at the top.
pub enum Samples {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

/// `channels` (name, samples of `width * height`) as one layer, listed alphabetically as EXR
/// requires.
pub fn encode_channels(
    to: impl Write + Seek,
    (width, height): (u32, u32),
    channels: Vec<(&str, Samples)>,
) -> Result<(), Error> {
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
    let size = (width as usize, height as usize);
    Image::from_encoded_channels(size, ENCODING, AnyChannels::sort(list))
        .write()
        .to_buffered(to)
}

/// The size of every layer the header declares, from the header alone (before any pixel
/// memory is allocated: a reader checks them against its limits first).
pub fn layer_sizes(bytes: &[u8]) -> Result<Vec<(usize, usize)>, Error> {
    let meta = read_meta(bytes)?;
    Ok(meta
        .headers
        .iter()
        .map(|h| (h.layer_size.0, h.layer_size.1))
        .collect())
}

/// The size of the layer [`decode_rgba`] decodes, from the header alone: the first whose
/// channels include R, G and B (a file's layers may differ in size).
pub fn rgba_layer_size(bytes: &[u8]) -> Option<(usize, usize)> {
    rgba_header(&read_meta(bytes).ok()?).map(|h| (h.layer_size.0, h.layer_size.1))
}

/// The header of the layer [`decode_rgba`] decodes: the first whose channels include R, G
/// and B.
fn rgba_header(meta: &::exr::meta::MetaData) -> Option<&::exr::meta::header::Header> {
    let has = |h: &::exr::meta::header::Header, name: &str| {
        (h.channels.list.iter()).any(|c| c.name.to_string() == name)
    };
    (meta.headers.iter()).find(|h| ["R", "G", "B"].iter().all(|c| has(h, c)))
}

/// The header, refused where the crate would accept what the format does not: a data or
/// display window whose corners are inverted, an attribute given twice, a channel named twice
/// (`exr_header.rs`).
fn read_meta(bytes: &[u8]) -> Result<::exr::meta::MetaData, Error> {
    if let Some(why) = super::exr_header::header_fault(bytes) {
        return Err(Error::Invalid(why.into()));
    }
    ::exr::meta::MetaData::read_from_buffered(bytes, false)
}

/// [`read_meta`] of a whole file's `bytes`, also refusing a multi-part file cut short in a
/// part (`exr_header::cut_short`): the crate reads only the chunks of the part it decodes.
/// What decodes pixels reads the header this way; what sizes a file from its first bytes
/// cannot.
fn read_whole_meta(bytes: &[u8]) -> Result<::exr::meta::MetaData, Error> {
    use ::exr::meta::BlockDescription;
    let meta = read_meta(bytes)?;
    let parts: Vec<(usize, Option<usize>)> = (meta.headers.iter())
        .map(|h| {
            let size_field = match h.blocks {
                _ if h.deep => None,
                BlockDescription::ScanLines => Some(4),
                BlockDescription::Tiles(_) => Some(16),
            };
            (h.chunk_count, size_field)
        })
        .collect();
    match super::exr_header::cut_short(bytes, &parts) {
        Some(why) => Err(Error::Invalid(why.into())),
        None => Ok(meta),
    }
}

/// Where the colour layer [`decode_rgba`] decodes starts (its data window's corner), from the
/// header alone: specchio writes (0, 0), other tools may crop.
pub fn rgba_layer_origin(bytes: &[u8]) -> Option<(i32, i32)> {
    let position = rgba_header(&read_meta(bytes).ok()?)?
        .own_attributes
        .layer_position;
    Some((position.0, position.1))
}

/// The most channels a layer may have for [`decode_channels`] (the sensor's ray map has 7).
pub const MAX_CHANNELS: usize = 64;
/// The most bytes [`decode_channels`] decodes a layer to: an RGBA float image of 16384 px a
/// side, as the metrics read (a small compressed file may declare far more).
pub const MAX_DECODED_BYTES: u64 = 16384 * 16384 * 16;

/// One layer of an EXR file: its size (width, height) and its channels by name, each of
/// width × height samples, rows from the top.
pub struct Layer {
    pub size: (usize, usize),
    pub channels: Vec<(String, Channel)>,
}

/// The first layer, every channel of it, from bytes whose header was checked
/// ([`layer_sizes`]); a layer of more than [`MAX_CHANNELS`] channels is refused from the
/// header, before any pixel memory is allocated.
pub fn decode_channels(bytes: &[u8]) -> Result<Layer, Error> {
    let meta = read_whole_meta(bytes)?;
    for h in &meta.headers {
        let channels = h.channels.list.len();
        let samples = (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64);
        // Decoded as 4 bytes a sample, whatever the file's compression.
        let decoded = samples.saturating_mul(channels as u64).saturating_mul(4);
        if channels > MAX_CHANNELS || decoded > MAX_DECODED_BYTES {
            return Err(Error::Invalid(
                format!(
                    "{channels} channels of {}x{} decode to {decoded} bytes; at most \
                     {MAX_CHANNELS} channels and {MAX_DECODED_BYTES} bytes are read",
                    h.layer_size.0, h.layer_size.1
                )
                .into(),
            ));
        }
    }
    use ::exr::prelude::{ReadChannels as _, ReadLayers as _};
    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))?;
    let size = (image.layer_data.size.0, image.layer_data.size.1);
    let channels = (image.layer_data.channel_data.list.into_iter())
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect();
    Ok(Layer { size, channels })
}

/// The channel names of each layer, from the header alone (for a message about a file that
/// holds no colour layer).
pub fn channel_names(bytes: &[u8]) -> Result<Vec<String>, Error> {
    let meta = read_meta(bytes)?;
    Ok((meta.headers.iter())
        .flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string()))
        .collect())
}

pub use super::exr_header::has_magic;

/// The first RGBA layer as 32-bit float (alpha 1 when the file has none).
pub fn decode_rgba(bytes: &[u8]) -> Result<RgbaImage, Error> {
    decode_rgba_watched(bytes, |_| {}, &|| false)
}

/// [`decode_rgba`], saying its progress (0 to 1) to `progress` as it goes, and ended at the
/// next chunk it reads once `stop` says so (an error [`is_stopped`] tells): an 8192² image
/// decodes for seconds.
pub fn decode_rgba_watched(
    bytes: &[u8],
    progress: impl FnMut(f64),
    stop: &dyn Fn() -> bool,
) -> Result<RgbaImage, Error> {
    use ::exr::prelude::{ReadChannels as _, ReadLayers as _};
    read_whole_meta(bytes)?;
    let reader = Stoppable {
        inner: std::io::Cursor::new(bytes),
        stop,
    };
    let read = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res: ::exr::math::Vec2<usize>, _: &::exr::prelude::RgbaChannels| RgbaImage {
                width: res.width() as u32,
                height: res.height() as u32,
                pixels: vec![[0.0; 4]; res.width() * res.height()],
            },
            |img: &mut RgbaImage, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                let i = pos.y() * img.width as usize + pos.x();
                img.pixels[i] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .on_progress(progress)
        .from_buffered(reader)?;
    Ok(read.layer_data.channel_data.pixels)
}

/// Bytes read until `stop` says otherwise: then each read fails, and the decoder with it.
struct Stoppable<'a> {
    inner: std::io::Cursor<&'a [u8]>,
    stop: &'a dyn Fn() -> bool,
}

impl std::io::Read for Stoppable<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if (self.stop)() {
            // Not `Interrupted`: `read_exact` retries that for ever.
            return Err(std::io::Error::other(DecodeStopped));
        }
        self.inner.read(buf)
    }
}

impl std::io::Seek for Stoppable<'_> {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(to)
    }
}

/// The error a stopped reader gives.
#[derive(Debug)]
struct DecodeStopped;

impl std::fmt::Display for DecodeStopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stopped")
    }
}

impl std::error::Error for DecodeStopped {}

/// Whether `e` is the error of a decoding that its `stop` ended.
pub fn is_stopped(e: &Error) -> bool {
    matches!(e, Error::Io(io) if io.get_ref().is_some_and(|e| e.is::<DecodeStopped>()))
}

/// Every channel of the first layer of the file at `path`, by name (for tests and tools that
/// check the files): floats as f32, ids as u32 (see [`u32_channel`]).
pub fn read_channels(path: &Path) -> Result<Vec<(String, Channel)>, Error> {
    use ::exr::prelude::{ReadChannels as _, ReadLayers as _};
    let bytes = std::fs::read(path)?;
    read_whole_meta(&bytes)?;
    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))?;
    let layer =
        (image.layer_data.into_iter().next()).ok_or_else(|| Error::Invalid("no layer".into()))?;
    Ok((layer.channel_data.list.into_iter())
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect())
}

/// The samples of channel `name` as f32, if it is a float channel.
pub fn f32_channel<'a>(channels: &'a [(String, Channel)], name: &str) -> Option<&'a [f32]> {
    channels.iter().find_map(|(n, s)| match s {
        FlatSamples::F32(v) if n == name => Some(v.as_slice()),
        _ => None,
    })
}

/// The samples of channel `name` as f32, if it is a float channel of either width (a
/// panorama's are half floats).
pub fn float_channel(channels: &[(String, Channel)], name: &str) -> Option<Vec<f32>> {
    channels.iter().find_map(|(n, s)| match s {
        FlatSamples::F32(v) if n == name => Some(v.clone()),
        FlatSamples::F16(v) if n == name => Some(v.iter().map(|h| h.to_f32()).collect()),
        _ => None,
    })
}

/// The samples of channel `name` as u32, if it is an integer channel (ids: exact, where a
/// float would round them above 2^24).
pub fn u32_channel<'a>(channels: &'a [(String, Channel)], name: &str) -> Option<&'a [u32]> {
    channels.iter().find_map(|(n, s)| match s {
        FlatSamples::U32(v) if n == name => Some(v.as_slice()),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ::exr::prelude::{ImageAttributes, IntegerBounds, Layer, LayerAttributes};

    /// The size read from the header is the colour layer's, the one the decoder reads, where
    /// a file's layers differ in size: a small layer of other channels first.
    #[test]
    fn the_colour_layers_size_is_read_from_the_header() {
        let depth = Layer::new(
            (8, 8),
            LayerAttributes::named("depth"),
            ENCODING,
            AnyChannels::sort(SmallVec::from_vec(vec![AnyChannel::new(
                "Z",
                FlatSamples::F32(vec![1.0; 64]),
            )])),
        );
        let colour = Layer::new(
            (48, 20),
            LayerAttributes::named("colour"),
            ENCODING,
            AnyChannels::sort(SmallVec::from_vec(
                ["R", "G", "B", "A"]
                    .iter()
                    .enumerate()
                    .map(|(i, name)| {
                        let v = [0.5, 0.25, 0.125, 1.0][i];
                        AnyChannel::new(*name, FlatSamples::F32(vec![v; 48 * 20]))
                    })
                    .collect(),
            )),
        );
        let window = IntegerBounds::from_dimensions((48, 20));
        let image = Image::from_layers(ImageAttributes::new(window), vec![depth, colour]);
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write().to_buffered(&mut bytes).unwrap();
        let bytes = bytes.into_inner();
        assert_eq!(layer_sizes(&bytes).unwrap(), [(8, 8), (48, 20)]);
        assert_eq!(rgba_layer_size(&bytes), Some((48, 20)));
        let decoded = decode_rgba(&bytes).unwrap();
        assert_eq!((decoded.width, decoded.height), (48, 20));
    }
}
