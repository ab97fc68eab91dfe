//! An open folder: names inside it are renamed, examined and removed relative to the handle
//! (`renameat2`, `fstatat`, `unlinkat` on Linux), never by a path that another program could
//! redirect meanwhile. The protocol holds its staging folder this way from the moment it made
//! it, and opens the earlier output it swapped out the same way, so a staging folder renamed
//! away and replaced by a link, or a folder inside the old output replaced by a link, cannot
//! make it remove anything outside them.

use std::ffi::OsStr;
use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};

/// What a name in a folder is, not following a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entry {
    Folder,
    Link,
    Other,
}

/// How a rename treats what is at its destination.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rename {
    /// Replaces a file (or an empty folder), as `rename(2)`.
    Replace,
    /// Fails with `AlreadyExists` when anything is there.
    NoReplace,
    /// Swaps the two atomically; both must exist.
    Exchange,
}

/// An open folder.
#[derive(Debug)]
pub struct Dir {
    file: File,
    /// The path it was opened by, for what has no handle-relative call elsewhere than Linux.
    #[cfg_attr(target_os = "linux", allow(dead_code))]
    path: PathBuf,
}

#[cfg(target_os = "linux")]
mod imp {
    use super::*;
    use std::ffi::CString;
    use std::os::fd::{AsRawFd, FromRawFd};
    use std::os::unix::ffi::OsStrExt;

    fn c(name: &OsStr) -> io::Result<CString> {
        CString::new(name.as_bytes()).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))
    }

    fn check(rc: libc::c_int) -> io::Result<()> {
        match rc {
            0 => Ok(()),
            _ => Err(io::Error::last_os_error()),
        }
    }

    pub fn open(at: libc::c_int, name: &OsStr, path: PathBuf) -> io::Result<Dir> {
        let name = c(name)?;
        let flags = libc::O_RDONLY | libc::O_DIRECTORY | libc::O_NOFOLLOW | libc::O_CLOEXEC;
        // SAFETY: a valid NUL-terminated name; the descriptor returned is owned below.
        let fd = unsafe { libc::openat(at, name.as_ptr(), flags) };
        if fd < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: `fd` is a fresh descriptor nothing else owns.
        let file = unsafe { File::from_raw_fd(fd) };
        Ok(Dir { file, path })
    }

    impl Dir {
        pub(super) fn fd(&self) -> libc::c_int {
            self.file.as_raw_fd()
        }

        pub fn entry(&self, name: &OsStr) -> io::Result<Entry> {
            let name = c(name)?;
            // SAFETY: a zeroed stat is valid; fstatat fills it.
            let mut st: libc::stat = unsafe { std::mem::zeroed() };
            let rc = unsafe {
                libc::fstatat(self.fd(), name.as_ptr(), &mut st, libc::AT_SYMLINK_NOFOLLOW)
            };
            check(rc)?;
            Ok(match st.st_mode & libc::S_IFMT {
                libc::S_IFDIR => Entry::Folder,
                libc::S_IFLNK => Entry::Link,
                _ => Entry::Other,
            })
        }

        pub fn remove(&self, name: &OsStr, folder: bool) -> io::Result<()> {
            let name = c(name)?;
            let flags = if folder { libc::AT_REMOVEDIR } else { 0 };
            // SAFETY: a valid NUL-terminated name relative to our own descriptor.
            check(unsafe { libc::unlinkat(self.fd(), name.as_ptr(), flags) })
        }

        pub fn rename(&self, name: &OsStr, to: (&Dir, &OsStr), how: Rename) -> io::Result<()> {
            self.rename_raw(name, to.0.fd(), to.1, how)
        }

        pub fn rename_out(&self, name: &OsStr, to: &Path, how: Rename) -> io::Result<()> {
            self.rename_raw(name, libc::AT_FDCWD, to.as_os_str(), how)
        }

        pub fn rename_in(&self, from: &Path, name: &OsStr) -> io::Result<()> {
            let (from, name) = (c(from.as_os_str())?, c(name)?);
            // SAFETY: valid NUL-terminated names; the destination relative to our descriptor.
            let rc = unsafe {
                libc::renameat2(libc::AT_FDCWD, from.as_ptr(), self.fd(), name.as_ptr(), 0)
            };
            check(rc)
        }

        fn rename_raw(
            &self,
            name: &OsStr,
            to_at: libc::c_int,
            to: &OsStr,
            how: Rename,
        ) -> io::Result<()> {
            let flags = match how {
                Rename::Replace => 0,
                Rename::NoReplace => libc::RENAME_NOREPLACE,
                Rename::Exchange => libc::RENAME_EXCHANGE,
            };
            let (name, to) = (c(name)?, c(to)?);
            // SAFETY: valid NUL-terminated names; the source relative to our descriptor.
            let rc =
                unsafe { libc::renameat2(self.fd(), name.as_ptr(), to_at, to.as_ptr(), flags) };
            check(rc)
        }

        /// A path that leads to this very folder wherever it has been moved (through the
        /// descriptor's link in /proc; the final `.` makes even `symlink_metadata` follow
        /// it), for reading its contents with ordinary calls.
        pub fn path(&self) -> PathBuf {
            PathBuf::from(format!("/proc/self/fd/{}/.", self.fd()))
        }
    }

    pub const CWD: libc::c_int = libc::AT_FDCWD;
}

#[cfg(not(target_os = "linux"))]
mod imp {
    //! Elsewhere: the same operations by path (no handle-relative calls in `std`).
    use super::*;

    pub const CWD: i32 = 0;

    pub fn open(_: i32, _: &OsStr, path: PathBuf) -> io::Result<Dir> {
        let meta = std::fs::symlink_metadata(&path)?;
        if !meta.is_dir() {
            return Err(io::Error::other("not a folder"));
        }
        Ok(Dir {
            file: File::open(&path)?,
            path,
        })
    }

    impl Dir {
        pub fn entry(&self, name: &OsStr) -> io::Result<Entry> {
            let t = std::fs::symlink_metadata(self.path.join(name))?.file_type();
            Ok(match () {
                _ if t.is_dir() => Entry::Folder,
                _ if t.is_symlink() => Entry::Link,
                _ => Entry::Other,
            })
        }
        pub fn remove(&self, name: &OsStr, folder: bool) -> io::Result<()> {
            match folder {
                true => std::fs::remove_dir(self.path.join(name)),
                false => std::fs::remove_file(self.path.join(name)),
            }
        }
        pub fn rename(&self, name: &OsStr, to: (&Dir, &OsStr), how: Rename) -> io::Result<()> {
            self.rename_out(name, &to.0.path.join(to.1), how)
        }
        pub fn rename_out(&self, name: &OsStr, to: &Path, how: Rename) -> io::Result<()> {
            match how {
                Rename::Replace => std::fs::rename(self.path.join(name), to),
                _ => Err(io::ErrorKind::Unsupported.into()),
            }
        }
        pub fn rename_in(&self, from: &Path, name: &OsStr) -> io::Result<()> {
            std::fs::rename(from, self.path.join(name))
        }
        pub fn path(&self) -> PathBuf {
            self.path.clone()
        }
    }
}

impl Dir {
    /// Opens the folder at `path`, refusing a link in its place.
    pub fn open(path: &Path) -> io::Result<Dir> {
        imp::open(imp::CWD, path.as_os_str(), path.to_owned())
    }

    /// Makes this folder's entries durable (`fsync` on the folder).
    pub fn sync(&self) -> io::Result<()> {
        self.file.sync_all()
    }

    /// Opens the folder `name` inside this one, refusing a link in its place.
    pub fn open_dir(&self, name: &OsStr) -> io::Result<Dir> {
        #[cfg(target_os = "linux")]
        let at = self.fd();
        #[cfg(not(target_os = "linux"))]
        let at = imp::CWD;
        imp::open(at, name, self.path.join(name))
    }
}
