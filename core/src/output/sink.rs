//! Where an output's files go: [`Sink`] is what every writer of files (the sensor outputs, a
//! dataset frame, a calibration) writes through, so that one writer serves two ends:
//! - a [`Transaction`](super::Transaction): staged beside the target, placed whole at commit;
//! - [`MemoryFiles`]: kept in memory as (relative path, bytes), for a process that only renders
//!   and hands its files to the one that writes (a Ray worker's dataset frames, returned to the
//!   driver, which alone owns the output folder).
//!
//! Each encoder (EXR, PNG, JSON) encodes into memory and hands the bytes to
//! [`Sink::write_bytes`], the one method a sink implements: a file is the same bytes whichever
//! end it goes to, which is what makes a dataset written by Ray workers byte-identical to one
//! written by a single process.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::{exr_error, png_error, OutputError};
use crate::image::exr::{self, Samples};
use crate::image::{png, RgbaImage};

pub trait Sink {
    /// Bytes as they are (CSV, SVG, an encoded image, ...) at `path`.
    fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError>;

    /// Linear RGBA, 32-bit float, as OpenEXR.
    fn write_exr(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        exr::encode_rgba(&mut bytes, image).map_err(|e| exr_error(path, e))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// [`Self::write_exr`] in half floats ([`exr::encode_rgba_half`]).
    fn write_exr_half(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        exr::encode_rgba_half(&mut bytes, image).map_err(|e| exr_error(path, e))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// `channels` (name, samples of `width * height`) as one EXR layer; the file lists the
    /// channels alphabetically, as EXR requires.
    fn write_channels(
        &self,
        path: &Path,
        size: (u32, u32),
        channels: Vec<(&str, Samples)>,
    ) -> Result<(), OutputError> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        exr::encode_channels(&mut bytes, size, channels).map_err(|e| exr_error(path, e))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// An 8-bit sRGB RGB preview of a linear image.
    fn write_png(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        self.write_png_rgb8(path, image.width, image.height, &png::srgb8_rgb(image))
    }

    /// An 8-bit sRGB RGB PNG from bytes already encoded (3 per pixel, rows top to bottom),
    /// e.g. a colour-mapped error heatmap.
    fn write_png_rgb8(
        &self,
        path: &Path,
        width: u32,
        height: u32,
        rgb8: &[u8],
    ) -> Result<(), OutputError> {
        let mut bytes = Vec::new();
        png::encode_rgb8(&mut bytes, width, height, rgb8).map_err(|e| png_error(path, e))?;
        self.write_bytes(path, &bytes)
    }

    /// JSON of any serialisable record, pretty-printed, with a final newline.
    fn write_json<T: serde::Serialize + ?Sized>(
        &self,
        path: &Path,
        value: &T,
    ) -> Result<(), OutputError>
    where
        Self: Sized,
    {
        let text = json_text(path, value)?;
        self.write_bytes(path, text.as_bytes())
    }
}

/// `value` as the JSON text every sink writes: pretty-printed, with a final newline.
pub fn json_text<T: serde::Serialize + ?Sized>(
    path: &Path,
    value: &T,
) -> Result<String, OutputError> {
    serde_json::to_string_pretty(value)
        .map(|text| text + "\n")
        .map_err(|e| OutputError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        })
}

/// Files kept in memory, each under its path relative to `root`. Writers on several threads
/// may share it (a dataset frame's files are encoded at the same time).
pub struct MemoryFiles {
    root: PathBuf,
    files: Mutex<Vec<(PathBuf, Vec<u8>)>>,
}

impl MemoryFiles {
    /// Files addressed under `root` (as a transaction's writes are addressed under its
    /// folder); each is kept under its path relative to it.
    pub fn new(root: &Path) -> Self {
        MemoryFiles {
            root: root.to_owned(),
            files: Mutex::new(Vec::new()),
        }
    }

    /// The files written: (path relative to the root, bytes), sorted by path, whichever
    /// thread finished first.
    pub fn into_files(self) -> Vec<(PathBuf, Vec<u8>)> {
        // A writer that panicked left no half-pushed entry: `push` is the only change.
        let mut files = self.files.into_inner().unwrap_or_else(|e| e.into_inner());
        files.sort_by(|a, b| a.0.cmp(&b.0));
        files
    }
}

impl Sink for MemoryFiles {
    fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        let relative = path
            .strip_prefix(&self.root)
            .map_err(|_| OutputError::NotStaged {
                path: path.to_owned(),
            })?;
        let mut files = self.files.lock().unwrap_or_else(|e| e.into_inner());
        // A file is written once, as in a transaction (whose `create` is exclusive).
        if files.iter().any(|(p, _)| p == relative) {
            return Err(OutputError::Io {
                path: path.to_owned(),
                source: std::io::Error::from(std::io::ErrorKind::AlreadyExists),
            });
        }
        files.push((relative.to_owned(), bytes.to_vec()));
        Ok(())
    }
}
