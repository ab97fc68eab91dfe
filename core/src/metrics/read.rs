//! Reading a comparison's images: EXR files through the loaders' one reader, checked against
//! the limits from their headers before any pixel is decoded, decoded with their rows
//! reported to a [`Watch`] (an 8192² image decodes for seconds) and stopped at its word; masks
//! from EXR or PNG.

use std::path::Path;

use super::{check_size, same_size, same_size_as_mask, Mask, MetricsError, MASK_THRESHOLD};
use crate::files::{read_regular_file, read_regular_file_head, FileError};
use crate::image::{exr, RgbaImage};
use crate::scene::TextureData;
use crate::watch::{Unwatched, Watch};

/// The first RGBA layer of an OpenEXR file, as 32-bit float (alpha 1 when the file has none).
pub fn read_exr(path: &Path) -> Result<RgbaImage, MetricsError> {
    decode(path, &read_checked_exr(path)?, &Unwatched)
}

/// The colour image of an EXR file's `bytes` (read from `path`), its rows reported to
/// `watch` as they are decoded; [`MetricsError::Stopped`] when `watch` stops it.
fn decode(path: &Path, bytes: &[u8], watch: &dyn Watch) -> Result<RgbaImage, MetricsError> {
    let rows = header_size(bytes).map_or(0, |(_, h)| u64::from(h));
    let progress = crate::watch::rows_of_fraction(watch, rows);
    let stop = || watch.stop();
    exr::decode_rgba_watched(bytes, progress, &stop).map_err(|e| match exr::channel_names(bytes) {
        _ if exr::is_stopped(&e) => MetricsError::Stopped,
        // A readable file without colour: one of the sensor's single-quantity layers.
        Ok(names) if !["R", "G", "B"].iter().all(|c| names.iter().any(|n| n == c)) => {
            MetricsError::Read {
                path: path.to_owned(),
                message: format!(
                    "holds no colour image (channels R, G, B) but {}: this reads colour \
                     images; a layer such as sensor.range.exr is read by channel name \
                     (specchio.read_exr in Python)",
                    match names.is_empty() {
                        true => "no channel at all".to_owned(),
                        false => names.join(", "),
                    }
                ),
            }
        }
        _ => exr_error(path, e),
    })
}

/// Every channel of the first layer of an OpenEXR file by name, with the layer's size
/// (width, height), read with the same limits as [`read_exr`] (the Python package's
/// `read_exr`: the sensor's layers by channel name).
pub fn read_exr_channels(path: &Path) -> Result<exr::Layer, MetricsError> {
    let bytes = read_checked_exr(path)?;
    exr::decode_channels(&bytes).map_err(|e| exr_error(path, e))
}

/// An OpenEXR file's bytes, in one read through the loaders' regular-file reader (a FIFO
/// would block, a folder fail late), its header checked against the limits; the decoding
/// works on these bytes.
fn read_checked_exr(path: &Path) -> Result<Vec<u8>, MetricsError> {
    let bytes = read_regular_file(path, MAX_INPUT_FILE_BYTES).map_err(|e| file_error(path, e))?;
    check_exr_head(path, &bytes)?;
    Ok(bytes)
}

/// The bytes of an EXR read for its header before the whole file: specchio's headers are a
/// few hundred bytes, a large multi-part file's some kilobytes.
const HEAD_BYTES: u64 = 1 << 20;

/// The size of `path`'s colour layer from its first [`HEAD_BYTES`] alone, checked as
/// [`read_checked_exr`] checks the whole file (an uncompressed 8192² image is a gigabyte, some
/// seconds to read from a cold disk); none where its header reaches past them, or it has no
/// colour layer (the whole file's reading says what is wrong then).
fn exr_head_size(path: &Path) -> Result<Option<(u32, u32)>, MetricsError> {
    let head = read_regular_file_head(path, MAX_INPUT_FILE_BYTES, HEAD_BYTES)
        .map_err(|e| file_error(path, e))?;
    size_from_head(path, &head, head.len() as u64 == HEAD_BYTES)
}

/// [`exr_head_size`] of a file's first bytes `head`, `cut` where the file goes on past them.
pub(super) fn size_from_head(
    path: &Path,
    head: &[u8],
    cut: bool,
) -> Result<Option<Size>, MetricsError> {
    if cut && exr::has_magic(head) && exr::layer_sizes(head).is_err() {
        return Ok(None);
    }
    check_exr_head(path, head)?;
    Ok(header_size(head))
}

/// Refuses bytes that do not start as an EXR does, or whose header declares a layer larger
/// than the metrics read.
fn check_exr_head(path: &Path, bytes: &[u8]) -> Result<(), MetricsError> {
    if !exr::has_magic(bytes) {
        // Said from its first bytes: the parser calls a file shorter than its magic number
        // truncated.
        return Err(MetricsError::Read {
            path: path.to_owned(),
            message: NOT_EXR.to_owned(),
        });
    }
    check_exr_size(path, bytes)
}

/// A regular-file reader's refusal as the metrics say it.
fn file_error(path: &Path, e: FileError) -> MetricsError {
    match e {
        FileError::NotFound { .. } => MetricsError::Missing {
            path: path.to_owned(),
        },
        other => MetricsError::Read {
            path: path.to_owned(),
            message: other.to_string(),
        },
    }
}

/// The largest image side the metrics read: twice the largest view specchio writes (8192 px),
/// so a corrupt or hostile header cannot ask for gigabytes before a pixel is read.
pub const MAX_INPUT_SIDE_PX: usize = 16384;

/// The largest EXR file the metrics read: an uncompressed RGBA f32 image of
/// [`MAX_INPUT_SIDE_PX`] a side, with room for its header and offset tables.
const MAX_INPUT_FILE_BYTES: u64 = (MAX_INPUT_SIDE_PX * MAX_INPUT_SIDE_PX * 16) as u64 + (64 << 20);

/// Refuses an EXR whose header declares a layer larger than [`MAX_INPUT_SIDE_PX`] a side,
/// from the header alone (the pixels would be allocated before they are read).
fn check_exr_size(path: &Path, bytes: &[u8]) -> Result<(), MetricsError> {
    for (w, h) in exr::layer_sizes(bytes).map_err(|e| exr_error(path, e))? {
        if w > MAX_INPUT_SIDE_PX || h > MAX_INPUT_SIDE_PX {
            return Err(MetricsError::Read {
                path: path.to_owned(),
                message: format!(
                    "the image is {w}x{h}; at most {MAX_INPUT_SIDE_PX} px a side is read"
                ),
            });
        }
    }
    Ok(())
}

const NOT_EXR: &str = "not an OpenEXR image (expected the linear .exr files that `specchio \
     render` and `specchio reference` write)";

/// The parser ran out of bytes: a file cut short, or one whose header or offsets were
/// damaged so that they point past its end.
const CUT_SHORT: &str = "the OpenEXR file ends before its header or pixels do: truncated or \
     damaged";

/// An OpenEXR reading error in words a user can act on.
fn exr_error(path: &Path, e: exr::Error) -> MetricsError {
    let message = match e {
        exr::Error::Invalid(why) if why.contains("identifier") => NOT_EXR.to_owned(),
        exr::Error::Invalid(why) if why.contains("missing bytes") => CUT_SHORT.to_owned(),
        exr::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            CUT_SHORT.to_owned()
        }
        other => format!("not a readable OpenEXR image: {other}"),
    };
    MetricsError::Read {
        path: path.to_owned(),
        message,
    }
}

/// A mask from an EXR (by extension `.exr`, any case) or any other file decoded as PNG.
pub fn read_mask(path: &Path) -> Result<Mask, MetricsError> {
    if is_exr_name(path) {
        return Ok(Mask::from_red(&read_exr(path)?));
    }
    decode_png_mask(path, &read_png_mask(path)?.0)
}

/// A PNG mask's bytes and its size from its header (no pixel decoded).
fn read_png_mask(path: &Path) -> Result<(Vec<u8>, Size), MetricsError> {
    check_exists(path)?;
    let unreadable = |message: String| MetricsError::Read {
        path: path.to_owned(),
        message,
    };
    let bytes = read_regular_file(path, crate::files::MAX_TEXTURE_FILE_BYTES)
        .map_err(|e| file_error(path, e))?;
    let size = crate::image::png::dimensions(&bytes).map_err(unreadable)?;
    Ok((bytes, size))
}

/// The mask a PNG's bytes decode to: its red channel over [`MASK_THRESHOLD`].
fn decode_png_mask(path: &Path, bytes: &[u8]) -> Result<Mask, MetricsError> {
    let png = TextureData::from_png_bytes(bytes, path).map_err(|e| MetricsError::Read {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(Mask {
        width: png.width,
        height: png.height,
        selected: png
            .rgba8
            .chunks_exact(4)
            .map(|p| f32::from(p[0]) / 255.0 > MASK_THRESHOLD)
            .collect(),
    })
}

/// A comparison's images as read from their files: same size, the mask (if any) selecting
/// some pixel.
pub struct Inputs {
    pub test: RgbaImage,
    pub reference: RgbaImage,
    pub mask: Option<Mask>,
}

/// Reads the files for a comparison; a size mismatch or an empty mask names the files.
pub fn read_inputs(
    test: &Path,
    reference: &Path,
    mask: Option<&Path>,
) -> Result<Inputs, MetricsError> {
    read_inputs_watched(test, reference, mask, &Unwatched)
}

/// [`read_inputs`], the EXR images' rows reported to `watch` as they are decoded (`begin`
/// says how many there are), stopped at its word ([`MetricsError::Stopped`]). The sizes are
/// compared from the headers before any pixel is decoded: a mask of another size used to be
/// found after seconds of decoding at 8192².
pub fn read_inputs_watched(
    test: &Path,
    reference: &Path,
    mask: Option<&Path>,
    watch: &dyn Watch,
) -> Result<Inputs, MetricsError> {
    let name = |p: &Path| p.display().to_string();
    let exr_mask = mask.filter(|m| is_exr_name(m));
    // The sizes compared from each file's first bytes, then from the whole where a header
    // reached past them: a mask of another size is said before gigabytes are read.
    let check_sizes = |(t, r): (Option<Size>, Option<Size>), m: Option<Size>| {
        if let (Some(t), Some(r)) = (t, r) {
            check_size(&name(test), t, &name(reference), r)?;
        }
        match (exr_mask, m, r) {
            (Some(path), Some(m), Some(r)) => check_size(&name(reference), r, &name(path), m),
            _ => Ok(()),
        }
    };
    let sizes = (exr_head_size(test)?, exr_head_size(reference)?);
    let mask_size = exr_mask.map(exr_head_size).transpose()?.flatten();
    check_sizes(sizes, mask_size)?;
    // The memory it takes, before any file is read whole: a comparison at the 16384² the
    // metrics read holds some 13 GB, and none was estimated. (Headers past the first bytes:
    // from the whole files, before any pixel is decoded.)
    let estimate = |(w, h): Size| crate::memory::estimates::compare([w, h], mask.is_some());
    let head_sized = sizes.0.or(sizes.1);
    head_sized.map(estimate).transpose()?;
    // A PNG mask's size is checked from its header first; it is decoded with the images,
    // its rows counted in the reading's progress (0.6 s at 8192², left out of the estimate's
    // rate when it was decoded before the count began).
    let png_mask = match mask.filter(|m| !is_exr_name(m)) {
        Some(path) => Some((path, read_png_mask(path)?)),
        None => None,
    };
    if let (Some((path, (_, m))), Some(r)) = (&png_mask, sizes.1) {
        check_size(&name(reference), r, &name(path), *m)?;
    }
    let (test_bytes, reference_bytes) = (read_checked_exr(test)?, read_checked_exr(reference)?);
    let mask_bytes = exr_mask.map(read_checked_exr).transpose()?;
    let sizes = (header_size(&test_bytes), header_size(&reference_bytes));
    check_sizes(sizes, mask_bytes.as_deref().and_then(header_size))?;
    // A PNG mask against the reference's size from the whole file, where its first bytes did
    // not hold the header: still before any image is decoded.
    if let (Some((path, (_, m))), Some(r)) = (&png_mask, sizes.1) {
        check_size(&name(reference), r, &name(path), *m)?;
    }
    // The EXR mask's window, where it is one, starts where the reference's does too.
    let origins = [
        (test, Some(&test_bytes[..])),
        (reference, Some(&reference_bytes[..])),
        (exr_mask.unwrap_or(reference), mask_bytes.as_deref()),
    ]
    .map(|(path, bytes)| (name(path), bytes.and_then(exr::rgba_layer_origin)));
    check_origins(&origins)?;
    if head_sized.is_none() {
        sizes.0.or(sizes.1).map(estimate).transpose()?;
    }
    let exrs = 2 + u64::from(mask_bytes.is_some());
    let (width, height) = sizes.1.unwrap_or((0, 0));
    let png_rows = png_mask.as_ref().map_or(0, |(_, (_, (_, h)))| *h);
    watch.begin(exrs * u64::from(height) + u64::from(png_rows), width);
    // Each file's bytes let go once decoded: an uncompressed 8192² EXR is a gigabyte.
    let test_image = decode(test, &test_bytes, watch)?;
    drop(test_bytes);
    let reference_image = decode(reference, &reference_bytes, watch)?;
    drop(reference_bytes);
    let mask = match (exr_mask, mask_bytes, png_mask) {
        (Some(path), Some(bytes), _) => Some((path, Mask::from_red(&decode(path, &bytes, watch)?))),
        (_, _, Some((path, (bytes, _)))) => {
            let mask = decode_png_mask(path, &bytes)?;
            watch.rows_done(png_rows);
            Some((path, mask))
        }
        _ => None,
    };
    same_size(
        (&name(test), &test_image),
        (&name(reference), &reference_image),
    )?;
    if let Some((path, mask)) = &mask {
        same_size_as_mask((&name(reference), &reference_image), (&name(path), mask))?;
        mask.check_selects(path)?;
    }
    Ok(Inputs {
        test: test_image,
        reference: reference_image,
        mask: mask.map(|(_, m)| m),
    })
}

/// Every image's data window starting at the same pixel (None: no colour layer, which its
/// decoding then says).
fn check_origins(origins: &[(String, Option<(i32, i32)>)]) -> Result<(), MetricsError> {
    let known: Vec<(&String, (i32, i32))> = (origins.iter())
        .filter_map(|(name, at)| at.map(|at| (name, at)))
        .collect();
    match known.iter().find(|(_, at)| *at != known[0].1) {
        Some((b_name, b_origin)) => Err(MetricsError::OriginMismatch {
            a_name: known[0].0.clone(),
            a_origin: known[0].1,
            b_name: (*b_name).clone(),
            b_origin: *b_origin,
        }),
        None => Ok(()),
    }
}

/// A missing file gets its own error (the decoders' messages do not always name it).
fn check_exists(path: &Path) -> Result<(), MetricsError> {
    match std::fs::metadata(path) {
        Ok(_) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(MetricsError::Missing {
            path: path.to_owned(),
        }),
        Err(e) => Err(MetricsError::Read {
            path: path.to_owned(),
            message: e.to_string(),
        }),
    }
}

/// An image's width and height in pixels.
type Size = (u32, u32);

/// Whether `path` names an EXR file (by its extension, any case): masks are read by it.
pub fn is_exr_name(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// The size of the colour layer an EXR's header declares, the one the decoder reads (a file's
/// layers may differ in size: "all layers alike" left a file of an 8192² layer and an 8x8 one
/// unsized, and its reading's estimate said 9 hours).
fn header_size(bytes: &[u8]) -> Option<Size> {
    exr::rgba_layer_size(bytes).map(|(w, h)| (w as u32, h as u32))
}
