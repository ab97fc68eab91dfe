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
use crate::watch::Watch;

pub trait Sink {
    /// Bytes as they are (CSV, SVG, an encoded image, ...) at `path`.
    fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError>;

    /// Asked before a file is encoded: an error stops the writer there (a transaction's, once
    /// the process was asked to stop: `output::stop_between_files`).
    fn ready(&self, _path: &Path) -> Result<(), OutputError> {
        Ok(())
    }

    /// Linear RGBA, 32-bit float, as OpenEXR.
    fn write_exr(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        self.write_exr_watched(path, image, &crate::watch::Unwatched)
    }

    /// [`Self::write_exr`], its rows counted to `watch` as they are encoded.
    fn write_exr_watched(
        &self,
        path: &Path,
        image: &RgbaImage,
        watch: &dyn Watch,
    ) -> Result<(), OutputError> {
        self.ready(path)?;
        let rows = u64::from(image.height);
        watch.begin(rows, image.width);
        let progress = crate::watch::rows_of_fraction(watch, rows);
        let mut bytes = Stoppable::new();
        exr::encode_rgba_watched(&mut bytes, image, progress)
            .map_err(|e| encode_failed(path, e, exr_error))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// [`Self::write_exr`] in half floats ([`exr::encode_rgba_half`]).
    fn write_exr_half(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        self.ready(path)?;
        let mut bytes = Stoppable::new();
        exr::encode_rgba_half(&mut bytes, image).map_err(|e| encode_failed(path, e, exr_error))?;
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
        self.ready(path)?;
        let mut bytes = Stoppable::new();
        exr::encode_channels(&mut bytes, size, channels)
            .map_err(|e| encode_failed(path, e, exr_error))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// An 8-bit sRGB RGB preview of a linear image.
    fn write_png(&self, path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
        self.ready(path)?;
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
        self.ready(path)?;
        let mut bytes = Stoppable::new();
        png::encode_rgb8(&mut bytes, width, height, rgb8)
            .map_err(|e| encode_failed(path, e, png_error))?;
        self.write_bytes(path, bytes.get_ref())
    }

    /// [`Sink::write_png_rgb8`], its rows counted to `watch` as they are encoded (an 8192²
    /// heatmap of a noisy comparison encodes for seconds).
    fn write_png_rgb8_watched(
        &self,
        path: &Path,
        (width, height): (u32, u32),
        rgb8: &[u8],
        watch: &dyn Watch,
    ) -> Result<(), OutputError> {
        self.ready(path)?;
        watch.begin(u64::from(height), width);
        let mut bytes = Stoppable::new();
        png::encode_rgb8_watched(&mut bytes, width, height, rgb8, |rows| {
            watch.rows_done(rows)
        })
        .map_err(|e| encode_failed(path, e, png_error))?;
        self.write_bytes(path, bytes.get_ref())
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
        self.ready(path)?;
        let text = json_text(path, value)?;
        self.write_bytes(path, text.as_bytes())
    }
}

/// An encoder's bytes in memory, refused from the moment the process is asked to stop
/// (`output::stop_between_files`): the encoders write as they go, so a large image (a 4096²
/// ray map takes seconds) stops at its next block of lines, not after its last.
struct Stoppable(std::io::Cursor<Vec<u8>>);

impl Stoppable {
    fn new() -> Self {
        Self(std::io::Cursor::new(Vec::new()))
    }

    fn get_ref(&self) -> &[u8] {
        self.0.get_ref()
    }
}

impl std::io::Write for Stoppable {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if super::stop_asked() {
            // Not `ErrorKind::Interrupted`, which `write_all` retries for ever.
            return Err(std::io::Error::other("stopped"));
        }
        self.0.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl std::io::Seek for Stoppable {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        self.0.seek(to)
    }
}

/// An encoder's error for `path`: a stop where the process was asked to stop (the encoder
/// failed at [`Stoppable`]'s refusal), else the encoder's own (`as_error`).
fn encode_failed<E>(path: &Path, e: E, as_error: fn(&Path, E) -> OutputError) -> OutputError {
    match super::stop_asked() {
        true => OutputError::Stopped {
            path: path.to_owned(),
        },
        false => as_error(path, e),
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
    fn ready(&self, path: &Path) -> Result<(), OutputError> {
        super::check_stop(path)
    }

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
