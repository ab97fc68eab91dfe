//! Image files: linear EXR and sRGB PNG previews, written atomically.
//!
//! Every file is written to a temporary name in its folder and renamed into place, so a failed
//! or interrupted run never leaves a half-written image behind.

use std::fs;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::image::RgbaImage;

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {message}")]
    Encode { path: PathBuf, message: String },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_owned(),
        source,
    }
}

/// `dir/.name.partial`: hidden, in the same folder so that the rename is atomic.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.partial"))
}

/// Writes through `write` to a temporary file, then renames it to `path`.
fn atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let tmp = temp_path(path);
    match write(&tmp) {
        Ok(()) => fs::rename(&tmp, path).map_err(io(path)),
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Linear RGBA, 32-bit float, as OpenEXR.
pub fn write_exr(path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
    atomically(path, |tmp| {
        let w = image.width as usize;
        exr::prelude::write_rgba_file(tmp, w, image.height as usize, |x, y| {
            let p = image.pixels[y * w + x];
            (p[0], p[1], p[2], p[3])
        })
        .map_err(|e| OutputError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        })
    })
}

/// The linear-to-sRGB transfer function (IEC 61966-2-1), input clamped to [0, 1].
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// An 8-bit sRGB RGB preview of a linear image.
pub fn write_png(path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]])
        .map(|v| (linear_to_srgb(v) * 255.0).round() as u8)
        .collect();
    write_png_rgb8(path, image.width, image.height, &bytes)
}

/// An 8-bit sRGB RGB PNG from bytes already encoded (3 per pixel, rows top to bottom), e.g. a
/// colour-mapped error heatmap.
pub fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb8: &[u8],
) -> Result<(), OutputError> {
    atomically(path, |tmp| {
        let file = fs::File::create(tmp).map_err(io(tmp))?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let enc = |e: png::EncodingError| OutputError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let mut writer = encoder.write_header().map_err(enc)?;
        writer.write_image_data(rgb8).map_err(enc)?;
        writer.finish().map_err(enc)
    })
}

/// Writes JSON (pretty) atomically.
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), OutputError> {
    atomically(path, |tmp| {
        let text = serde_json::to_string_pretty(value).map_err(|e| OutputError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        fs::write(tmp, text + "\n").map_err(io(tmp))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_known_values() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        // 18% grey is about 46% in sRGB.
        assert!((linear_to_srgb(0.18) - 0.4614).abs() < 1e-3);
        assert_eq!(linear_to_srgb(f32::NAN), 0.0);
    }

    #[test]
    fn exr_round_trips_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("specchio-exr-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let image = RgbaImage {
            width: 3,
            height: 2,
            pixels: (0..6).map(|i| [i as f32, 0.5, 2.0, 1.0]).collect(),
        };
        let path = dir.join("a.exr");
        write_exr(&path, &image).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| vec![[0f32; 4]; res.width() * res.height()],
            |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * 3 + pos.x()] = [r, g, b, a]
            },
        )
        .unwrap();
        assert_eq!(read.layer_data.channel_data.pixels, image.pixels);
        assert!(!temp_path(&path).exists());
        fs::remove_dir_all(&dir).unwrap();
    }
}
