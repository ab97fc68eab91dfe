//! Numbered files that never replace anything: `PREFIX-0001.png`, `PREFIX-0002.png`, ... in a
//! folder, for outputs a person asks for one at a time (the viewer's screenshot key).
//!
//! The file is written whole under a hidden name of its own (an exclusive create), synced, and
//! then given its number with a link that fails if the name exists: a file that appeared
//! under that number meanwhile (another viewer, a user's copy) is never replaced, the next
//! number is tried instead; and a reader never sees a half-written file under a numbered name.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::{sys, OutputError};

/// The most numbers tried: a folder already holding this many is refused, not searched on.
const MAX_NUMBER: u32 = 9999;

/// Writes `bytes` as the first free `PREFIX-NNNN.EXT` in `folder` and returns its path.
pub fn write_numbered(
    folder: &Path,
    prefix: &str,
    ext: &str,
    bytes: &[u8],
) -> Result<PathBuf, OutputError> {
    let hidden = folder.join(format!(".{prefix}-{}.partial", std::process::id()));
    let io_error = |path: &Path| {
        let path = path.to_owned();
        move |source| OutputError::Io { path, source }
    };
    let written = sys::create_new(&hidden)
        .and_then(|mut file| file.write_all(bytes).and_then(|()| file.sync_all()))
        .map_err(io_error(&hidden));
    let first = first_candidate(folder, prefix, ext);
    let named = written.and_then(|()| link_first_free(&hidden, folder, (prefix, ext), first));
    // The hidden name goes whatever happened (the number, if one was taken, keeps the data).
    let _ = std::fs::remove_file(&hidden);
    named
}

/// Links `from` as the first number from `first` on that is not taken; the path it got.
fn link_first_free(
    from: &Path,
    folder: &Path,
    (prefix, ext): (&str, &str),
    first: u32,
) -> Result<PathBuf, OutputError> {
    for n in first..=MAX_NUMBER {
        let to = folder.join(format!("{prefix}-{n:04}.{ext}"));
        match std::fs::hard_link(from, &to) {
            Ok(()) => return Ok(to),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(source) => return Err(OutputError::Io { path: to, source }),
        }
    }
    Err(OutputError::Io {
        path: folder.join(format!("{prefix}-{MAX_NUMBER:04}.{ext}")),
        source: io::Error::other(format!(
            "every number up to {MAX_NUMBER} is taken in this folder"
        )),
    })
}

/// One past the highest number already in the folder (1 in an empty or unreadable one), so
/// that a new file sorts after the earlier ones even when some were deleted.
fn first_candidate(folder: &Path, prefix: &str, ext: &str) -> u32 {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return 1;
    };
    let head = format!("{prefix}-");
    let tail = format!(".{ext}");
    entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|name| {
            let number = name.strip_prefix(&head)?.strip_suffix(&tail)?;
            number.parse::<u32>().ok()
        })
        .max()
        .map_or(1, |highest| highest.saturating_add(1).min(MAX_NUMBER))
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
        let source = dir.join("source");
        std::fs::write(&source, b"new").unwrap();
        let got = link_first_free(&source, &dir, ("shot", "png"), 1).unwrap();
        assert_eq!(got, dir.join("shot-0003.png"));
        assert_eq!(std::fs::read(dir.join("shot-0001.png")).unwrap(), b"old");
        assert!(!dir.join("nowhere").exists(), "written through the link");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_folder_is_an_error_naming_it() {
        let dir = folder("missing").join("not-there");
        let e = write_numbered(&dir, "shot", "png", b"x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not-there"), "{e}");
    }
}
