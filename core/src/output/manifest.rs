//! An output folder's manifest ([`MANIFEST`]: what the output wrote there), and what it lets
//! a later run do with an earlier output: remove what it lists, move anything else aside to a
//! visible folder, and recover a dead run's staging folder. Below both the staging (which
//! sweeps dead runs) and the placing (which retires the output it replaced): it knows neither.

use std::collections::HashSet;
use std::ffi::OsStr;
use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use super::dir::{Dir, Entry, Rename};
use super::sys;

/// The file in every output folder that lists, one relative path a line, what the output
/// wrote there: what a later run may replace.
pub const MANIFEST: &str = ".specchio-files";

/// The most bytes of an earlier output's manifest read (about a million entries).
const MAX_MANIFEST_BYTES: u64 = 64 << 20;
/// The most `NAME.kept-N` folders tried before giving up on a free name.
const MAX_KEPT_NAMES: u32 = 1000;

/// Where a swap in three renames parks the target's folder (and its alternative, should the
/// target be called that).
pub(super) const SPARE: &str = ".specchio-old";
pub(super) const SPARE_TOO: &str = ".specchio-old-";

/// The entries an earlier output's manifest lists (empty when it has none or it cannot be
/// read: then nothing of the folder counts as the output's).
pub(super) fn read_manifest(dir: &Path) -> HashSet<String> {
    let mut text = String::new();
    let read = sys::open_no_follow(&dir.join(MANIFEST)).and_then(|f| {
        if !f.metadata()?.is_file() {
            return Ok(0);
        }
        f.take(MAX_MANIFEST_BYTES).read_to_string(&mut text)
    });
    match read {
        Ok(_) => text.lines().map(str::to_owned).collect(),
        Err(_) => HashSet::new(),
    }
}

/// Every file and folder under `dir` (symbolic links not followed) as relative paths with
/// `/` separators, sorted; the manifest itself left out.
pub fn entries(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut found = Vec::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(rel) = pending.pop() {
        for entry in fs::read_dir(dir.join(&rel))? {
            let entry = entry?;
            let path = rel.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                pending.push(path.clone());
            }
            let name = path
                .to_string_lossy()
                .replace(std::path::MAIN_SEPARATOR, "/");
            if name != MANIFEST {
                found.push(name);
            }
        }
    }
    found.sort();
    Ok(found)
}

/// Removes what the old output's manifest lists from `old` (deepest first; a folder only when
/// empty; never a link, never through one: every step is relative to an open folder), then
/// the manifest and `old` itself (`name` in `stage`) if nothing else is left. Returns what is
/// left.
pub(super) fn retire(old: &Dir, stage: &Dir, name: &OsStr) -> Vec<String> {
    let mut listed: Vec<String> = read_manifest(&old.path())
        .into_iter()
        .filter(|e| is_plain_relative(e))
        .collect();
    listed.sort();
    for rel in listed.iter().rev() {
        let _ = remove_listed(old, rel);
    }
    let _ = old.remove(OsStr::new(MANIFEST), false);
    if stage.remove(name, true).is_ok() {
        return Vec::new();
    }
    entries(&old.path()).unwrap_or_else(|_| vec!["(unreadable)".to_owned()])
}

/// Removes the listed `rel` under `old`, walking its folders by handle (a link among them
/// ends the walk: what lies beyond is not the output's).
fn remove_listed(old: &Dir, rel: &str) -> std::io::Result<()> {
    let parts: Vec<&OsStr> = Path::new(rel).iter().collect();
    let Some((last, folders)) = parts.split_last() else {
        return Ok(());
    };
    let mut walked: Option<Dir> = None;
    for folder in folders {
        let next = walked.as_ref().unwrap_or(old).open_dir(folder)?;
        walked = Some(next);
    }
    let at = walked.as_ref().unwrap_or(old);
    match at.entry(last)? {
        Entry::Folder => at.remove(last, true),
        Entry::Other => at.remove(last, false),
        // No output writes a link: it is the user's.
        Entry::Link => Ok(()),
    }
}

/// A manifest line that names a path inside the folder: no root, no `..`, no `.`.
fn is_plain_relative(entry: &str) -> bool {
    !entry.is_empty()
        && Path::new(entry)
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
}

/// Moves `name` of `stage` (what remained of an earlier output) to `TARGET.kept-N` beside the
/// target, the first free N; None when no name could be taken.
pub(super) fn keep_aside(stage: &Dir, name: &OsStr, target: &Path) -> Option<PathBuf> {
    for n in 1..=MAX_KEPT_NAMES {
        let mut kept = target.to_owned().into_os_string();
        kept.push(format!(".kept-{n}"));
        let kept = PathBuf::from(kept);
        match stage.rename_out(name, &kept, Rename::NoReplace) {
            Ok(()) => return Some(kept),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) if sys::unsupported(&e) && fs::symlink_metadata(&kept).is_err() => {
                if stage.rename_out(name, &kept, Rename::Replace).is_ok() {
                    return Some(kept);
                }
            }
            Err(_) => {}
        }
    }
    None
}

/// A dead run's staging folder that may hold an earlier output of `target` (it was killed
/// between its swap and its end): each folder in it is retired by its manifest, as a live run
/// would, and what is left moved beside the target and reported on stderr. True when nothing
/// of the user's is left in it.
pub fn recover(stage: &Dir, name: &str, target: &Path) -> bool {
    let mut clean = true;
    for item in [name, SPARE, SPARE_TOO].map(OsStr::new) {
        if stage.entry(item).ok() != Some(Entry::Folder) {
            continue;
        }
        let Ok(folder) = stage.open_dir(item) else {
            clean = false;
            continue;
        };
        let left = retire(&folder, stage, item);
        if left.is_empty() {
            continue;
        }
        match keep_aside(stage, item, target) {
            Some(kept) => crate::warnings::warn(&format!(
                "a run killed while it replaced {} left {} in the earlier output that the \
                 output did not write: kept in {}",
                target.display(),
                left.join(", "),
                kept.display()
            )),
            None => clean = false,
        }
    }
    clean
}
