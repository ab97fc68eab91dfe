//! Numbered files that never replace anything: `PREFIX-0001.png`, `PREFIX-0002.png`, ... in a
//! folder, for outputs a person asks for one at a time (the viewer's screenshot key).
//!
//! The file is written whole under a hidden name of its own (an exclusive create), synced, and
//! then given its number by `tempfile`'s `persist_noclobber`: a rename that never replaces
//! (`renameat2` with `RENAME_NOREPLACE`) or, where the file system lacks that, a link that
//! fails if the name exists followed by an unlink of the hidden name. A file that appeared
//! under that number meanwhile (another viewer, a user's copy) is never replaced, the next
//! number is tried instead; and a reader never sees a half-written file under a numbered name.
//!
//! Only the hidden name and its removal are `tempfile`'s: the file is created by
//! [`sys::create_new`] (the permissions of any new file, not `tempfile`'s 0600; no final link
//! followed), and errors are this module's, naming the numbered path.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use super::{sys, OutputError};

/// The highest number: five digits once four are used up (after `-9999` comes `-10000`, not
/// the lowest free number, which sent the 10 000th shot back to `-0002`; a name sort then
/// puts `-10000` before `-9999`, a natural sort after it). Longer numbers (a date,
/// `-20240101`) are not of the series; a five-digit one of the user's is, and the series goes
/// on after it. Only past it does the series take the lowest free number, and a folder with
/// every one taken is refused.
const MAX_NUMBER: u32 = 99_999;

/// Writes `bytes` as the first free `PREFIX-NNNN.EXT` in `folder` (after the highest number
/// already there, else the lowest free one) and returns its path. Errors name that path (or
/// the first one tried), never the hidden one.
pub fn write_numbered(
    folder: &Path,
    prefix: &str,
    ext: &str,
    bytes: &[u8],
) -> Result<PathBuf, OutputError> {
    let first = first_candidate(folder, prefix, ext);
    let numbered = |n: u32| folder.join(format!("{prefix}-{n:04}.{ext}"));
    super::transaction::check_not_inside_an_output(&numbered(first), &numbered(first))?;
    let io_error = |source| OutputError::Io {
        path: numbered(first),
        source,
    };
    // `.PREFIX-RANDOM.partial`, created exclusively: a name that exists (another writer's, a
    // planted link) is never taken over, another is drawn. Dropped on any path below, the
    // hidden file is removed unless it was given its number.
    let hidden_prefix = format!(".{prefix}-");
    let mut hidden = tempfile::Builder::new()
        .prefix(&hidden_prefix)
        .suffix(".partial")
        .rand_bytes(16)
        .make_in(folder, sys::create_new)
        .map_err(io_error)?;
    let file = hidden.as_file_mut();
    (file.write_all(bytes).and_then(|()| file.sync_all())).map_err(io_error)?;
    place(hidden, bytes, first, &numbered)
}

/// Gives the written file `hidden` the first number not taken, from `first` up and then from
/// 1 (a rename or link that fails where the name exists). Where the file system has neither
/// (vfat on an old kernel, some network file systems), the hidden file goes and the number is
/// created exclusively and the bytes written into it.
fn place(
    hidden: NamedTempFile<File>,
    bytes: &[u8],
    first: u32,
    numbered: &dyn Fn(u32) -> PathBuf,
) -> Result<PathBuf, OutputError> {
    // None once the file system was found to have no way to place it.
    let mut hidden = Some(hidden);
    for n in (first..=MAX_NUMBER).chain(1..first) {
        let to = numbered(n);
        let made = match hidden.take().map(|h| h.persist_noclobber(&to)) {
            Some(Ok(_)) => Ok(()),
            Some(Err(e)) if e.error.kind() != io::ErrorKind::AlreadyExists && !exists(&to) => {
                drop(e.file);
                write_new(&to, bytes)
            }
            Some(Err(e)) => {
                hidden = Some(e.file);
                Err(e.error)
            }
            None => write_new(&to, bytes),
        };
        match made {
            Ok(()) => return Ok(to),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(source) => return Err(OutputError::Io { path: to, source }),
        }
    }
    Err(OutputError::Io {
        path: numbered(first),
        source: io::Error::other(format!("every number from 1 to {MAX_NUMBER} is taken")),
    })
}

/// Whether anything (a link included) is at `path`.
fn exists(path: &Path) -> bool {
    path.symlink_metadata().is_ok()
}

/// The bytes as a new file at `to` (never an existing one); a failed write removes the file
/// this call made.
fn write_new(to: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut file = sys::create_new(to)?;
    let written = file.write_all(bytes).and_then(|()| file.sync_all());
    if written.is_err() {
        let _ = std::fs::remove_file(to);
    }
    written
}

/// One past the highest number in 1..=MAX_NUMBER already in the folder (1 in an empty or
/// unreadable one), so that a new file sorts after the earlier ones even when some were
/// deleted; names with larger numbers (a date, say) are not numbers of this series.
fn first_candidate(folder: &Path, prefix: &str, ext: &str) -> u32 {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return 1;
    };
    let head = format!("{prefix}-");
    let tail = format!(".{ext}");
    let highest = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|name| {
            let number = name.strip_prefix(&head)?.strip_suffix(&tail)?;
            number.parse::<u32>().ok().filter(|&n| n <= MAX_NUMBER)
        })
        .max()
        .unwrap_or(0);
    if highest < MAX_NUMBER {
        highest + 1
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("specchio-numbered-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn numbers_follow_the_highest_and_nothing_is_replaced() {
        let dir = folder("follow");
        let first = write_numbered(&dir, "shot", "png", b"one").unwrap();
        assert_eq!(first, dir.join("shot-0001.png"));
        // A user's file at 0007: the next one goes after it, and 0007 keeps its bytes.
        std::fs::write(dir.join("shot-0007.png"), b"mine").unwrap();
        let next = write_numbered(&dir, "shot", "png", b"two").unwrap();
        assert_eq!(next, dir.join("shot-0008.png"));
        assert_eq!(std::fs::read(dir.join("shot-0007.png")).unwrap(), b"mine");
        assert_eq!(std::fs::read(&next).unwrap(), b"two");
        // No hidden file is left behind.
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A name taken between the scan and the link (here a file at 1, and a dangling symbolic
    /// link planted at 2) is skipped, not written through or replaced.
    #[test]
    fn a_number_taken_meanwhile_is_skipped() {
        let dir = folder("race");
        std::fs::write(dir.join("shot-0001.png"), b"old").unwrap();
        std::os::unix::fs::symlink(dir.join("nowhere"), dir.join("shot-0002.png")).unwrap();
        let mut source = NamedTempFile::new_in(&dir).unwrap();
        source.write_all(b"new").unwrap();
        let hidden = source.path().to_owned();
        let numbered = |n: u32| dir.join(format!("shot-{n:04}.png"));
        let got = place(source, b"new", 1, &numbered).unwrap();
        assert_eq!(got, dir.join("shot-0003.png"));
        assert_eq!(std::fs::read(&got).unwrap(), b"new");
        assert_eq!(std::fs::read(dir.join("shot-0001.png")).unwrap(), b"old");
        assert!(!dir.join("nowhere").exists(), "written through the link");
        assert!(!hidden.exists(), "the hidden name stays");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The numbered file has the permissions of any new file (the umask's), not the 0600 of
    /// a temporary one.
    #[test]
    fn the_file_has_a_new_files_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = folder("mode");
        let got = write_numbered(&dir, "shot", "png", b"x").unwrap();
        drop(sys::create_new(&dir.join("plain")).unwrap());
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode();
        assert_eq!(mode(&got), mode(&dir.join("plain")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The error names the file the user would have got, never the hidden one.
    #[test]
    fn a_missing_folder_is_an_error_naming_it() {
        let dir = folder("missing").join("not-there");
        let e = write_numbered(&dir, "shot", "png", b"x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not-there/shot-0001.png"), "{e}");
        assert!(!e.contains(".partial"), "{e}");
    }

    /// A name with a larger number (a date) is not part of the series; after 9999 comes 10000
    /// (not the lowest free number); a file at the last number sends the next one back to the
    /// lowest free number instead of refusing.
    #[test]
    fn large_numbers_block_nothing() {
        let dir = folder("large");
        std::fs::write(dir.join("shot-20240101.png"), b"dated").unwrap();
        assert_eq!(
            write_numbered(&dir, "shot", "png", b"a").unwrap(),
            dir.join("shot-0001.png")
        );
        std::fs::write(dir.join("shot-9999.png"), b"four digits").unwrap();
        assert_eq!(
            write_numbered(&dir, "shot", "png", b"b").unwrap(),
            dir.join("shot-10000.png")
        );
        std::fs::write(dir.join(format!("shot-{MAX_NUMBER}.png")), b"last").unwrap();
        assert_eq!(
            write_numbered(&dir, "shot", "png", b"c").unwrap(),
            dir.join("shot-0002.png")
        );
        assert_eq!(
            std::fs::read(dir.join("shot-20240101.png")).unwrap(),
            b"dated"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
