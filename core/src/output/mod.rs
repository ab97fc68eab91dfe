//! Output files: linear EXR, sRGB PNG previews and JSON, all written through a
//! [`Transaction`] so that a command's outputs appear together or not at all.
//!
//! The one-file functions (`write_exr`, `write_png`, ...) are a transaction of one file: a
//! failed or interrupted write never leaves a half-written file, and every error names the
//! user's path, never the hidden temporary one.

mod dir;
mod manifest;
mod numbered;
mod replace;
mod sink;
mod stage;
mod staged;
mod sys;
mod transaction;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::image::{exr, png, RgbaImage};

pub use dir::{Dir, Entry};
pub use manifest::MANIFEST;
pub use sink::{json_text, MemoryFiles, Sink};
pub use stage::remove_live as remove_staging_folders;
pub use sys::{create_new, open_no_follow, try_lock};
pub use transaction::{names_a_folder, Transaction};

/// Why an output could not be written. Each names the user's path; an I/O cause is the
/// error's `source` (printed after it by `{:#}` in the CLI), not repeated in the message.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot create the folder {path}")]
    CreateFolder {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {message}")]
    Encode { path: PathBuf, message: String },
    #[error("cannot write {path}: the folder {folder} does not exist")]
    NoFolder { path: PathBuf, folder: PathBuf },
    #[error("cannot write {path}: it is a folder; a file name is needed")]
    IsAFolder { path: PathBuf },
    #[error(
        "cannot write {path}: a name that ends in `/`, `.` or `..` is a folder's; a file name \
         is needed"
    )]
    FolderName { path: PathBuf },
    #[error("cannot write {path}: it is {what}; a file output replaces only a regular file")]
    NotAFile { path: PathBuf, what: &'static str },
    #[error(
        "cannot write {path}: the output in {output} wrote it (its {manifest} lists it), and a \
         file output does not replace another output's file; choose another name"
    )]
    AnothersFile {
        path: PathBuf,
        output: PathBuf,
        manifest: &'static str,
    },
    #[error(
        "cannot write {path}: it is inside {output}, another command's output folder (its \
         {manifest} lists what that output wrote); a file of its own there would stop that \
         command from replacing its output on its next run; choose a path outside it"
    )]
    InsideAnOutput {
        path: PathBuf,
        output: PathBuf,
        manifest: &'static str,
    },
    #[error("cannot write {path}: it exists and is not a folder (a file or a symbolic link)")]
    NotAFolder { path: PathBuf },
    #[error(
        "{path} exists and is not an earlier output (it holds files but no {marker}): \
         refusing to replace it; choose a new folder, or remove it first"
    )]
    NotAnOutput { path: PathBuf, marker: String },
    #[error(
        "{path} holds {entry}, which no earlier output there wrote (an output lists its files \
         in {manifest}): refusing to replace it; choose a new folder, or move {entry} out first"
    )]
    Foreign {
        path: PathBuf,
        entry: String,
        manifest: &'static str,
    },
    #[error(
        "cannot write {path}: it is the file system's root (or resolves to it), which cannot be \
         replaced as an output; name a folder or file inside it"
    )]
    NoName { path: PathBuf },
    #[error("cannot write {path}: its name is not valid UTF-8")]
    NotUtf8 { path: PathBuf },
    #[error(
        "{path} was replaced, but {} kept in {kept}: nothing was deleted; look through it \
         and remove it",
        written_meanwhile(.entries)
    )]
    KeptAside {
        path: PathBuf,
        entries: Vec<String>,
        kept: PathBuf,
    },
    #[error(
        "{path}: a rename failed while the earlier output was being replaced, and the earlier \
         output could not be put back: it is kept in {at} (nothing was deleted); move it back or \
         remove it by hand"
    )]
    StuckAside {
        path: PathBuf,
        at: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {path}: it is the input {input}; the output must go to another file")]
    IsAnInput { path: PathBuf, input: PathBuf },
    #[error("{path} is given for two outputs of one command")]
    Twice { path: PathBuf },
    #[error("{path} is not among this command's outputs (a bug in the caller)")]
    NotStaged { path: PathBuf },
    #[error("interrupted before {path} was written: nothing was written")]
    Stopped { path: PathBuf },
}

/// The check a transaction makes before it encodes and before it writes each file: a process
/// that catches stopping signals installs it (`process::interrupt::catch`), so that a run
/// writing many large files (a 4096² sensor's outputs take half a minute) stops at its next
/// file, not after the last.
static STOP: std::sync::OnceLock<fn() -> bool> = std::sync::OnceLock::new();

/// Makes every transaction stop at its next file once `stop` says so (set once a process).
pub fn stop_between_files(stop: fn() -> bool) {
    let _ = STOP.set(stop);
}

/// Whether the process was asked to stop ([`stop_between_files`]): for long work between
/// files, a panorama's rows, say.
pub fn stop_asked() -> bool {
    STOP.get().is_some_and(|stop| stop())
}

/// An error for `path` once the process was asked to stop.
pub(crate) fn check_stop(path: &Path) -> Result<(), OutputError> {
    match stop_asked() {
        true => Err(OutputError::Stopped {
            path: path.to_owned(),
        }),
        false => Ok(()),
    }
}

/// What appeared in an earlier output while it was replaced, in words.
fn written_meanwhile(entries: &[String]) -> String {
    let (count, verb) = match entries.len() {
        1 => ("1 entry".to_owned(), "is"),
        n => (format!("{n} entries"), "are"),
    };
    format!(
        "{count} of the earlier output that it did not write or that could not be removed \
         ({}) {verb}",
        entries.join(", ")
    )
}

/// An I/O failure is reported as one, naming `path`; anything else the encoder says is an
/// encoding failure.
pub(crate) fn exr_error(path: &Path, e: exr::Error) -> OutputError {
    match e {
        exr::Error::Io(source) => OutputError::Io {
            path: path.to_owned(),
            source,
        },
        other => OutputError::Encode {
            path: path.to_owned(),
            message: other.to_string(),
        },
    }
}

pub(crate) fn png_error(path: &Path, e: png::EncodingError) -> OutputError {
    match e {
        png::EncodingError::IoError(source) => OutputError::Io {
            path: path.to_owned(),
            source,
        },
        other => OutputError::Encode {
            path: path.to_owned(),
            message: other.to_string(),
        },
    }
}

impl Sink for Transaction {
    fn ready(&self, path: &Path) -> Result<(), OutputError> {
        check_stop(path)
    }

    fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        check_stop(path)?;
        let mut file = self.create(path)?;
        file.write_all(bytes)
            .and_then(|()| file.flush())
            .map_err(|source| OutputError::Io {
                path: path.to_owned(),
                source,
            })
    }
}

/// Makes a write beyond a file-size limit (`ulimit -f`) fail with `File too large` instead of
/// killing the process with SIGXFSZ, so that the output transaction removes what it wrote, as
/// after any other error. Call it once at start-up, before other threads exist.
pub fn survive_file_size_limit() {
    #[cfg(target_os = "linux")]
    // SAFETY: sets the disposition of one signal; called before other threads start.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

/// Runs `write` in a transaction of the one file `path`.
fn one_file(
    path: &Path,
    write: impl FnOnce(&Transaction) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let mut out = Transaction::new();
    out.file(path)?;
    write(&out)?;
    out.commit()
}

/// Linear RGBA, 32-bit float, as OpenEXR, atomically.
pub fn write_exr(path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
    one_file(path, |out| out.write_exr(path, image))
}

/// An 8-bit sRGB RGB preview of a linear image, atomically.
pub fn write_png(path: &Path, image: &RgbaImage) -> Result<(), OutputError> {
    one_file(path, |out| out.write_png(path, image))
}

/// [`Transaction::write_png_rgb8`] as one file, atomically.
pub fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb8: &[u8],
) -> Result<(), OutputError> {
    one_file(path, |out| out.write_png_rgb8(path, width, height, rgb8))
}

/// An 8-bit sRGB RGB PNG (as [`Transaction::write_png_rgb8`]) as the first free
/// `PREFIX-NNNN.png` in `folder`, never replacing a file; its path.
pub fn write_png_rgb8_numbered(
    folder: &Path,
    prefix: &str,
    width: u32,
    height: u32,
    rgb8: &[u8],
) -> Result<PathBuf, OutputError> {
    let mut bytes = Vec::new();
    png::encode_rgb8(&mut bytes, width, height, rgb8).map_err(|e| png_error(folder, e))?;
    numbered::write_numbered(folder, prefix, "png", &bytes)
}

/// JSON (pretty), atomically.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), OutputError> {
    one_file(path, |out| out.write_json(path, value))
}

/// Held by the tests that start a child process and by those that need a dead run's lock to be
/// free: a child shares the parent's open files from its fork to its exec, a staging folder's
/// locked token included, so a child started by another test thread at that moment keeps a
/// just-abandoned stage looking alive (a race of the tests, not of the protocol: a run's lock
/// held by anyone means a live run).
#[cfg(test)]
pub(crate) fn serial_with_children() -> std::sync::MutexGuard<'static, ()> {
    static CHILDREN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    CHILDREN.lock().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod protocol_tests;
#[cfg(test)]
mod tests;
