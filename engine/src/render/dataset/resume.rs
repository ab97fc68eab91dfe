//! Resumable datasets: a long run keeps the frames it has finished in a work folder beside
//! its output (`OUT.partial`), so that a run stopped by Ctrl-C, a crash, a lost machine or a
//! full disk goes on from where it stopped (`--resume`) instead of starting again.
//!
//! The work folder is a journal and the frame folders it lists:
//! - `journal.jsonl`, first line the run's [`RunKey`] (what the frames' bytes depend on: the
//!   inputs' contents, the poses, the lookup, the device, this version), then one line per
//!   finished frame with its files' names and sizes and its index line;
//! - `frames/NNNNNN/`, written as the output's.
//!
//! A frame is journaled only after its files and their folder are on disk (`fsync`), so the
//! journal never names a frame that a crash can take back; a frame folder the journal does
//! not name is a frame cut short, written again. A resumed run takes the folder only when it
//! is a real folder (not a link), holds nothing but those entries, and its key is this run's;
//! anything else is refused, naming what differs, and left as it is. Two runs never share it
//! (an advisory lock on the journal). When every frame is done, the frames are linked (or,
//! where the file system has no hard links, copied) into the staged output, which is placed
//! as every output is; only then is the work folder removed, entry by entry, as far as the
//! journal names.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{DatasetError, Frame};
use crate::output::{OutputError, Transaction};
use crate::sensor::dataset::{frame_folder, FRAME_FILES};

/// The work folder's name is the output's with this added.
pub const WORK_SUFFIX: &str = ".partial";
/// The journal, inside the work folder.
pub const JOURNAL: &str = "journal.jsonl";
/// The journal's format; a journal of another format is refused.
const FORMAT: u32 = 1;
/// Longest journal line read back: a frame's line is a few hundred bytes.
const MAX_LINE: usize = 64 << 10;

/// What a dataset's bytes depend on: a run resumes only a work folder whose key is its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunKey {
    /// This program's version.
    pub specchio: String,
    /// The scene's files (the scene, its meshes and textures) and the trajectory file, by
    /// length and CRC-32 (`files::digest`), sorted.
    pub inputs: Vec<String>,
    /// The poses as checked, by CRC-32 of their exact values (a grid has no file).
    pub poses: String,
    pub frames: usize,
    pub lookup: String,
    pub ground_truth: String,
    /// The device's name and driver: another device may round differently.
    pub device: String,
}

/// One journal line.
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum Line {
    Run { format: u32, key: RunKey },
    Frame(Journaled),
}

/// A finished frame: its files (name in its folder, size) and its index line.
#[derive(Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Journaled {
    frame: usize,
    files: Vec<(String, u64)>,
    index: String,
}

/// A dataset's work folder, opened by this run (and locked while it is open).
pub struct WorkFolder {
    path: PathBuf,
    journal: File,
    done: BTreeMap<usize, Journaled>,
    frames: usize,
}

/// The device as a run key names it: its name and driver, since another driver may round
/// differently.
pub fn device_key(device: &crate::vk::physical::DeviceInfo) -> String {
    format!(
        "{} ({} {})",
        device.name, device.driver_name, device.driver_version
    )
}

/// The work folder of the output `out`: beside it, its name with [`WORK_SUFFIX`].
pub fn work_path(out: &Path) -> PathBuf {
    let out = match out.file_name() {
        Some(_) => out.to_owned(),
        None => fs::canonicalize(out).unwrap_or_else(|_| out.to_owned()),
    };
    let mut name = out.file_name().unwrap_or_default().to_owned();
    name.push(WORK_SUFFIX);
    out.with_file_name(name)
}

impl WorkFolder {
    /// Opens `out`'s work folder for a run keyed `key`: creates it when there is none, else
    /// takes it when it is this run's, with the frames it holds done.
    pub fn open(out: &Path, key: &RunKey) -> Result<WorkFolder, DatasetError> {
        let path = work_path(out);
        match fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Self::create(path, key),
            Err(e) => Err(io(&path)(e)),
            Ok(meta) if !meta.is_dir() => Err(refuse(
                &path,
                "is not a folder (a file or a link): it is no work folder of a dataset",
            )),
            Ok(_) => Self::take(path, key),
        }
    }

    fn create(path: PathBuf, key: &RunKey) -> Result<WorkFolder, DatasetError> {
        fs::create_dir(&path).map_err(io(&path))?;
        let at = path.join(JOURNAL);
        let journal = crate::output::create_new(&at).map_err(io(&at))?;
        lock(&journal, &path)?;
        let mut work = WorkFolder {
            path,
            journal,
            done: BTreeMap::new(),
            frames: key.frames,
        };
        let format = FORMAT;
        work.append(&Line::Run {
            format,
            key: key.clone(),
        })?;
        sync_folder(&work.path)?;
        Ok(work)
    }

    fn take(path: PathBuf, key: &RunKey) -> Result<WorkFolder, DatasetError> {
        let at = path.join(JOURNAL);
        let mut journal = open_journal(&at).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => refuse(&path, &format!("holds no {JOURNAL}: it is no work folder of a dataset; choose another --out, or move it away")),
            _ => io(&at)(e),
        })?;
        lock(&journal, &path)?;
        let (lines, complete) = read_lines(&mut journal, &at)?;
        let mut lines = lines.into_iter().enumerate();
        let theirs = match lines.next() {
            Some((_, Line::Run { format, key })) if format == FORMAT => key,
            _ => return Err(refuse(&at, "line 1: not a dataset run of this version")),
        };
        if let Some(why) = differs(&theirs, key) {
            return Err(refuse(
                &path,
                &format!("was made by another run ({why}): it cannot be resumed with these inputs; remove it to start again"),
            ));
        }
        let mut done = BTreeMap::new();
        for (n, line) in lines {
            match line {
                Line::Frame(f) if f.frame < key.frames => {
                    done.insert(f.frame, f);
                }
                _ => {
                    let why = format!("line {}: not a frame of this dataset", n + 1);
                    return Err(refuse(&at, &why));
                }
            }
        }
        // A line cut short by a crash is dropped; the frame it would name is done again.
        journal.set_len(complete).map_err(io(&at))?;
        journal.seek(SeekFrom::End(0)).map_err(io(&at))?;
        let mut work = WorkFolder {
            path,
            journal,
            done,
            frames: key.frames,
        };
        work.check_entries()?;
        work.done.retain(|_, f| on_disk(&work.path, f));
        Ok(work)
    }

    /// The work folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The frames finished and their index lines.
    pub fn done(&self) -> impl Iterator<Item = (usize, &str)> {
        self.done.iter().map(|(&i, f)| (i, f.index.as_str()))
    }

    /// Writes `frame` into the work folder and journals it once it is on disk.
    pub fn write(&mut self, frame: &Frame) -> Result<(), DatasetError> {
        let folder_name = frame_folder(frame.frame);
        let folder = self.path.join(&folder_name);
        self.clear_cut_short(&folder)?;
        let frames = self.path.join("frames");
        if !frames.exists() {
            fs::create_dir(&frames).map_err(io(&frames))?;
            sync_folder(&self.path)?;
        }
        fs::create_dir(&folder).map_err(io(&folder))?;
        let mut files = Vec::with_capacity(frame.files.len());
        for (rel, bytes) in &frame.files {
            let name = (rel.strip_prefix(&folder_name).ok())
                .and_then(|n| n.to_str())
                .filter(|n| allowed(n))
                .ok_or_else(|| refuse(rel, "is not a file of a frame folder (a bug)"))?;
            let at = folder.join(name);
            let mut file = crate::output::create_new(&at).map_err(io(&at))?;
            (file.write_all(bytes).and_then(|()| file.sync_all())).map_err(io(&at))?;
            files.push((name.to_owned(), bytes.len() as u64));
        }
        sync_folder(&folder)?;
        sync_folder(&frames)?;
        let journaled = Journaled {
            frame: frame.frame,
            files,
            index: frame.index_line.clone(),
        };
        self.append(&Line::Frame(journaled.clone()))?;
        self.done.insert(frame.frame, journaled);
        Ok(())
    }

    /// Links every finished frame's files into the staged output `root` (copies where the
    /// file system has no hard links): the work folder keeps them until the output is placed.
    pub fn link_into(&self, out: &Transaction, root: &Path) -> Result<(), DatasetError> {
        for f in self.done.values() {
            let folder = frame_folder(f.frame);
            for (name, _) in &f.files {
                let from = self.path.join(&folder).join(name);
                let to = out.path_for(&root.join(&folder).join(name))?;
                if fs::hard_link(&from, &to).is_err() {
                    fs::copy(&from, &to).map_err(io(&from))?;
                }
            }
        }
        Ok(())
    }

    /// Removes the work folder, as far as the journal names it (after the output is placed).
    /// What could not be removed is returned, to be said.
    pub fn remove(self) -> Vec<String> {
        let mut left = Vec::new();
        let mut gone = |r: std::io::Result<()>, p: &Path| {
            if let Err(e) = r {
                left.push(format!("{}: {e}", p.display()));
            }
        };
        for f in self.done.values() {
            let folder = self.path.join(frame_folder(f.frame));
            for (name, _) in &f.files {
                gone(fs::remove_file(folder.join(name)), &folder.join(name));
            }
            gone(fs::remove_dir(&folder), &folder);
        }
        let frames = self.path.join("frames");
        if frames.exists() {
            gone(fs::remove_dir(&frames), &frames);
        }
        let journal = self.path.join(JOURNAL);
        gone(fs::remove_file(&journal), &journal);
        gone(fs::remove_dir(&self.path), &self.path);
        left
    }

    fn append(&mut self, line: &Line) -> Result<(), DatasetError> {
        let at = self.path.join(JOURNAL);
        let mut text = serde_json::to_string(line).map_err(|e| refuse(&at, &e.to_string()))?;
        text.push('\n');
        (self.journal.write_all(text.as_bytes())).map_err(io(&at))?;
        self.journal.sync_data().map_err(io(&at))
    }

    /// Every entry is the journal, `frames`, or a frame folder of this dataset holding frame
    /// files: anything else is someone else's, and the folder is not taken.
    fn check_entries(&self) -> Result<(), DatasetError> {
        for name in names(&self.path)? {
            if name != JOURNAL && name != "frames" {
                return Err(foreign(&self.path, &name));
            }
        }
        let frames = self.path.join("frames");
        if !frames.exists() {
            return Ok(());
        }
        for name in names(&frames)? {
            let ours = (name.len() == 6 && name.bytes().all(|b| b.is_ascii_digit()))
                .then(|| name.parse::<usize>().ok())
                .flatten()
                .is_some_and(|i| i < self.frames);
            let folder = frames.join(&name);
            if !ours || !is_real_folder(&folder) {
                return Err(foreign(&frames, &name));
            }
            for file in names(&folder)? {
                if !allowed(&file) || !is_regular(&folder.join(&file)) {
                    return Err(foreign(&folder, &file));
                }
            }
        }
        Ok(())
    }

    /// Removes what a frame cut short left in `folder` (only frame files: `check_entries`).
    fn clear_cut_short(&mut self, folder: &Path) -> Result<(), DatasetError> {
        if !folder.exists() {
            return Ok(());
        }
        for file in names(folder)? {
            let at = folder.join(&file);
            if !allowed(&file) || !is_regular(&at) {
                return Err(foreign(folder, &file));
            }
            fs::remove_file(&at).map_err(io(&at))?;
        }
        fs::remove_dir(folder).map_err(io(folder))
    }
}

/// The first field in which two keys differ, said for a person.
fn differs(theirs: &RunKey, ours: &RunKey) -> Option<String> {
    let field = if theirs.specchio != ours.specchio {
        format!("specchio {} against {}", theirs.specchio, ours.specchio)
    } else if theirs.frames != ours.frames {
        format!(
            "other poses: {} frames against {}",
            theirs.frames, ours.frames
        )
    } else if theirs.inputs != ours.inputs || theirs.poses != ours.poses {
        "the scene, its assets or the poses changed since".to_owned()
    } else if theirs.lookup != ours.lookup || theirs.ground_truth != ours.ground_truth {
        format!(
            "the {} lookup with {} ground truth, against {} with {}",
            theirs.lookup, theirs.ground_truth, ours.lookup, ours.ground_truth
        )
    } else if theirs.device != ours.device {
        format!("device {} against {}", theirs.device, ours.device)
    } else {
        return None;
    };
    Some(field)
}

/// A frame file's name: one of [`FRAME_FILES`] (`*` standing for any plain suffix).
fn allowed(name: &str) -> bool {
    FRAME_FILES.iter().any(|f| match f.split_once('*') {
        None => *f == name,
        Some((head, _)) => {
            name.len() > head.len() && name.starts_with(head) && !name.contains(['/', '\\'])
        }
    })
}

/// Whether the journaled frame's files are there, regular, with their sizes.
fn on_disk(work: &Path, f: &Journaled) -> bool {
    let folder = work.join(frame_folder(f.frame));
    f.files.iter().all(|(name, size)| {
        fs::symlink_metadata(folder.join(name)).is_ok_and(|m| m.is_file() && m.len() == *size)
    })
}

/// The journal's lines, and the length of its whole lines (a last line without its newline
/// was cut short).
fn read_lines(journal: &mut File, at: &Path) -> Result<(Vec<Line>, u64), DatasetError> {
    let mut text = Vec::new();
    let limit = (crate::sensor::dataset::trajectory::MAX_POSES as u64 + 1) * MAX_LINE as u64;
    (journal.take(limit).read_to_end(&mut text)).map_err(io(at))?;
    let complete = text.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let mut lines = Vec::new();
    for (n, line) in text[..complete].split(|&b| b == b'\n').enumerate() {
        if line.is_empty() && n > 0 {
            continue;
        }
        let parsed = (line.len() <= MAX_LINE)
            .then(|| serde_json::from_slice(line).ok())
            .flatten()
            .ok_or_else(|| refuse(at, &format!("line {}: not a journal line", n + 1)))?;
        lines.push(parsed);
    }
    Ok((lines, complete as u64))
}

fn open_journal(at: &Path) -> std::io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true).write(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NOFOLLOW);
    }
    let file = options.open(at)?;
    match file.metadata()?.is_file() {
        true => Ok(file),
        false => Err(std::io::Error::other("not a regular file")),
    }
}

fn lock(journal: &File, work: &Path) -> Result<(), DatasetError> {
    match crate::output::try_lock(journal) {
        Ok(true) => Ok(()),
        Ok(false) => Err(refuse(work, "is in use by another run")),
        // A file system without locks: the run goes on without (as the output protocol does).
        Err(_) => Ok(()),
    }
}

fn names(dir: &Path) -> Result<Vec<String>, DatasetError> {
    let mut names = Vec::new();
    for entry in fs::read_dir(dir).map_err(io(dir))? {
        let name = entry.map_err(io(dir))?.file_name();
        names.push(name.to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

fn is_real_folder(p: &Path) -> bool {
    fs::symlink_metadata(p).is_ok_and(|m| m.is_dir())
}

fn is_regular(p: &Path) -> bool {
    fs::symlink_metadata(p).is_ok_and(|m| m.is_file())
}

/// Makes a folder's new entries durable (where the file system can).
fn sync_folder(dir: &Path) -> Result<(), DatasetError> {
    match File::open(dir).and_then(|d| d.sync_all()) {
        // Some file systems cannot sync a folder; the journal still comes after the files.
        Err(e) if e.kind() == std::io::ErrorKind::InvalidInput => Ok(()),
        r => r.map_err(io(dir)),
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DatasetError + '_ {
    move |source| {
        DatasetError::Output(OutputError::Io {
            path: path.to_owned(),
            source,
        })
    }
}

fn refuse(path: &Path, why: &str) -> DatasetError {
    DatasetError::Resume {
        path: path.to_owned(),
        why: why.to_owned(),
    }
}

fn foreign(dir: &Path, name: &str) -> DatasetError {
    refuse(
        dir,
        &format!("holds {name}, which no dataset run wrote: refusing to resume it; move {name} out, or remove the work folder to start again"),
    )
}

#[cfg(test)]
mod tests;
