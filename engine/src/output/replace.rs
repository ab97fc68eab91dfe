//! Placing a staged output folder: into a free target in one rename, or over an earlier output
//! by an atomic swap, after which the old output, out of every path's reach in this run's
//! staging folder, is checked once more and removed only as far as its manifest names.
//!
//! Why the second check: between the first check and the swap anyone may write into the old
//! folder, and a check cannot be atomic with a rename. After the swap the old folder sits in
//! a staging folder under a random name that nobody else addresses, so what the check sees
//! there is final for every writer that goes by path. If it finds an entry the old output did
//! not write, the swap is undone and the run refuses, as it would have before any work. A
//! writer already inside the old folder (a shell whose working folder it is, an open folder
//! handle) can still add files while the old output is removed: those are moved aside to a
//! visible folder beside the target and reported, never deleted.

use std::collections::HashSet;
use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use super::sys;
use super::transaction::{io, Kind, Staged, MANIFEST};
use super::OutputError;
use crate::files::identity::FileId;

/// The most bytes of an earlier output's manifest read (about a million entries).
const MAX_MANIFEST_BYTES: u64 = 64 << 20;
/// The most `NAME.kept-N` folders tried before giving up on a free name.
const MAX_KEPT_NAMES: u32 = 1000;

/// Where a test's hook runs during [`place`] (the transaction passes none outside tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Point {
    /// After the first check, before the old output is swapped out.
    BeforeSwap,
    /// After the old output passed its second check, before it is removed.
    BeforeRetire,
}

/// A hook called with the point and the staged item's path.
pub type Hook<'a> = Option<&'a dyn Fn(Point, &Path)>;

/// How a staged output was placed.
pub enum Placed {
    Clean,
    /// Entries that appeared in the old output while it was removed: moved to this folder.
    KeptAside(Vec<String>, PathBuf),
}

/// Renames the staged output onto its target (see the module's documentation).
pub fn place(
    s: &mut Staged,
    inputs: &[(FileId, PathBuf)],
    hook: Hook,
) -> Result<Placed, OutputError> {
    let item = s.item();
    let Kind::Folder { marker } = &s.kind else {
        fs::rename(&item, &s.target).map_err(io(&s.given))?;
        return Ok(Placed::Clean);
    };
    let marker = marker.clone();
    run_hook(hook, Point::BeforeSwap, &item);
    if place_if_free(s, &item)? {
        return Ok(Placed::Clean);
    }
    let spare = spare_name(s);
    if let Err(e) = swap(&item, &s.target, &spare) {
        // A swap in three renames that failed at its last step leaves the old output at
        // `spare`: it must survive this run, named in the error.
        if fs::symlink_metadata(&spare).is_ok() {
            s.stage.keep();
            return Err(OutputError::StuckAside {
                path: s.given.clone(),
                at: spare,
                source: e,
            });
        }
        return Err(OutputError::Io {
            path: s.given.clone(),
            source: e,
        });
    }
    // `item` is now the old output.
    if let Err(refusal) = check_replaceable(&s.given, &item, &marker, inputs) {
        if let Err(e) = swap(&item, &s.target, &spare) {
            s.stage.keep();
            return Err(OutputError::StuckAside {
                path: s.given.clone(),
                at: item,
                source: e,
            });
        }
        return Err(refusal);
    }
    run_hook(hook, Point::BeforeRetire, &item);
    let left = retire(&item);
    if left.is_empty() {
        return Ok(Placed::Clean);
    }
    let kept = keep_aside(s, &item)?;
    Ok(Placed::KeptAside(left, kept))
}

fn run_hook(hook: Hook, point: Point, item: &Path) {
    if let Some(h) = hook {
        h(point, item);
    }
}

/// Renames `item` to the target when nothing is there; false when something is.
fn place_if_free(s: &Staged, item: &Path) -> Result<bool, OutputError> {
    match sys::rename_no_replace(item, &s.target) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) if sys::unsupported(&e) => match fs::symlink_metadata(&s.target) {
            // Without the flag: a plain rename, which the first check and this test guard.
            Err(_) => fs::rename(item, &s.target)
                .map(|_| true)
                .map_err(io(&s.given)),
            Ok(_) => Ok(false),
        },
        Err(source) => Err(OutputError::Io {
            path: s.given.clone(),
            source,
        }),
    }
}

/// A name in the staging folder that is neither the token nor the staged item.
fn spare_name(s: &Staged) -> PathBuf {
    let spare = if s.name == ".specchio-old" {
        ".specchio-old-"
    } else {
        ".specchio-old"
    };
    s.stage.dir().join(spare)
}

/// Swaps `a` and `b`: atomically where the file system can, else in three renames through
/// `spare` (a folder written into `b` meanwhile moves with it, so nothing is lost either way;
/// a failed middle step is undone).
fn swap(a: &Path, b: &Path, spare: &Path) -> std::io::Result<()> {
    match sys::exchange(a, b) {
        Err(e) if sys::unsupported(&e) => {}
        other => return other,
    }
    fs::rename(b, spare)?;
    if let Err(e) = fs::rename(a, b) {
        let _ = fs::rename(spare, b);
        return Err(e);
    }
    fs::rename(spare, a)
}

/// Ok when `target` is free, or a folder that is empty or an earlier output holding `marker`
/// and nothing its manifest does not list, and no input of the command.
pub fn check_replaceable(
    given: &Path,
    target: &Path,
    marker: &str,
    inputs: &[(FileId, PathBuf)],
) -> Result<(), OutputError> {
    let meta = match fs::symlink_metadata(target) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(OutputError::Io {
                path: given.to_owned(),
                source,
            })
        }
        Ok(meta) => meta,
    };
    if !meta.is_dir() {
        return Err(OutputError::NotAFolder {
            path: given.to_owned(),
        });
    }
    let held = entries(target).map_err(io(given))?;
    if held.is_empty() && !target.join(MANIFEST).exists() {
        return Ok(());
    }
    if !fs::symlink_metadata(target.join(marker)).is_ok_and(|m| m.is_file()) {
        return Err(OutputError::NotAnOutput {
            path: given.to_owned(),
            marker: marker.to_owned(),
        });
    }
    let listed = read_manifest(target);
    if let Some(entry) = held.iter().find(|e| !listed.contains(e.as_str())) {
        return Err(OutputError::Foreign {
            path: given.to_owned(),
            entry: entry.clone(),
            manifest: MANIFEST,
        });
    }
    for entry in &held {
        let meta = fs::symlink_metadata(target.join(entry)).ok();
        // No output writes a link: one at a listed name is the user's, put there since.
        if meta.as_ref().is_some_and(|m| m.file_type().is_symlink()) {
            return Err(OutputError::Foreign {
                path: given.to_owned(),
                entry: format!("{entry} (a symbolic link)"),
                manifest: MANIFEST,
            });
        }
        let id = meta.as_ref().and_then(FileId::of);
        if let Some((_, input)) = inputs.iter().find(|(i, _)| Some(*i) == id) {
            return Err(OutputError::IsAnInput {
                path: given.join(entry),
                input: input.clone(),
            });
        }
    }
    Ok(())
}

/// The entries an earlier output's manifest lists (empty when it has none or it cannot be
/// read: then nothing of the folder counts as the output's).
fn read_manifest(dir: &Path) -> HashSet<String> {
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

/// Lists the staged folder's contents in its manifest, just before it is placed.
pub fn write_manifest(s: &Staged) -> Result<(), OutputError> {
    let mut text = entries(&s.item()).map_err(io(&s.given))?.join("\n");
    text.push('\n');
    let to = s.item().join(MANIFEST);
    let mut file = sys::create_new(&to).map_err(io(&s.given.join(MANIFEST)))?;
    std::io::Write::write_all(&mut file, text.as_bytes()).map_err(io(&s.given.join(MANIFEST)))
}

/// Removes what the old output's manifest lists from `old` (deepest first; a folder only when
/// empty; never through a link), then the manifest and `old` itself if nothing else is left.
/// Returns what is left.
fn retire(old: &Path) -> Vec<String> {
    let mut listed: Vec<String> = read_manifest(old)
        .into_iter()
        .filter(|e| is_plain_relative(e))
        .collect();
    listed.sort();
    for rel in listed.iter().rev() {
        if !parents_are_folders(old, rel) {
            continue;
        }
        let path = old.join(rel);
        let _ = match fs::symlink_metadata(&path) {
            Ok(m) if m.is_dir() => fs::remove_dir(&path),
            Ok(_) => fs::remove_file(&path),
            Err(_) => Ok(()),
        };
    }
    let _ = fs::remove_file(old.join(MANIFEST));
    if fs::remove_dir(old).is_ok() {
        return Vec::new();
    }
    entries(old).unwrap_or_else(|_| vec!["(unreadable)".to_owned()])
}

/// A manifest line that names a path inside the folder: no root, no `..`, no `.`.
fn is_plain_relative(entry: &str) -> bool {
    !entry.is_empty()
        && Path::new(entry)
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
}

/// Every folder on the way from `root` to `rel` is a real folder, not a link (removing through
/// a link would reach outside).
fn parents_are_folders(root: &Path, rel: &str) -> bool {
    let mut at = root.to_owned();
    let parts: Vec<_> = Path::new(rel).components().collect();
    for part in &parts[..parts.len().saturating_sub(1)] {
        at.push(part);
        if !fs::symlink_metadata(&at).is_ok_and(|m| m.is_dir()) {
            return false;
        }
    }
    true
}

/// Moves `old` (what remained of the earlier output) to `NAME.kept-N` beside the target, the
/// first free N; if none can be taken the staging folder is kept where it is.
fn keep_aside(s: &mut Staged, old: &Path) -> Result<PathBuf, OutputError> {
    for n in 1..=MAX_KEPT_NAMES {
        let mut name = s.target.clone().into_os_string();
        name.push(format!(".kept-{n}"));
        let kept = PathBuf::from(name);
        match sys::rename_no_replace(old, &kept) {
            Ok(()) => return Ok(kept),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) if sys::unsupported(&e) && fs::symlink_metadata(&kept).is_err() => {
                if fs::rename(old, &kept).is_ok() {
                    return Ok(kept);
                }
            }
            Err(_) => {}
        }
    }
    s.stage.keep();
    Ok(old.to_owned())
}
