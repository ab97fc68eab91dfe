//! PNG textures, decoded to 8-bit RGBA.

#[cfg(test)]
use std::fs::File;
use std::path::{Path, PathBuf};

use super::asset::AssetError;
use crate::files::{read_regular_file, MAX_TEXTURE_FILE_BYTES};

/// Largest texture side accepted (texels).
pub const MAX_TEXTURE_SIZE_PX: u32 = 8192;

/// A decoded image: `width * height` texels, rows top to bottom (first row = top of the image,
/// texture v = 0), 4 bytes per texel, sRGB-encoded colour exactly as stored in the file
/// (the renderer samples it through an sRGB format), alpha linear.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureData {
    /// The file the image came from (resolved, as opened).
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

impl TextureData {
    /// Decodes the PNG at `path` (see [`TextureData::from_png_bytes`]).
    ///
    /// The error is a plain message (the caller adds the scene file, line and field);
    /// [`TextureData::load_png`] gives the typed error.
    pub fn from_png(path: &Path) -> Result<TextureData, String> {
        Self::load_png(path).map_err(|e| e.to_string())
    }

    /// [`TextureData::from_png`] with a typed error. Only a regular file of at most
    /// [`MAX_TEXTURE_FILE_BYTES`] is read.
    pub fn load_png(path: &Path) -> Result<TextureData, AssetError> {
        let bytes = read_regular_file(path, MAX_TEXTURE_FILE_BYTES)?;
        Self::from_png_bytes(&bytes, path)
    }

    /// Decodes a PNG of any colour type and bit depth: palette and grayscale are expanded,
    /// 16-bit channels are reduced to 8 bits, missing alpha becomes 255. `path` is recorded
    /// as the texture's source. Each side must be in 1..=[`MAX_TEXTURE_SIZE_PX`], checked from
    /// the header before any pixel memory is allocated.
    pub fn from_png_bytes(bytes: &[u8], path: &Path) -> Result<TextureData, AssetError> {
        let (width, height, rgba8) =
            crate::image::png::decode_rgba8(bytes, MAX_TEXTURE_SIZE_PX).map_err(AssetError::Png)?;
        Ok(TextureData {
            path: path.to_path_buf(),
            width,
            height,
            rgba8,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_png(
        path: &Path,
        w: u32,
        h: u32,
        color: png::ColorType,
        depth: png::BitDepth,
        data: &[u8],
    ) {
        let file = File::create(path).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(color);
        enc.set_depth(depth);
        let mut writer = enc.write_header().unwrap();
        writer.write_image_data(data).unwrap();
    }

    #[test]
    fn grayscale_and_16_bit_expand_to_rgba8() {
        let dir = std::env::temp_dir().join(format!("specchio-tex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gray = dir.join("gray.png");
        write_png(
            &gray,
            2,
            1,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &[10, 200],
        );
        let t = TextureData::from_png(&gray).unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        assert_eq!(t.rgba8, vec![10, 10, 10, 255, 200, 200, 200, 255]);

        let rgb16 = dir.join("rgb16.png");
        write_png(
            &rgb16,
            1,
            1,
            png::ColorType::Rgb,
            png::BitDepth::Sixteen,
            &[255, 0, 0, 0, 128, 0],
        );
        let t = TextureData::from_png(&rgb16).unwrap();
        assert_eq!(t.rgba8, vec![255, 0, 128, 255]);

        let bad = dir.join("bad.png");
        std::fs::write(&bad, b"not a png").unwrap();
        assert!(TextureData::from_png(&bad).is_err());
        assert!(TextureData::from_png(&dir.join("missing.png")).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The orientation test texture shipped as `scenes/textures/orientation.png`, generated here
/// so that it is reproducible: 128 x 128, four tinted quadrants (top-left red, top-right green,
/// bottom-left blue, bottom-right yellow), a dark border, a big black "F" (no rotation or
/// mirror image of an F looks like an F) and a small up-arrow in the top-right quadrant.
#[cfg(test)]
pub(crate) fn orientation_texture() -> (u32, u32, Vec<u8>) {
    const N: u32 = 128;
    let mut rgba = Vec::with_capacity((N * N * 4) as usize);
    for y in 0..N {
        for x in 0..N {
            let (left, top) = (x < N / 2, y < N / 2);
            let mut c: [u8; 3] = match (left, top) {
                (true, true) => [240, 170, 170],
                (false, true) => [170, 235, 170],
                (true, false) => [170, 185, 245],
                (false, false) => [245, 235, 150],
            };
            let border = x < 4 || y < 4 || x >= N - 4 || y >= N - 4;
            // "F": stem, top bar, middle bar.
            let stem = (36..52).contains(&x) && (24..104).contains(&y);
            let top_bar = (36..92).contains(&x) && (24..40).contains(&y);
            let mid_bar = (36..80).contains(&x) && (58..72).contains(&y);
            // Up-arrow in the top-right quadrant: shaft and a triangular head.
            let shaft = (103..107).contains(&x) && (16..44).contains(&y);
            let head = (8..18).contains(&y) && x.abs_diff(105) <= (y - 8);
            if border || stem || top_bar || mid_bar || shaft || head {
                c = [20, 20, 20];
            }
            rgba.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
    (N, N, rgba)
}

#[cfg(test)]
mod shipped_texture {
    use super::*;

    /// The committed PNG decodes to exactly the generated pixels. Set
    /// `SPECCHIO_WRITE_TEXTURES=1` (or delete the file) to (re)write it.
    #[test]
    fn orientation_png_matches_generator() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/textures/orientation.png");
        let (w, h, rgba) = orientation_texture();
        if std::env::var_os("SPECCHIO_WRITE_TEXTURES").is_some() || !path.exists() {
            let file = File::create(&path).unwrap();
            let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().unwrap();
            writer.write_image_data(&rgba).unwrap();
        }
        let t = TextureData::from_png(&path).unwrap();
        assert_eq!((t.width, t.height), (w, h));
        assert!(
            t.rgba8 == rgba,
            "{} differs from the generator",
            path.display()
        );
    }
}
