//! The one way input files are read: the scene file, meshes, glTF buffers, textures, images
//! to compare, baselines and landmark files.
//!
//! Every reader goes through [`read_regular_file`], so the same rules hold everywhere:
//! only regular files are opened (a FIFO or a character device would block or never end, a
//! directory is a user's slip), the bytes read are bounded by a stated budget, and every
//! refusal says what the path is and what is allowed. And every file read is recorded by
//! identity ([`identity`]): no output of the command may replace it.

pub mod digest;
pub mod identity;
pub mod json;

use std::fs::{File, Metadata};
use std::io::{self, Read};
use std::path::{Path, PathBuf};

/// Largest scene file read (bytes): scene files are hand-written text; crowds come from
/// `[[generate]]`, not from listing objects one by one.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;
/// Largest mesh file (OBJ, glTF JSON or GLB) read (bytes).
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;
/// Most bytes one glTF file may pull in from external buffer files, all buffers together.
pub const MAX_GLTF_BUFFER_BYTES: u64 = 256 << 20;
/// Largest PNG file read (bytes).
pub const MAX_TEXTURE_FILE_BYTES: u64 = 64 << 20;

/// Why a file was not read. Messages leave out the path: every caller already names the file
/// (the scene error, or the glTF buffer whose URI led to it); `path` is kept for programs.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("file not found")]
    NotFound { path: PathBuf },

    /// A directory, FIFO, socket or device: reading it would fail, block or never end.
    #[error("is {what}, not a regular file (only regular files are read)")]
    NotRegular { path: PathBuf, what: &'static str },

    #[error("symbolic link loop (or too many links in a row); a link must end at a regular file")]
    LinkLoop { path: PathBuf },

    #[error("file is {size} bytes, more than the limit of {limit} bytes ({})", mib(*limit))]
    TooLarge {
        path: PathBuf,
        size: u64,
        limit: u64,
    },

    #[error("{source}")]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

impl From<FileError> for io::Error {
    /// Keeps the kind a caller may test for (not found) and the full message.
    fn from(e: FileError) -> io::Error {
        let kind = match &e {
            FileError::NotFound { .. } => io::ErrorKind::NotFound,
            FileError::Io { source, .. } => source.kind(),
            _ => io::ErrorKind::InvalidInput,
        };
        io::Error::new(kind, e)
    }
}

fn mib(bytes: u64) -> String {
    format!("{} MiB", bytes >> 20)
}

/// Reads the whole of `path`, which must be a regular file (after following links) of at most
/// `limit` bytes ([`open_regular`] checks both). The size is checked from the metadata and enforced while reading, so a file that
/// grows while it is read still cannot exceed `limit`.
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let io_err = |source: io::Error| classify(path, source);
    let (file, opened) = open_regular(path, limit)?;
    identity::record(path, &opened);
    let mut bytes = Vec::with_capacity(opened.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(io_err)?;
    if bytes.len() as u64 > limit {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            size: bytes.len() as u64,
            limit,
        });
    }
    digest::note(&bytes);
    Ok(bytes)
}

/// The first `head` bytes of `path` (all of it where it is shorter), checked as
/// [`read_regular_file`] checks it: a header read before a large file is read whole.
pub fn read_regular_file_head(path: &Path, limit: u64, head: u64) -> Result<Vec<u8>, FileError> {
    let (file, opened) = open_regular(path, limit)?;
    let mut bytes = Vec::with_capacity(opened.len().min(head) as usize);
    (file.take(head).read_to_end(&mut bytes)).map_err(|e| classify(path, e))?;
    Ok(bytes)
}

/// `path` opened for reading once it is known to be a regular file of at most `limit` bytes,
/// with its metadata as opened.
///
/// The type is checked before the file is opened, because opening a FIFO for reading blocks
/// until a writer appears; it is checked again on the open handle in case the path was swapped
/// in between.
fn open_regular(path: &Path, limit: u64) -> Result<(File, Metadata), FileError> {
    let io_err = |source: io::Error| classify(path, source);
    let meta = std::fs::metadata(path).map_err(io_err)?;
    check_regular(path, &meta, limit)?;
    // Without waiting: if the path became a FIFO since the check, the open returns at once
    // (`O_NONBLOCK`; it changes nothing for a regular file) and the check below refuses it.
    let file = open_no_wait(path).map_err(io_err)?;
    let opened = file.metadata().map_err(io_err)?;
    check_regular(path, &opened, limit)?;
    Ok((file, opened))
}

/// Opens `path` for reading with `O_NONBLOCK` where the OS has it.
fn open_no_wait(path: &Path) -> io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

fn check_regular(path: &Path, meta: &Metadata, limit: u64) -> Result<(), FileError> {
    if !meta.is_file() {
        return Err(FileError::NotRegular {
            path: path.to_path_buf(),
            what: describe(meta),
        });
    }
    if meta.len() > limit {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            size: meta.len(),
            limit,
        });
    }
    Ok(())
}

/// What a non-regular file is, in words.
fn describe(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
    }
    "not a plain file"
}

/// Turns an OS error into the specific refusals users can act on.
fn classify(path: &Path, source: io::Error) -> FileError {
    let path = path.to_path_buf();
    if source.kind() == io::ErrorKind::NotFound {
        return FileError::NotFound { path };
    }
    // ELOOP: a link cycle, or more links in a row than the OS follows.
    #[cfg(target_os = "linux")]
    if source.raw_os_error() == Some(40) {
        return FileError::LinkLoop { path };
    }
    if source.kind() == io::ErrorKind::IsADirectory {
        return FileError::NotRegular {
            path,
            what: "a directory",
        };
    }
    FileError::Io { path, source }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("specchio-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn reads_small_regular_files_and_refuses_the_rest() {
        let d = temp("kinds");
        let f = d.join("a.txt");
        std::fs::write(&f, b"hello").unwrap();
        assert_eq!(read_regular_file(&f, 5).unwrap(), b"hello");
        let e = read_regular_file(&f, 4).unwrap_err();
        assert!(
            matches!(
                e,
                FileError::TooLarge {
                    size: 5,
                    limit: 4,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_regular_file(&d, 100).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        let e = read_regular_file(&d.join("gone"), 100).unwrap_err();
        assert!(e.to_string().ends_with("file not found"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn fifos_and_link_loops_are_refused_without_blocking() {
        let _serial = crate::output::serial_with_children();
        let d = temp("special");
        let fifo = d.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) makes a FIFO"
        );
        // Opening this FIFO for reading would block forever: the check must come first.
        let e = read_regular_file(&fifo, 100).unwrap_err();
        assert!(e.to_string().contains("FIFO"), "{e}");
        let (a, b) = (d.join("a"), d.join("b"));
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        let e = read_regular_file(&a, 100).unwrap_err();
        assert!(matches!(e, FileError::LinkLoop { .. }), "{e}");
        let io: io::Error = e.into();
        assert!(io.to_string().contains("symbolic link loop"), "{io}");
        let _ = std::fs::remove_dir_all(&d);
    }
}
