//! PNG: the 8-bit sRGB previews of linear images (and colour maps) the commands write, and
//! the textures and masks they read, decoded to 8-bit RGBA.

use std::io::{Cursor, Write};

use super::RgbaImage;

pub use ::png::{DecodingError, EncodingError};

/// The linear-to-sRGB transfer function (IEC 61966-2-1), input clamped to [0, 1], NaN as 0.
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear image's colour as 8-bit sRGB bytes, 3 per pixel (alpha dropped).
pub fn srgb8_rgb(image: &RgbaImage) -> Vec<u8> {
    (image.pixels.iter())
        .flat_map(|p| [p[0], p[1], p[2]])
        .map(|v| (linear_to_srgb(v) * 255.0).round() as u8)
        .collect()
}

/// An 8-bit sRGB RGB PNG from bytes already encoded (3 per pixel, rows top to bottom).
pub fn encode_rgb8(
    to: impl Write,
    width: u32,
    height: u32,
    rgb8: &[u8],
) -> Result<(), EncodingError> {
    let mut writer = rgb8_encoder(to, width, height).write_header()?;
    writer.write_image_data(rgb8)?;
    writer.finish()
}

/// An encoder of an 8-bit sRGB RGB image of `width` x `height`.
fn rgb8_encoder<W: Write>(to: W, width: u32, height: u32) -> ::png::Encoder<'static, W> {
    let mut encoder = ::png::Encoder::new(to, width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    encoder
}

/// The rows [`encode_rgb8_watched`] hands the encoder at a time: some 6 MB of an 8192² image.
const ROWS_A_BAND: usize = 256;

/// [`encode_rgb8`], its rows counted to `rows_done` as the encoder takes them, a band of
/// [`ROWS_A_BAND`] at a time: an 8192² image of noise encodes for some 5 s (a heatmap of a
/// noisy comparison comes near that).
pub fn encode_rgb8_watched(
    to: impl Write,
    width: u32,
    height: u32,
    rgb8: &[u8],
    mut rows_done: impl FnMut(u32),
) -> Result<(), EncodingError> {
    let mut writer = rgb8_encoder(to, width, height).write_header()?;
    // IDAT chunks of a megabyte, not the stream's default 4 KiB (some 10,000 chunk headers
    // in a noisy 4096² image).
    let mut stream = writer.stream_writer_with_size(1 << 20)?;
    let row_bytes = (width as usize * 3).max(1);
    for band in rgb8.chunks(row_bytes * ROWS_A_BAND) {
        stream.write_all(band)?;
        rows_done((band.len() / row_bytes) as u32);
    }
    stream.finish()?;
    // The end chunk written here, its error returned (a drop would write it and lose one).
    writer.finish()
}

/// A 16-bit greyscale PNG of `values` (rows top to bottom): integers a reader takes back
/// exactly, such as millimetres of range.
pub fn encode_gray16(
    to: impl Write,
    (width, height): (u32, u32),
    values: &[u16],
) -> Result<(), EncodingError> {
    let mut encoder = ::png::Encoder::new(to, width, height);
    encoder.set_color(::png::ColorType::Grayscale);
    encoder.set_depth(::png::BitDepth::Sixteen);
    let mut writer = encoder.write_header()?;
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    writer.write_image_data(&bytes)?;
    writer.finish()
}

/// An RGB PNG of a camera's codes: `samples` 8- or 16-bit (big-endian, 3 per pixel, rows top
/// to bottom), of which the top `significant` bits carry the code (an `sBIT` chunk says so,
/// so that a reader can shift them back). No colour space is claimed: the codes are the
/// camera's, through whatever response curve it has.
pub fn encode_rgb_samples(
    to: impl Write,
    (width, height): (u32, u32),
    samples: &[u8],
    (sample_bits, significant): (u8, u8),
) -> Result<(), EncodingError> {
    let mut encoder = ::png::Encoder::new(to, width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(match sample_bits {
        8 => ::png::BitDepth::Eight,
        _ => ::png::BitDepth::Sixteen,
    });
    let mut writer = encoder.write_header()?;
    // sBIT comes before the image data (PNG 1.2, 4.2.6): one byte per colour channel.
    writer.write_chunk(::png::chunk::sBIT, &[significant; 3])?;
    writer.write_image_data(samples)?;
    writer.finish()
}

/// A PNG's size from its header alone (no pixel is decoded): for budgets checked before the
/// decoding's memory is taken.
pub fn dimensions(bytes: &[u8]) -> Result<(u32, u32), String> {
    let decoder = ::png::Decoder::new(Cursor::new(bytes));
    let reader = decoder
        .read_info()
        .map_err(|e| format!("not a valid PNG: {e}"))?;
    Ok((reader.info().width, reader.info().height))
}

/// A PNG of any colour type and bit depth decoded to 8-bit RGBA, rows top to bottom, colour as
/// stored (sRGB-encoded): palette and grayscale expanded, 16-bit channels reduced to 8 bits,
/// missing alpha 255. Each side must be in 1..=`max_side`, checked from the header before any
/// pixel memory is allocated. The error is a message for the caller to place.
pub fn decode_rgba8(bytes: &[u8], max_side: u32) -> Result<(u32, u32, Vec<u8>), String> {
    let bad = |e: DecodingError| format!("not a valid PNG: {e}");
    let mut decoder = ::png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(::png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(bad)?;
    let (width, height) = (reader.info().width, reader.info().height);
    if width == 0 || height == 0 || width > max_side || height > max_side {
        return Err(format!(
            "image is {width}x{height}; each side must be in 1..={max_side}"
        ));
    }
    let size = (reader.output_buffer_size()).ok_or("image too large for this machine")?;
    let mut buf = vec![0u8; size];
    let frame = reader.next_frame(&mut buf).map_err(bad)?;
    let texels = width as usize * height as usize;
    let packed = frame.line_size == 4 * width as usize && buf.len() >= 4 * texels;
    if frame.color_type == ::png::ColorType::Rgba
        && frame.bit_depth == ::png::BitDepth::Eight
        && packed
    {
        // Already RGBA8, rows packed: the decoder's buffer is the texture (no second copy of
        // an 8192² image).
        buf.truncate(4 * texels);
        return Ok((width, height, buf));
    }
    let rgba8 = expand(&buf, &frame, width, height)?;
    Ok((width, height, rgba8))
}

/// The decoded frame as RGBA8, one texel per pixel.
fn expand(
    buf: &[u8],
    frame: &::png::OutputInfo,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, String> {
    if frame.bit_depth != ::png::BitDepth::Eight {
        return Err(format!(
            "unexpected bit depth {:?} after conversion",
            frame.bit_depth
        ));
    }
    let channels = match frame.color_type {
        ::png::ColorType::Grayscale => 1,
        ::png::ColorType::GrayscaleAlpha => 2,
        ::png::ColorType::Rgb => 3,
        ::png::ColorType::Rgba => 4,
        ::png::ColorType::Indexed => return Err("palette image was not expanded".into()),
    };
    let texels = width as usize * height as usize;
    let mut rgba8 = Vec::with_capacity(texels * 4);
    for row in buf.chunks(frame.line_size.max(1)).take(height as usize) {
        for px in row.chunks_exact(channels).take(width as usize) {
            let texel = match *px {
                [g] => [g, g, g, 255],
                [g, a] => [g, g, g, a],
                [r, g, b] => [r, g, b, 255],
                [r, g, b, a] => [r, g, b, a],
                _ => [0, 0, 0, 255],
            };
            rgba8.extend_from_slice(&texel);
        }
    }
    if rgba8.len() != texels * 4 {
        return Err("image data is shorter than its header says".into());
    }
    Ok(rgba8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_matches_the_standard() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        // 18 % grey is about 46 % in sRGB.
        assert!((linear_to_srgb(0.18) - 0.4614).abs() < 1e-3);
        assert_eq!(linear_to_srgb(f32::NAN), 0.0);
    }

    #[test]
    fn what_is_encoded_decodes_to_the_same_bytes() {
        let rgb = [255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 20, 30];
        let mut file = Vec::new();
        encode_rgb8(&mut file, 2, 2, &rgb).unwrap();
        let (w, h, rgba) = decode_rgba8(&file, 2).unwrap();
        assert_eq!((w, h), (2, 2));
        let back: Vec<u8> = rgba.chunks(4).flat_map(|t| [t[0], t[1], t[2]]).collect();
        assert_eq!(back, rgb);
        assert!(rgba.chunks(4).all(|t| t[3] == 255));
        let too_big = decode_rgba8(&file, 1).unwrap_err();
        assert!(too_big.contains("1..=1"), "{too_big}");
    }

    /// Encoded in bands, with every row counted once: the same pixels back.
    #[test]
    fn a_watched_encoding_counts_its_rows_and_decodes_to_the_same_bytes() {
        let (w, h) = (3u32, 600u32);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 251) as u8).collect();
        let (mut file, mut bands) = (Vec::new(), Vec::new());
        encode_rgb8_watched(&mut file, w, h, &rgb, |rows| bands.push(rows)).unwrap();
        assert_eq!(bands, [256, 256, 88]);
        let (_, _, rgba) = decode_rgba8(&file, 600).unwrap();
        let back: Vec<u8> = rgba.chunks(4).flat_map(|t| [t[0], t[1], t[2]]).collect();
        assert_eq!(back, rgb);
    }
}
