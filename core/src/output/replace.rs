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

use std::ffi::{OsStr, OsString};
use std::fs;
use std::path::{Path, PathBuf};

use super::dir::Rename;
use super::manifest::{entries, keep_aside, read_manifest, retire, MANIFEST, SPARE, SPARE_TOO};
use super::staged::{io, Kind, Staged};
use super::sys;
use super::OutputError;
use crate::files::identity::FileId;

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
    let name = OsString::from(&s.name);
    // Before any rename out of the stage: a second signal's cleaner must not be removing its
    // files while they become the target's (`stage::remove_live`).
    s.stage.mark_placing();
    let Kind::Folder { marker } = &s.kind else {
        let stage = s.stage.handle();
        stage
            .rename_out(&name, &s.target, Rename::Replace)
            .map_err(io(&s.given))?;
        return Ok(Placed::Clean);
    };
    let marker = marker.clone();
    run_hook(hook, Point::BeforeSwap, &item);
    if place_if_free(s, &name)? {
        return Ok(Placed::Clean);
    }
    s.stage
        .mark_may_hold_earlier_output()
        .map_err(io(&s.given))?;
    let spare = spare_name(s);
    if let Err(e) = swap(s, &name, &spare) {
        // A swap in three renames that failed at its last step leaves the old output at
        // `spare`: it must survive this run, named in the error.
        if s.stage.handle().entry(&spare).is_ok() {
            return Err(stuck(s, &spare, e));
        }
        return Err(OutputError::Io {
            path: s.given.clone(),
            source: e,
        });
    }
    // `name` in the staging folder is now the old output: opened by handle, checked again.
    let old = s.stage.handle().open_dir(&name);
    let checked = match &old {
        Ok(old) => check_replaceable(&s.given, &old.path(), &marker, inputs),
        Err(_) => Err(OutputError::NotAFolder {
            path: s.given.clone(),
        }),
    };
    if let Err(refusal) = checked {
        drop(old);
        if let Err(e) = swap(s, &name, &spare) {
            return Err(stuck(s, &name, e));
        }
        return Err(refusal);
    }
    let old = old.expect("checked above");
    run_hook(hook, Point::BeforeRetire, &item);
    let left = retire(&old, s.stage.handle(), &name);
    if left.is_empty() {
        return Ok(Placed::Clean);
    }
    match keep_aside(s.stage.handle(), &name, &s.target) {
        Some(kept) => Ok(Placed::KeptAside(left, kept)),
        None => {
            s.stage.keep();
            Ok(Placed::KeptAside(left, item))
        }
    }
}

/// The error for an earlier output left at `at` in the staging folder, which is kept.
fn stuck(s: &mut Staged, at: &OsStr, source: std::io::Error) -> OutputError {
    s.stage.keep();
    OutputError::StuckAside {
        path: s.given.clone(),
        at: s.stage.dir().join(at),
        source,
    }
}

fn run_hook(hook: Hook, point: Point, item: &Path) {
    if let Some(h) = hook {
        h(point, item);
    }
}

/// Renames the staged `name` to the target when nothing is there; false when something is.
fn place_if_free(s: &Staged, name: &OsStr) -> Result<bool, OutputError> {
    let stage = s.stage.handle();
    match stage.rename_out(name, &s.target, Rename::NoReplace) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) if sys::unsupported(&e) => match fs::symlink_metadata(&s.target) {
            // Without the flag: a plain rename, which the first check and this test guard.
            Err(_) => stage
                .rename_out(name, &s.target, Rename::Replace)
                .map(|()| true)
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
fn spare_name(s: &Staged) -> OsString {
    OsString::from(if s.name == SPARE { SPARE_TOO } else { SPARE })
}

/// Swaps the staged `name` with the target: atomically where the file system can, else in
/// three renames through `spare` (a folder written into the target meanwhile moves with it,
/// so nothing is lost either way; a failed middle step is undone). The same call swaps back.
fn swap(s: &Staged, name: &OsStr, spare: &OsStr) -> std::io::Result<()> {
    let stage = s.stage.handle();
    match stage.rename_out(name, &s.target, Rename::Exchange) {
        Err(e) if sys::unsupported(&e) => {}
        other => return other,
    }
    stage.rename_in(&s.target, spare)?;
    if let Err(e) = stage.rename_out(name, &s.target, Rename::Replace) {
        let _ = stage.rename_out(spare, &s.target, Rename::Replace);
        return Err(e);
    }
    stage.rename(spare, (stage, name), Rename::Replace)
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

/// Lists the staged folder's contents in its manifest, just before it is placed.
pub fn write_manifest(s: &Staged) -> Result<(), OutputError> {
    let mut text = entries(&s.item()).map_err(io(&s.given))?.join("\n");
    text.push('\n');
    let to = s.item().join(MANIFEST);
    let mut file = sys::create_new(&to).map_err(io(&s.given.join(MANIFEST)))?;
    std::io::Write::write_all(&mut file, text.as_bytes()).map_err(io(&s.given.join(MANIFEST)))
}
