//! All-or-nothing outputs: a command's files and folders are written into staging folders
//! beside their targets and renamed into place only when everything succeeded.
//!
//! A command stages its targets first ([`Transaction::folder`], [`Transaction::file`]), writes
//! through the transaction under the targets' own paths (which it redirects into the staging
//! folders, so every error names the user's path), and ends with [`Transaction::commit`].
//! Dropped without a commit (an error, a panic that unwinds), it removes its staging folders
//! and every parent folder it created: the user finds exactly what was there before.
//!
//! The protocol, and the invariants it keeps, are in docs/outputs.md:
//! - a run writes only into staging folders it made itself ([`stage`]): random names,
//!   exclusive creation, never a link followed, never a name reused;
//! - an existing folder is replaced only when it is an earlier output of the same command (it
//!   holds the command's marker file and nothing its manifest, [`MANIFEST`](super::MANIFEST), does not list),
//!   or is empty; this is checked once before any work, and again on the old folder itself
//!   after it has been swapped out atomically, where no path can reach it: an entry that
//!   appeared in between makes the run swap back and refuse ([`replace`]);
//! - the old output is then removed only as far as its manifest names; anything else is moved
//!   aside, visible, and reported, never deleted;
//! - no output replaces a file the command read: inputs are compared by identity (device and
//!   inode, [`crate::files::identity`]), so no spelling, case folding or link gets past.

use std::fs::{self, File};
use std::path::{Path, PathBuf};

use super::replace::{self, Placed};
use super::stage::{self, Stage};
use super::staged::{io, Kind, Staged};
use super::{sys, OutputError};
use crate::files::identity::{self, FileId};

/// A test's hook into [`Transaction::commit`], run at the named point with the staged item
/// (`Send + Sync`, so that a transaction is `Sync` in tests too: files are written into it from
/// several threads).
#[cfg(test)]
pub(super) type Hook = Box<dyn Fn(replace::Point, &Path) + Send + Sync>;
#[cfg(not(test))]
type Hook = std::convert::Infallible;

/// A set of outputs that appear together at `commit`, or not at all.
#[derive(Default)]
pub struct Transaction {
    staged: Vec<Staged>,
    /// Parent folders this transaction created, outermost first; removed again on rollback.
    created: Vec<PathBuf>,
    /// Inputs named to this transaction (the registry of files read holds the rest).
    inputs: Vec<(FileId, PathBuf)>,
    committed: bool,
    /// Called at fixed points of the commit: how the tests drive races deterministically.
    pub(super) hook: Option<Hook>,
}

impl std::fmt::Debug for Transaction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Transaction")
            .field("staged", &self.staged)
            .field("created", &self.created)
            .finish_non_exhaustive()
    }
}

impl Transaction {
    pub fn new() -> Self {
        Self::default()
    }

    /// Stages the folder `target` (its missing parents are created, and removed again if the
    /// transaction is dropped). Fails now, before any work, when `target` exists and is not
    /// an earlier output holding `marker`.
    pub fn folder(&mut self, target: &Path, marker: &str) -> Result<(), OutputError> {
        let (resolved, name) = named(target)?;
        self.check_new(target, &resolved, &name)?;
        check_not_inside_an_output(target, &resolved)?;
        replace::check_replaceable(target, &resolved, marker, &self.inputs())?;
        let parent = parent_of(&resolved);
        self.create_parents(&parent)?;
        self.stage(target, resolved, name, &parent, |item| fs::create_dir(item))?;
        let staged = self.staged.last_mut().expect("just staged");
        staged.kind = Kind::Folder {
            marker: marker.to_owned(),
        };
        Ok(())
    }

    /// Records an input file of the command by identity: staging an output over it, before
    /// or after this, fails (`--json scene.toml` must not replace the scene it benchmarks).
    /// Files read through [`crate::files::read_regular_file`] are recorded without this.
    pub fn input(&mut self, path: &Path) -> Result<(), OutputError> {
        let Some(id) = FileId::of_path(path) else {
            return Ok(()); // the command's own read reports a missing input
        };
        self.inputs.push((id, path.to_owned()));
        for s in self.staged.iter().filter(|s| matches!(s.kind, Kind::File)) {
            check_not_an_input(&s.given, &s.target, &self.inputs)?;
        }
        Ok(())
    }

    /// Checks the staged files against every input so far: a command that stages its outputs
    /// before it reads the files a scene names (meshes, textures) calls this after reading
    /// them, so that an output over one is refused before the work, not at the commit.
    pub fn check_inputs(&self) -> Result<(), OutputError> {
        let inputs = self.inputs();
        for s in self.staged.iter().filter(|s| matches!(s.kind, Kind::File)) {
            check_not_an_input(&s.given, &s.target, &inputs)?;
        }
        Ok(())
    }

    /// Stages the file `target`, whose folder must exist; an existing file is replaced,
    /// unless it is one of the command's inputs.
    pub fn file(&mut self, target: &Path) -> Result<(), OutputError> {
        // `h.png/` and `h.png/.` are a folder's names: the components drop the slash and the
        // dot, and a file `h.png` was written under them.
        if names_a_folder(target) {
            return Err(OutputError::FolderName {
                path: target.to_owned(),
            });
        }
        let (resolved, name) = named(target)?;
        self.check_new(target, &resolved, &name)?;
        check_not_an_input(target, &resolved, &self.inputs())?;
        check_file_target(target, &resolved)?;
        check_not_anothers(target, &resolved)?;
        let parent = parent_of(&resolved);
        if !parent.is_dir() {
            return Err(OutputError::NoFolder {
                path: target.to_owned(),
                folder: parent,
            });
        }
        // The file itself is created by the first write (`create`), exclusively.
        self.stage(target, resolved, name, &parent, |_| Ok(()))
    }

    /// Where a write addressed to `path` (a staged file, or a path inside a staged folder)
    /// goes until the commit; its parent folders inside the staged folder are created.
    pub fn path_for(&self, path: &Path) -> Result<PathBuf, OutputError> {
        let (staged, rest) = self
            .staged
            .iter()
            .find_map(|s| Some((s, path.strip_prefix(&s.given).ok()?)))
            .ok_or_else(|| OutputError::NotStaged {
                path: path.to_owned(),
            })?;
        let to = match rest.as_os_str().is_empty() {
            true => staged.item(),
            false => staged.item().join(rest),
        };
        if let (Some(dir), Some(user_dir)) = (to.parent(), path.parent()) {
            fs::create_dir_all(dir).map_err(|source| OutputError::CreateFolder {
                path: user_dir.to_owned(),
                source,
            })?;
        }
        Ok(to)
    }

    /// The files written so far into the staged folder `folder` (as its target is spelled),
    /// as relative paths with `/`, sorted: what a command says it wrote, from what it wrote.
    pub fn written(&self, folder: &Path) -> Result<Vec<String>, OutputError> {
        let item = self.path_for(folder)?;
        let mut files = super::manifest::entries(&item).map_err(|source| OutputError::Io {
            path: folder.to_owned(),
            source,
        })?;
        files.retain(|f| item.join(f).is_file());
        Ok(files)
    }

    /// Creates the file a write addressed to `path` goes to (see [`Transaction::path_for`]),
    /// exclusively: a file is written once per transaction, and never through a link.
    pub fn create(&self, path: &Path) -> Result<File, OutputError> {
        let to = self.path_for(path)?;
        sys::create_new(&to).map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })
    }

    /// Places every staged output. Each target is checked again first, so that one taken
    /// meanwhile fails before anything is placed; each folder is checked once more after it
    /// is swapped out (`replace`).
    pub fn commit(mut self) -> Result<(), OutputError> {
        let inputs = self.inputs();
        for s in &self.staged {
            match &s.kind {
                Kind::File => {
                    check_file_target(&s.given, &s.target)?;
                    check_not_an_input(&s.given, &s.target, &inputs)?;
                }
                Kind::Folder { marker } => {
                    replace::write_manifest(s)?;
                    replace::check_replaceable(&s.given, &s.target, marker, &inputs)?;
                }
            }
        }
        let mut kept = Vec::new();
        for s in &mut self.staged {
            match replace::place(s, &inputs, hook(&self.hook))? {
                Placed::Clean => {}
                Placed::KeptAside(entries, at) => kept.push((s.given.clone(), entries, at)),
            }
        }
        self.committed = true;
        match kept.into_iter().next() {
            None => Ok(()),
            Some((path, entries, kept)) => Err(OutputError::KeptAside {
                path,
                entries,
                kept,
            }),
        }
    }

    /// Every input still in place: those named here and every file the process has read.
    fn inputs(&self) -> Vec<(FileId, PathBuf)> {
        let named = self.inputs.iter().filter(|(id, p)| identity::still(*id, p));
        let mut all: Vec<_> = named.cloned().collect();
        all.extend(identity::read_so_far());
        all
    }

    /// Sweeps the dead runs' staging folders for `name`, makes this run's, and makes the
    /// staged item in it.
    fn stage(
        &mut self,
        given: &Path,
        target: PathBuf,
        name: String,
        parent: &Path,
        make: impl FnOnce(&Path) -> std::io::Result<()>,
    ) -> Result<(), OutputError> {
        stage::sweep_dead(parent, &name);
        let stage = Stage::create(parent, &name).map_err(io(given))?;
        let staged = Staged {
            given: given.to_owned(),
            target,
            name,
            stage,
            kind: Kind::File,
        };
        make(&staged.item()).map_err(io(given))?;
        self.staged.push(staged);
        Ok(())
    }

    /// The same target twice would make one output silently overwrite the other, however it
    /// is spelt (`x` and `sub/../x`, `./x`, an absolute path, a linked folder): targets are
    /// compared by their folder's identity and their name.
    fn check_new(&self, given: &Path, resolved: &Path, name: &str) -> Result<(), OutputError> {
        let folder = FileId::of_path(&parent_of(resolved));
        let same = |s: &Staged| {
            s.given == given
                || (folder.is_some()
                    && s.name == name
                    && FileId::of_path(&parent_of(&s.target)) == folder)
        };
        match self.staged.iter().any(same) {
            true => Err(OutputError::Twice {
                path: given.to_owned(),
            }),
            false => Ok(()),
        }
    }

    /// Creates the missing folders of `dir`, remembering each for the rollback.
    fn create_parents(&mut self, dir: &Path) -> Result<(), OutputError> {
        let missing: Vec<&Path> = dir
            .ancestors()
            .take_while(|d| !d.as_os_str().is_empty() && fs::symlink_metadata(d).is_err())
            .collect();
        for d in missing.into_iter().rev() {
            fs::create_dir(d).map_err(|source| OutputError::CreateFolder {
                path: d.to_owned(),
                source,
            })?;
            self.created.push(d.to_owned());
        }
        Ok(())
    }
}

impl Drop for Transaction {
    fn drop(&mut self) {
        // The staging folders go with their `Stage`s (they are this run's own).
        self.staged.clear();
        if self.committed {
            return;
        }
        // Only folders this run made, and only while empty (`remove_dir`).
        for d in self.created.iter().rev() {
            let _ = fs::remove_dir(d);
        }
    }
}

/// A file output replaces only a regular file: not a folder, and not a symbolic link, FIFO,
/// device or socket, which a rename would replace by a file (`--json /dev/stdout` would
/// replace the system's link; a link's target would be left as it was, not written).
fn check_file_target(given: &Path, target: &Path) -> Result<(), OutputError> {
    let Ok(meta) = fs::symlink_metadata(target) else {
        return Ok(()); // free
    };
    let t = meta.file_type();
    if t.is_file() {
        return Ok(());
    }
    if t.is_dir() || fs::metadata(target).is_ok_and(|m| m.is_dir()) {
        return Err(OutputError::IsAFolder {
            path: given.to_owned(),
        });
    }
    let what = if t.is_symlink() {
        "a symbolic link (name the file it leads to instead)"
    } else {
        "not a regular file (a FIFO, device or socket)"
    };
    Err(OutputError::NotAFile {
        path: given.to_owned(),
        what,
    })
}

/// A file output never replaces a file that an output folder (this command's or another's)
/// lists as its own: `compare A B --heatmap ref/sensor.png` would have put a heatmap in a
/// reference's place, and that folder would still claim it. Every folder above the file that
/// holds a manifest is asked, under the spelling its listings give (a case fold included).
/// A new name beside such files is not refused: the folder's next run says it is foreign.
fn check_not_anothers(given: &Path, target: &Path) -> Result<(), OutputError> {
    let Some(listed) = fs::symlink_metadata(target)
        .ok()
        .and_then(|_| listed_path(target))
    else {
        return check_not_inside_an_output(given, target);
    };
    for folder in listed.ancestors().skip(1) {
        let manifest = folder.join(super::manifest::MANIFEST);
        if !fs::symlink_metadata(&manifest).is_ok_and(|m| m.is_file()) {
            continue;
        }
        let Ok(inside) = listed.strip_prefix(folder) else {
            continue;
        };
        let inside = inside
            .to_string_lossy()
            .replace(std::path::MAIN_SEPARATOR, "/");
        if inside == super::manifest::MANIFEST
            || super::manifest::read_manifest(folder).contains(&inside)
        {
            return Err(OutputError::AnothersFile {
                path: given.to_owned(),
                output: folder.to_owned(),
                manifest: super::manifest::MANIFEST,
            });
        }
    }
    Ok(())
}

/// Refuses a new file or folder inside another output's folder (one holding a manifest):
/// that output would then hold something it did not write, and its command would refuse to
/// replace it on its next run (`--heatmap ref/x.png` blocked `reference --out ref`; so did
/// `render --out ref/sub`). The folders that do not exist yet are skipped up to one that does.
pub(super) fn check_not_inside_an_output(given: &Path, target: &Path) -> Result<(), OutputError> {
    let parent = parent_of(target);
    let Some(existing) = (parent.ancestors()).find_map(|a| fs::canonicalize(a).ok()) else {
        return Ok(());
    };
    for folder in existing.ancestors() {
        let manifest = folder.join(super::manifest::MANIFEST);
        if fs::symlink_metadata(&manifest).is_ok_and(|m| m.is_file()) {
            return Err(OutputError::InsideAnOutput {
                path: given.to_owned(),
                output: folder.to_owned(),
                manifest: super::manifest::MANIFEST,
            });
        }
    }
    Ok(())
}

/// A file output's `target` must not be an input, under any name: neither its own entry (a link
/// to an input is not the input, but a hard link is) nor what it leads to.
fn check_not_an_input(
    given: &Path,
    target: &Path,
    inputs: &[(FileId, PathBuf)],
) -> Result<(), OutputError> {
    let ids = [
        fs::symlink_metadata(target)
            .ok()
            .and_then(|m| FileId::of(&m)),
        fs::metadata(target).ok().and_then(|m| FileId::of(&m)),
    ];
    // By identity first; then, for a target that exists, by the path its folders list.
    let listed = ids
        .iter()
        .any(Option::is_some)
        .then(|| listed_path(target))
        .flatten();
    let same = |(id, input): &&(FileId, PathBuf)| {
        ids.contains(&Some(*id)) || listed.is_some() && listed == listed_path(input)
    };
    match inputs.iter().find(same) {
        Some((_, input)) => Err(OutputError::IsAnInput {
            path: given.to_owned(),
            input: input.clone(),
        }),
        None => Ok(()),
    }
}

/// The path of the existing file `path` as its folders list it: canonical (links and `..`
/// resolved), then each component spelled as its folder's listing spells it. Identities miss
/// a case fold where the file system gives each spelling its own inode (vfat through FUSE:
/// `t.EXR` and `T.exr` are one file and two inodes, `DIR` and `dir` one folder and two), so
/// the folders are asked which names they hold: a component listed exactly keeps its
/// spelling (a case-sensitive file system changes nothing), one that is not takes the listed
/// name it folds to. None where the path cannot be resolved.
fn listed_path(path: &Path) -> Option<PathBuf> {
    let canonical = fs::canonicalize(path).ok()?;
    let mut listed = PathBuf::new();
    for component in canonical.components() {
        let std::path::Component::Normal(name) = component else {
            listed.push(component); // the root
            continue;
        };
        let name = name.to_str()?;
        let folded = name.to_lowercase();
        let mut found = None;
        for entry in fs::read_dir(&listed).ok()?.flatten() {
            let entry = entry.file_name();
            let Some(entry) = entry.to_str() else {
                continue;
            };
            if entry == name {
                found = Some(entry.to_owned());
                break;
            }
            if found.is_none() && entry.to_lowercase() == folded {
                found = Some(entry.to_owned());
            }
        }
        listed.push(found.unwrap_or_else(|| name.to_owned()));
    }
    Some(listed)
}

/// The hook as `place` takes it.
#[cfg(test)]
fn hook(h: &Option<Hook>) -> replace::Hook<'_> {
    h.as_deref().map(|f| f as &dyn Fn(replace::Point, &Path))
}
#[cfg(not(test))]
fn hook(_: &Option<Hook>) -> replace::Hook<'_> {
    None
}

/// The target with a final name to stage it under: `.` and `..` are resolved to the folder
/// they stand for; `/` has no name and cannot be an output.
fn named(target: &Path) -> Result<(PathBuf, String), OutputError> {
    let no_name = || OutputError::NoName {
        path: target.to_owned(),
    };
    // `out/.` names `out` (its components drop the `.`): renamed onto as spelled, it did all
    // the work and then failed with EBUSY. `..` is resolved against the file system instead.
    let resolved = match target.file_name() {
        Some(_) => target.components().collect(),
        None => fs::canonicalize(target).map_err(|source| OutputError::Io {
            path: target.to_owned(),
            source,
        })?,
    };
    let name = resolved.file_name().ok_or_else(no_name)?;
    let name = name.to_str().ok_or_else(|| OutputError::NotUtf8 {
        path: target.to_owned(),
    })?;
    let name = name.to_owned();
    Ok((resolved, name))
}

/// Whether `path` as written can only name a folder: it ends in `/`, or its last component is
/// `.` or `..`.
pub fn names_a_folder(path: &Path) -> bool {
    let bytes = path.as_os_str().as_encoded_bytes();
    let last = bytes.rsplit(|&b| b == b'/').next().unwrap_or_default();
    bytes.ends_with(b"/") || last == b"." || last == b".."
}

/// The folder holding `path` (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}
