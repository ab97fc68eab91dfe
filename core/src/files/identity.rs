//! Files by identity: the device and inode a path leads to, and the process's record of every
//! file it has read.
//!
//! Two paths name the same file when their identities are equal, however they are spelled:
//! `T.exr` and `t.EXR` on a case-insensitive file system, a hard link, a symbolic link, `./a`
//! and `a`. Comparing canonical paths gets all of those wrong but the last. The output
//! protocol (`crate::output`) refuses to replace any file in this record, so a command can
//! never write over the scene, mesh, texture, baseline or landmark file it read, whichever
//! option names the output.

use std::fs::Metadata;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A file's identity: (device, inode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FileId {
    device: u64,
    inode: u64,
}

impl FileId {
    /// The identity in `meta` (None where the OS gives none).
    pub fn of(meta: &Metadata) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            Some(FileId {
                device: meta.dev(),
                inode: meta.ino(),
            })
        }
        #[cfg(not(unix))]
        {
            let _ = meta;
            None
        }
    }

    /// The identity of the file `path` leads to (links followed); None when there is none.
    pub fn of_path(path: &Path) -> Option<FileId> {
        std::fs::metadata(path).ok().as_ref().and_then(FileId::of)
    }
}

/// Every file this process has read through [`super::read_regular_file`], once per path.
static READ: Mutex<Vec<(FileId, PathBuf)>> = Mutex::new(Vec::new());

/// Forgets every file read so far: for a process that runs many commands (the Python
/// package), at the start of each one that writes, so that what it may not replace is what
/// that command read (it reads its inputs again), and the list stays bounded.
pub fn forget() {
    READ.lock().unwrap_or_else(|e| e.into_inner()).clear();
}

/// Records that `path`, whose open handle has `meta`, was read.
pub(super) fn record(path: &Path, meta: &Metadata) {
    let Some(id) = FileId::of(meta) else {
        return;
    };
    let mut read = READ.lock().unwrap_or_else(|e| e.into_inner());
    // By identity and path: an inode freed by a deleted input may come back as another file.
    if !read.iter().any(|(i, p)| *i == id && p == path) {
        read.push((id, path.to_owned()));
    }
}

/// The files read so far that are still where they were read, with that path. A file deleted
/// since is no input any more, and the file system may give its inode to a new file (an
/// output among them), so only records whose path still leads to their identity count.
pub fn read_so_far() -> Vec<(FileId, PathBuf)> {
    let read = READ.lock().unwrap_or_else(|e| e.into_inner()).clone();
    read.into_iter()
        .filter(|(id, path)| still(*id, path))
        .collect()
}

/// Whether `path` still leads to the file `id`.
pub fn still(id: FileId, path: &Path) -> bool {
    FileId::of_path(path) == Some(id)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// A hard link and a symbolic link are the file; a copy is not.
    #[test]
    fn links_share_an_identity_and_copies_do_not() {
        let d = std::env::temp_dir().join(format!("specchio-identity-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let a = d.join("a.toml");
        std::fs::write(&a, b"x").unwrap();
        std::fs::hard_link(&a, d.join("hard")).unwrap();
        std::os::unix::fs::symlink(&a, d.join("soft")).unwrap();
        std::fs::copy(&a, d.join("copy")).unwrap();
        let id = FileId::of_path(&a).unwrap();
        assert_eq!(FileId::of_path(&d.join("hard")), Some(id));
        assert_eq!(FileId::of_path(&d.join("soft")), Some(id));
        assert_eq!(FileId::of_path(&d.join("./a.toml")), Some(id));
        assert_ne!(FileId::of_path(&d.join("copy")), Some(id));
        assert_eq!(FileId::of_path(&d.join("gone")), None);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
