//! The system calls the output protocol needs beyond `std`, besides the folder handles of
//! `dir.rs`: an advisory lock that dies with its process, an exclusive create that never
//! follows a link, and an open that never waits. Linux has them all; elsewhere each says `Unsupported`
//! and the protocol takes its fallback (docs/outputs.md).

use std::fs::{File, OpenOptions};
use std::io;
use std::path::Path;

/// Creates `path` for writing; fails if anything is there already, a symbolic link included
/// (`O_CREAT | O_EXCL`, plus `O_NOFOLLOW` where the OS has it): a name planted before us is
/// never written through.
pub fn create_new(path: &Path) -> io::Result<File> {
    let mut options = OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc_flags::NOFOLLOW);
    }
    options.open(path)
}

/// Opens `path` for reading without following a final symbolic link and without waiting: a
/// FIFO planted at the name opens at once (`O_NONBLOCK`) instead of blocking until a writer
/// comes, and the caller's regular-file check on the handle then refuses it.
pub fn open_no_follow(path: &Path) -> io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc_flags::NOFOLLOW | libc_flags::NONBLOCK);
    }
    options.open(path)
}

#[cfg(target_os = "linux")]
mod libc_flags {
    pub const NOFOLLOW: i32 = libc::O_NOFOLLOW;
    pub const NONBLOCK: i32 = libc::O_NONBLOCK;
}
#[cfg(all(unix, not(target_os = "linux")))]
mod libc_flags {
    // Not linked to libc here: O_CREAT | O_EXCL already refuses a final link.
    pub const NOFOLLOW: i32 = 0;
    pub const NONBLOCK: i32 = 0;
}

/// Takes the exclusive advisory lock (`flock`) on `file` without waiting: `Ok(true)` when
/// taken, `Ok(false)` when another open file holds it. The kernel drops the lock when the last
/// descriptor of the holder closes, however its process ends (SIGKILL, an OOM kill, a resource
/// limit), and it does not depend on process ids, so a run in another PID namespace is seen
/// alive as it is.
#[cfg(target_os = "linux")]
pub fn try_lock(file: &File) -> io::Result<bool> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock on a descriptor this `File` owns for the duration of the call.
    let rc = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if rc == 0 {
        return Ok(true);
    }
    let e = io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(false),
        _ => Err(e),
    }
}

#[cfg(not(target_os = "linux"))]
pub fn try_lock(_: &File) -> io::Result<bool> {
    Err(io::ErrorKind::Unsupported.into())
}

/// The kernel or the file system has no such rename (vfat has neither flag; some network
/// file systems refuse them).
pub fn unsupported(e: &io::Error) -> bool {
    #[cfg(target_os = "linux")]
    if matches!(e.raw_os_error(), Some(libc::EINVAL | libc::ENOSYS)) {
        return true;
    }
    e.kind() == io::ErrorKind::Unsupported
}
