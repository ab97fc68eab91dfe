//! All-or-nothing outputs: a command's files and folders are written under hidden temporary
//! names beside their targets and renamed into place only when everything succeeded.
//!
//! A command stages its targets first ([`Transaction::folder`], [`Transaction::file`]), writes
//! through the transaction under the targets' own paths (which it redirects to the temporary
//! ones, so every error names the user's path), and ends with [`Transaction::commit`]. Dropped
//! without a commit (an error, a panic that unwinds), it removes its temporary files and
//! folders and every parent folder it created: the user finds exactly what was there before.
//!
//! An existing target folder is replaced atomically, but only when it is an earlier output of
//! the same command (it holds the command's marker file, e.g. `render.json`) or is empty;
//! anything else is refused, so `--out ~` can never delete a home folder. The marker alone
//! does not make a folder an earlier output: every output folder lists what it holds in
//! [`MANIFEST`], and a folder is replaced only when it holds nothing else (a scene file, the
//! user's notes or a source tree beside a `render.json` are never deleted).

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::OutputError;

/// Makes temporary names unique within the process (the pid makes them unique across
/// processes writing the same target at once).
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// The file in every output folder that lists, one relative path a line, what the output
/// wrote there: what a later run may replace.
pub const MANIFEST: &str = ".specchio-files";

#[derive(Debug)]
enum Kind {
    File,
    /// A folder, replaceable when it holds this marker file (or is empty).
    Folder {
        marker: String,
    },
}

#[derive(Debug)]
struct Staged {
    /// The target as the user spelled it: what writes are addressed to and errors name.
    given: PathBuf,
    /// The target the temporary is renamed to (`given`, or its real path for `.` and `..`).
    target: PathBuf,
    /// The hidden temporary beside `target`: `.NAME.partial-PID-N`.
    temp: PathBuf,
    kind: Kind,
}

/// A set of outputs that appear together at `commit`, or not at all.
#[derive(Debug, Default)]
pub struct Transaction {
    staged: Vec<Staged>,
    /// Parent folders this transaction created, outermost first; removed again on rollback.
    created: Vec<PathBuf>,
    /// The command's input files (real paths): no output may replace one.
    inputs: Vec<(PathBuf, PathBuf)>,
    committed: bool,
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
        self.check_new(target)?;
        check_replaceable(target, &resolved, marker)?;
        let parent = parent_of(&resolved);
        self.create_parents(&parent)?;
        remove_stale(&parent, &name);
        let temp = temp_beside(&parent, &name);
        fs::create_dir(&temp).map_err(io(target))?;
        self.staged.push(Staged {
            given: target.to_owned(),
            target: resolved,
            temp,
            kind: Kind::Folder {
                marker: marker.to_owned(),
            },
        });
        Ok(())
    }

    /// Records an input file of the command: staging it as an output file, before or after
    /// this, fails (`--json scene.toml` must not replace the scene it benchmarks).
    pub fn input(&mut self, path: &Path) -> Result<(), OutputError> {
        let Ok(real) = fs::canonicalize(path) else {
            return Ok(()); // the command's own read reports a missing input
        };
        for s in &self.staged {
            if matches!(s.kind, Kind::File) && fs::canonicalize(&s.target).is_ok_and(|t| t == real)
            {
                return Err(OutputError::IsAnInput {
                    path: s.given.clone(),
                    input: path.to_owned(),
                });
            }
        }
        self.inputs.push((path.to_owned(), real));
        Ok(())
    }

    /// Stages the file `target`, whose folder must exist; an existing file is replaced,
    /// unless it is one of the command's inputs ([`Transaction::input`]).
    pub fn file(&mut self, target: &Path) -> Result<(), OutputError> {
        let (resolved, name) = named(target)?;
        self.check_new(target)?;
        if let Ok(real) = fs::canonicalize(&resolved) {
            if let Some((input, _)) = self.inputs.iter().find(|(_, r)| *r == real) {
                return Err(OutputError::IsAnInput {
                    path: target.to_owned(),
                    input: input.clone(),
                });
            }
        }
        if resolved.is_dir() {
            return Err(OutputError::IsAFolder {
                path: target.to_owned(),
            });
        }
        let parent = parent_of(&resolved);
        if !parent.is_dir() {
            return Err(OutputError::NoFolder {
                path: target.to_owned(),
                folder: parent,
            });
        }
        remove_stale(&parent, &name);
        self.staged.push(Staged {
            given: target.to_owned(),
            target: resolved,
            temp: temp_beside(&parent, &name),
            kind: Kind::File,
        });
        Ok(())
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
        let to = if rest.as_os_str().is_empty() {
            staged.temp.clone()
        } else {
            staged.temp.join(rest)
        };
        if let (Some(dir), Some(user_dir)) = (to.parent(), path.parent()) {
            fs::create_dir_all(dir).map_err(|source| OutputError::CreateFolder {
                path: user_dir.to_owned(),
                source,
            })?;
        }
        Ok(to)
    }

    /// Renames every staged output into place. Each target is checked again first, so that
    /// one taken meanwhile fails before anything is placed.
    pub fn commit(mut self) -> Result<(), OutputError> {
        for s in &self.staged {
            if let Kind::Folder { marker } = &s.kind {
                write_manifest(s)?;
                check_replaceable(&s.given, &s.target, marker)?;
            }
        }
        for s in &self.staged {
            match s.kind {
                Kind::File => fs::rename(&s.temp, &s.target).map_err(io(&s.given))?,
                Kind::Folder { .. } => place_folder(s)?,
            }
        }
        self.committed = true;
        Ok(())
    }

    /// The same target twice would make one output silently overwrite the other.
    fn check_new(&self, target: &Path) -> Result<(), OutputError> {
        match self.staged.iter().find(|s| s.given == target) {
            Some(_) => Err(OutputError::Twice {
                path: target.to_owned(),
            }),
            None => Ok(()),
        }
    }

    /// Creates the missing folders of `dir`, remembering each for the rollback.
    fn create_parents(&mut self, dir: &Path) -> Result<(), OutputError> {
        let missing: Vec<&Path> = dir
            .ancestors()
            .take_while(|d| !d.as_os_str().is_empty() && !d.exists())
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
        if self.committed {
            return;
        }
        // Best effort: nothing useful can be done here about a folder that will not go.
        for s in self.staged.iter().rev() {
            let _ = match s.kind {
                Kind::File => fs::remove_file(&s.temp),
                Kind::Folder { .. } => fs::remove_dir_all(&s.temp),
            };
        }
        for d in self.created.iter().rev() {
            let _ = fs::remove_dir(d);
        }
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_owned(),
        source,
    }
}

/// The target with a final name to stage it under: `.` and `..` are resolved to the folder
/// they stand for; `/` has no name and cannot be an output.
fn named(target: &Path) -> Result<(PathBuf, String), OutputError> {
    let no_name = || OutputError::NoName {
        path: target.to_owned(),
    };
    let resolved = match target.file_name() {
        Some(_) => target.to_owned(),
        None => fs::canonicalize(target).map_err(|_| no_name())?,
    };
    let name = resolved.file_name().ok_or_else(no_name)?;
    Ok((resolved.clone(), name.to_string_lossy().into_owned()))
}

/// The folder holding `path` (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// A fresh hidden name in `dir`, so that the final rename stays on one file system (atomic).
fn temp_beside(dir: &Path, name: &str) -> PathBuf {
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    dir.join(format!(".{name}.partial-{}-{id}", std::process::id()))
}

/// Removes the temporaries of earlier runs for `name` in `dir` whose process is gone (killed
/// before it could clean up: SIGKILL, a second Ctrl-C, a power cut). Linux only: elsewhere
/// whether a process lives is not checked, and nothing is removed.
fn remove_stale(dir: &Path, name: &str) {
    if !cfg!(target_os = "linux") {
        return;
    }
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file_name.strip_prefix(&prefix) else {
            continue;
        };
        // `PID-N`, or `PID-N.old` for an earlier output moved aside.
        let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
        if pid.is_some_and(|pid| !Path::new(&format!("/proc/{pid}")).exists()) {
            let path = entry.path();
            let _ = if path.is_dir() {
                fs::remove_dir_all(&path)
            } else {
                fs::remove_file(&path)
            };
        }
    }
}

/// Ok when `target` is free, or a folder that is empty or an earlier output holding `marker`.
fn check_replaceable(given: &Path, target: &Path, marker: &str) -> Result<(), OutputError> {
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
    let empty = fs::read_dir(target).map_err(io(given))?.next().is_none();
    if empty {
        return Ok(());
    }
    if !target.join(marker).is_file() {
        return Err(OutputError::NotAnOutput {
            path: given.to_owned(),
            marker: marker.to_owned(),
        });
    }
    let listed = fs::read_to_string(target.join(MANIFEST)).unwrap_or_default();
    let listed: std::collections::HashSet<&str> = listed.lines().collect();
    let held = entries(target).map_err(io(given))?;
    match held.into_iter().find(|e| !listed.contains(e.as_str())) {
        Some(entry) => Err(OutputError::Foreign {
            path: given.to_owned(),
            entry,
            manifest: MANIFEST,
        }),
        None => Ok(()),
    }
}

/// Every file and folder under `dir` (symbolic links not followed) as relative paths with
/// `/` separators, sorted; the manifest itself left out.
fn entries(dir: &Path) -> std::io::Result<Vec<String>> {
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
fn write_manifest(s: &Staged) -> Result<(), OutputError> {
    let mut text = entries(&s.temp).map_err(io(&s.given))?.join("\n");
    text.push('\n');
    fs::write(s.temp.join(MANIFEST), text).map_err(io(&s.given.join(MANIFEST)))
}

/// Renames the staged folder to its target; an earlier output there is swapped out in one
/// step and then removed, so the target always holds either the old or the new output.
fn place_folder(s: &Staged) -> Result<(), OutputError> {
    if !s.target.exists() {
        return fs::rename(&s.temp, &s.target).map_err(io(&s.given));
    }
    match exchange(&s.temp, &s.target) {
        Ok(()) => {}
        // A file system without the atomic swap: move the old output aside first.
        Err(e) if swap_unsupported(&e) => replace_in_two_steps(s)?,
        Err(source) => {
            return Err(OutputError::Io {
                path: s.given.clone(),
                source,
            })
        }
    }
    // `temp` now holds the old output.
    let _ = fs::remove_dir_all(&s.temp);
    Ok(())
}

/// Old output to `temp.old`, new one into place, old one to `temp` (for the caller to remove);
/// if the second rename fails the old output is put back.
fn replace_in_two_steps(s: &Staged) -> Result<(), OutputError> {
    let mut aside = s.temp.clone().into_os_string();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    fs::rename(&s.target, &aside).map_err(io(&s.given))?;
    if let Err(source) = fs::rename(&s.temp, &s.target) {
        let _ = fs::rename(&aside, &s.target);
        return Err(OutputError::Io {
            path: s.given.clone(),
            source,
        });
    }
    fs::rename(&aside, &s.temp).map_err(io(&s.given))
}

/// The kernel or the file system cannot swap two paths atomically.
fn swap_unsupported(e: &std::io::Error) -> bool {
    #[cfg(target_os = "linux")]
    if matches!(e.raw_os_error(), Some(libc::EINVAL | libc::ENOSYS)) {
        return true;
    }
    e.kind() == std::io::ErrorKind::Unsupported
}

/// Swaps two paths atomically (Linux `renameat2(RENAME_EXCHANGE)`).
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| {
        CString::new(p.as_os_str().as_bytes())
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))
    };
    let (a, b) = (c(a)?, c(b)?);
    // SAFETY: two valid NUL-terminated paths relative to the working directory.
    let rc = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            a.as_ptr(),
            libc::AT_FDCWD,
            b.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fallback for file systems without the atomic swap: the new folder ends up in place,
    /// the old one where the temporary was (for the caller to remove), nothing else beside.
    #[test]
    fn the_two_step_replacement_puts_new_in_place_and_old_aside() {
        let dir = std::env::temp_dir().join(format!("specchio-swap-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let (target, temp) = (dir.join("out"), dir.join(".out.partial-1-0"));
        fs::create_dir_all(&target).unwrap();
        fs::write(target.join("old.txt"), b"old").unwrap();
        fs::create_dir_all(&temp).unwrap();
        fs::write(temp.join("new.txt"), b"new").unwrap();
        let staged = Staged {
            given: target.clone(),
            target: target.clone(),
            temp: temp.clone(),
            kind: Kind::Folder {
                marker: "render.json".into(),
            },
        };
        replace_in_two_steps(&staged).unwrap();
        assert!(target.join("new.txt").is_file());
        assert!(temp.join("old.txt").is_file());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 2);
        fs::remove_dir_all(&dir).unwrap();
    }
}
