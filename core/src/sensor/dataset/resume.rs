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
//! is a real folder (not a link), holds nothing but those entries, and its key is this run's,
//! and each journaled frame's index line (and its `pose.json`) is the one this run's plan
//! gives it; anything else is refused, naming what differs, and left as it is. Two runs never share it
//! (an advisory lock on the journal). When every frame is done, the frames are linked (or,
//! where the file system has no hard links, copied) into the staged output, which is placed
//! as every output is; only then is the work folder removed, entry by entry, as far as the
//! journal names.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::fs::{self, File};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::check::is_frame_file;
use super::{DatasetError, Frame};
use crate::output::{Dir, Entry, OutputError, Transaction};
use crate::sensor::dataset::frame_folder;

mod journal;
mod proof;

pub use journal::RunKey;
use journal::{check_journaled, differs, open_journal, read_journal, Journaled, Line, FORMAT};

/// The work folder's name is the output's with this added.
pub const WORK_SUFFIX: &str = ".partial";
/// The journal, inside the work folder.
pub const JOURNAL: &str = "journal.jsonl";
/// The folder of the frame folders, inside the work folder.
const FRAMES: &str = "frames";
/// A frame's pose file, checked against its index line, and the most of it read.
const POSE_FILE: &str = "pose.json";
const MAX_POSE_BYTES: u64 = 64 << 10;
/// A dataset's work folder, opened by this run (and locked while it is open). Removals go
/// through the folder handles (`output::Dir`), never by a path a link could redirect.
pub struct WorkFolder {
    path: PathBuf,
    dir: Dir,
    journal: File,
    done: BTreeMap<usize, Journaled>,
    frames: usize,
}

/// The work folder of the output `out`: beside it, its name with [`WORK_SUFFIX`].
pub fn work_path(out: &Path) -> PathBuf {
    // As the output's own name (`output::Transaction`): `out/.` is `out`.
    let out: PathBuf = match out.file_name() {
        Some(_) => out.components().collect(),
        None => fs::canonicalize(out).unwrap_or_else(|_| out.to_owned()),
    };
    let mut name = out.file_name().unwrap_or_default().to_owned();
    name.push(WORK_SUFFIX);
    out.with_file_name(name)
}

/// Whether `out`'s work folder is there and looks like a stopped run's: a folder (not a link)
/// holding a journal. A user's own `NAME.partial`, a file or a folder of notes, is not one:
/// `--resume` would refuse it, so nothing should suggest it.
pub fn holds_a_run(out: &Path) -> bool {
    let path = work_path(out);
    let folder = fs::symlink_metadata(&path).is_ok_and(|m| m.is_dir());
    folder && fs::symlink_metadata(path.join(JOURNAL)).is_ok_and(|m| m.is_file())
}

impl WorkFolder {
    /// Opens `out`'s work folder for a run keyed `key`: creates it when there is none, else
    /// takes it when it is this run's, with the frames it holds done. `index_of(i)` is the
    /// index line this run writes for frame `i` (from its plan, no GPU): a journaled frame is
    /// taken only when its line and its `pose.json` say what this run would.
    pub fn open(
        out: &Path,
        key: &RunKey,
        index_of: &mut dyn FnMut(usize) -> String,
    ) -> Result<WorkFolder, DatasetError> {
        let path = work_path(out);
        match fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Self::create(path, key),
            Err(e) => Err(io(&path)(e)),
            Ok(meta) if !meta.is_dir() => Err(refuse(
                &path,
                "is not a folder (a file or a link): it is no work folder of a dataset",
            )),
            Ok(_) => Self::take(path, key, index_of),
        }
    }

    fn create(path: PathBuf, key: &RunKey) -> Result<WorkFolder, DatasetError> {
        fs::create_dir(&path).map_err(io(&path))?;
        // The folder's own entry, so that a crash cannot take the whole work folder back.
        sync_folder(&parent_of(&path))?;
        let dir = Dir::open(&path).map_err(io(&path))?;
        let at = path.join(JOURNAL);
        // Through the folder's handle (`Dir::path`), like every write here: whatever is put
        // at the work folder's path meanwhile, a link included, is never written through.
        let journal = crate::output::create_new(&dir.path().join(JOURNAL)).map_err(io(&at))?;
        lock(&journal, &path)?;
        Self::start(path, dir, journal, key)
    }

    /// A work folder with an empty journal: the key line written first, and on disk.
    fn start(path: PathBuf, dir: Dir, journal: File, key: &RunKey) -> Result<Self, DatasetError> {
        let mut work = WorkFolder {
            path,
            dir,
            journal,
            done: BTreeMap::new(),
            frames: key.frames,
        };
        let format = FORMAT;
        let key = key.clone();
        work.append(&Line::Run { format, key })?;
        sync_dir(&work.dir, &work.path)?;
        Ok(work)
    }

    fn take(
        path: PathBuf,
        key: &RunKey,
        index_of: &mut dyn FnMut(usize) -> String,
    ) -> Result<WorkFolder, DatasetError> {
        // Opened without following a link: what is checked below is what is then used.
        let dir = Dir::open(&path).map_err(io(&path))?;
        let at = path.join(JOURNAL);
        let mut journal = open_journal(&dir.path().join(JOURNAL)).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => refuse(
                &path,
                &format!("holds no {JOURNAL}: it is no work folder of a dataset; choose another --out, or move it away"),
            ),
            _ => io(&at)(e),
        })?;
        lock(&journal, &path)?;
        let read = read_journal(&mut journal, key.frames).map_err(|e| match e {
            journal::JournalError::Io(e) => io(&at)(e),
            journal::JournalError::Bad(why) => refuse(&at, &why),
        })?;
        let mut lines = read.lines.into_iter();
        let Some((_, first)) = lines.next() else {
            // Made, but stopped before its key line was on disk: it holds nothing else, and
            // the journal nothing but the start of a key line.
            let a_key = read.tail.is_empty() || read.tail.starts_with(b"{\"run\"");
            if !a_key || names(&path)? != [JOURNAL] {
                return Err(refuse(
                    &at,
                    "holds no run key: it is no dataset run's journal",
                ));
            }
            journal.set_len(0).map_err(io(&at))?;
            journal.seek(SeekFrom::Start(0)).map_err(io(&at))?;
            return Self::start(path, dir, journal, key);
        };
        let theirs = match first {
            Line::Run { format, key } if format == FORMAT => key,
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
            let f = match line {
                Line::Frame(f) => f,
                Line::Run { .. } => {
                    return Err(refuse(&at, &format!("line {n}: a second run key")))
                }
            };
            check_journaled(&f, key).map_err(|why| refuse(&at, &format!("line {n}: {why}")))?;
            // Proven, not trusted: the line a run of these inputs writes for this frame.
            if !proof::same_json(&f.index, &index_of(f.frame)) {
                return Err(refuse(&at, &format!("line {n}: frame {}'s index line is not the one these inputs give it (the journal was edited, or its frames are not what it says): remove the work folder to start again", f.frame)));
            }
            // A frame done again (its files were lost) has a later line: the last one holds.
            done.insert(f.frame, f);
        }
        let mut work = WorkFolder {
            path,
            dir,
            journal,
            done,
            frames: key.frames,
        };
        work.check_entries()?;
        let lost: Vec<usize> = (work.done.values())
            .filter(|f| !work.on_disk(f))
            .map(|f| f.frame)
            .collect();
        for frame in lost {
            work.done.remove(&frame);
        }
        for f in work.done.values() {
            work.check_pose(f)?;
        }
        // Only now, the folder known to be this run's and its frames proven: a line cut short
        // by a crash is dropped (the frame it would name is done again). A folder refused
        // above is left as it was, journal included.
        work.journal.set_len(read.complete).map_err(io(&at))?;
        work.journal.seek(SeekFrom::End(0)).map_err(io(&at))?;
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

    /// Writes `frame` (checked by the caller: `folder::check_frame`) into the work folder, and
    /// journals it once it is on disk.
    pub fn write(&mut self, frame: &Frame) -> Result<(), DatasetError> {
        let name = frame_folder(frame.frame);
        let leaf = OsStr::new(name.rsplit('/').next().unwrap_or(&name));
        let frames = self.frames_dir()?;
        self.clear_cut_short(&frames, leaf)?;
        let folder = self.path.join(&name);
        fs::create_dir(frames.path().join(leaf)).map_err(io(&folder))?;
        let dir = frames.open_dir(leaf).map_err(io(&folder))?;
        let mut files = Vec::with_capacity(frame.files.len());
        for (rel, bytes) in &frame.files {
            let file_name = rel.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            let at = folder.join(file_name);
            let mut file =
                crate::output::create_new(&dir.path().join(file_name)).map_err(io(&at))?;
            (file.write_all(bytes).and_then(|()| file.sync_all())).map_err(io(&at))?;
            files.push((
                file_name.to_owned(),
                bytes.len() as u64,
                crc32fast::hash(bytes),
            ));
        }
        sync_dir(&dir, &folder)?;
        sync_dir(&frames, &self.path.join(FRAMES))?;
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
            let dir = self
                .frame_dir(f.frame)
                .map_err(io(&self.path.join(&folder)))?;
            for (name, size, _) in &f.files {
                let from = self.path.join(&folder).join(name);
                let to_user = root.join(&folder).join(name);
                let to = out.path_for(&to_user)?;
                // Through the frame folder's handle; a link there is linked as a link, and
                // then refused below.
                match fs::hard_link(dir.path().join(name), &to) {
                    // The link is to whatever was there: it must still be the frame's file.
                    Ok(())
                        if fs::symlink_metadata(&to)
                            .is_ok_and(|m| m.is_file() && m.len() == *size) => {}
                    Ok(()) => {
                        let _ = fs::remove_file(&to);
                        return Err(refuse(
                            &from,
                            "changed since it was written: --resume renders its frame again",
                        ));
                    }
                    Err(e) if no_links_here(&e) => {
                        copy_file((&dir.path().join(name), &from), *size, out, &to_user)?
                    }
                    Err(e) => return Err(io(&from)(e)),
                }
            }
        }
        Ok(())
    }

    /// Removes the work folder, as far as the journal names it (after the output is placed),
    /// through the folder handles. What could not be removed is returned, to be said.
    pub fn remove(self) -> Vec<String> {
        let mut left = Vec::new();
        // The placed output on disk first: the work folder is its only other copy.
        if let Err(e) = sync_file_system(&self.path) {
            let why = format!("{e} (kept: the output may not be on disk yet)");
            left.push(format!("{}: {why}", self.path.display()));
            return left;
        }
        let mut gone = |r: std::io::Result<()>, p: &Path| {
            if let Err(e) = r {
                left.push(format!("{}: {e}", p.display()));
            }
        };
        let frames_path = self.path.join(FRAMES);
        if let Ok(frames) = self.dir.open_dir(OsStr::new(FRAMES)) {
            for f in self.done.values() {
                let name = frame_folder(f.frame);
                let leaf = OsStr::new(name.rsplit('/').next().unwrap_or(&name));
                let at = self.path.join(&name);
                match frames.open_dir(leaf) {
                    Ok(folder) => {
                        for (file, _, _) in &f.files {
                            gone(folder.remove(OsStr::new(file), false), &at.join(file));
                        }
                        gone(frames.remove(leaf, true), &at);
                    }
                    Err(e) => gone(Err(e), &at),
                }
            }
            gone(self.dir.remove(OsStr::new(FRAMES), true), &frames_path);
        }
        let journal = self.path.join(JOURNAL);
        gone(self.dir.remove(OsStr::new(JOURNAL), false), &journal);
        gone(fs::remove_dir(&self.path), &self.path);
        left
    }

    /// Appends a line and makes it durable; a line that fails half-written is cut off again,
    /// so that the journal never holds a broken line in its middle.
    fn append(&mut self, line: &Line) -> Result<(), DatasetError> {
        let at = self.path.join(JOURNAL);
        let mut text = serde_json::to_string(line).map_err(|e| refuse(&at, &e.to_string()))?;
        text.push('\n');
        let before = self.journal.stream_position().map_err(io(&at))?;
        let written =
            (self.journal.write_all(text.as_bytes())).and_then(|()| self.journal.sync_data());
        if let Err(e) = written {
            let _ = self.journal.set_len(before);
            let _ = self.journal.seek(SeekFrom::Start(before));
            return Err(io(&at)(e));
        }
        Ok(())
    }

    /// The frames folder, made on first use; never a link.
    fn frames_dir(&self) -> Result<Dir, DatasetError> {
        let at = self.path.join(FRAMES);
        if let Err(e) = self.dir.entry(OsStr::new(FRAMES)) {
            if e.kind() != std::io::ErrorKind::NotFound {
                return Err(io(&at)(e));
            }
            fs::create_dir(self.dir.path().join(FRAMES)).map_err(io(&at))?;
            sync_dir(&self.dir, &self.path)?;
        }
        self.dir.open_dir(OsStr::new(FRAMES)).map_err(io(&at))
    }

    /// Frame `frame`'s folder, through the handles (never a link).
    fn frame_dir(&self, frame: usize) -> std::io::Result<Dir> {
        let name = frame_folder(frame);
        let leaf = OsStr::new(name.rsplit('/').next().unwrap_or(&name));
        self.dir.open_dir(OsStr::new(FRAMES))?.open_dir(leaf)
    }

    /// Every entry is the journal, `frames`, or a frame folder of this dataset holding frame
    /// files, none of them a link: anything else is someone else's, and the folder is not
    /// taken.
    fn check_entries(&self) -> Result<(), DatasetError> {
        for name in names(&self.path)? {
            let kind = self.dir.entry(OsStr::new(&name)).map_err(io(&self.path))?;
            let ours = match name.as_str() {
                JOURNAL => matches!(kind, Entry::Other),
                FRAMES => matches!(kind, Entry::Folder),
                _ => false,
            };
            if !ours {
                return Err(foreign(&self.path, &name));
            }
        }
        let Ok(frames) = self.dir.open_dir(OsStr::new(FRAMES)) else {
            return Ok(()); // none yet (checked above: not a link)
        };
        let frames_path = self.path.join(FRAMES);
        for name in names(&frames_path)? {
            let ours = (name.len() == 6 && name.bytes().all(|b| b.is_ascii_digit()))
                .then(|| name.parse::<usize>().ok())
                .flatten()
                .is_some_and(|i| i < self.frames);
            let leaf = OsStr::new(&name);
            if !ours || !matches!(frames.entry(leaf), Ok(Entry::Folder)) {
                return Err(foreign(&frames_path, &name));
            }
            let folder = frames.open_dir(leaf).map_err(io(&frames_path))?;
            for file in names(&frames_path.join(&name))? {
                if !is_frame_file(&file)
                    || !matches!(folder.entry(OsStr::new(&file)), Ok(Entry::Other))
                {
                    return Err(foreign(&frames_path.join(&name), &file));
                }
            }
        }
        Ok(())
    }

    /// Removes what a frame cut short left in `frames/leaf` (frame files only: a folder that
    /// holds anything else is refused), through the handles.
    fn clear_cut_short(&self, frames: &Dir, leaf: &OsStr) -> Result<(), DatasetError> {
        let at = self.path.join(FRAMES).join(leaf);
        match frames.entry(leaf) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(io(&at)(e)),
            Ok(Entry::Folder) => {}
            Ok(_) => return Err(foreign(&self.path.join(FRAMES), &leaf.to_string_lossy())),
        }
        let folder = frames.open_dir(leaf).map_err(io(&at))?;
        for file in names(&at)? {
            let ok =
                is_frame_file(&file) && matches!(folder.entry(OsStr::new(&file)), Ok(Entry::Other));
            if !ok {
                return Err(foreign(&at, &file));
            }
            folder
                .remove(OsStr::new(&file), false)
                .map_err(io(&at.join(&file)))?;
        }
        frames.remove(leaf, true).map_err(io(&at))
    }

    /// The journaled frame's `pose.json` says what its (proven) index line does: the files'
    /// sizes and CRC-32s are the journal's word, so the pose a user reads is checked too.
    fn check_pose(&self, f: &Journaled) -> Result<(), DatasetError> {
        let at = self.path.join(frame_folder(f.frame)).join(POSE_FILE);
        let mut bytes = Vec::new();
        let folder = self.frame_dir(f.frame).map_err(io(&at))?;
        let file = crate::output::open_no_follow(&folder.path().join(POSE_FILE));
        (file.and_then(|file| file.take(MAX_POSE_BYTES).read_to_end(&mut bytes)))
            .map_err(io(&at))?;
        match proof::pose_is_index(&bytes, &f.index) {
            true => Ok(()),
            false => Err(refuse(
                &at,
                &format!("is not frame {}'s pose as its index line gives it (the frame was edited): remove the work folder to start again", f.frame),
            )),
        }
    }

    /// Whether the journaled frame's files are there, regular, with their sizes and CRC-32s.
    fn on_disk(&self, f: &Journaled) -> bool {
        let Ok(folder) = self.frame_dir(f.frame) else {
            return false;
        };
        f.files.iter().all(|(name, size, crc)| {
            crate::output::open_no_follow(&folder.path().join(name))
                .is_ok_and(|file| proof::file_is(file, *size, *crc))
        })
    }
}

/// A hard link cannot be made here, but a copy can: another file system under the same name
/// (a bind mount), or one without hard links (vfat, some network and FUSE file systems).
fn no_links_here(e: &std::io::Error) -> bool {
    let codes = [
        libc::EXDEV,
        libc::EPERM,
        libc::EMLINK,
        libc::EOPNOTSUPP,
        libc::ENOSYS,
    ];
    e.raw_os_error().is_some_and(|c| codes.contains(&c))
        || e.kind() == std::io::ErrorKind::Unsupported
}

/// Copies the kept file `from` (its path through the folder's handle, and its path for
/// messages: a regular file of `size` bytes, never through a link) to a new file of the
/// staged output.
fn copy_file(
    (from, shown): (&Path, &Path),
    size: u64,
    out: &Transaction,
    to: &Path,
) -> Result<(), DatasetError> {
    let mut source = crate::output::open_no_follow(from).map_err(io(shown))?;
    if !source
        .metadata()
        .is_ok_and(|m| m.is_file() && m.len() == size)
    {
        return Err(refuse(
            shown,
            "changed since it was written: --resume renders its frame again",
        ));
    }
    let mut target = out.create(to)?;
    std::io::copy(&mut Read::by_ref(&mut source).take(size), &mut target).map_err(io(to))?;
    Ok(())
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

/// The folder holding `path` (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// Writes everything of the file system holding `path` to disk (`syncfs`): the placed
/// output, its copies and its rename, before the work folder that could redo them goes.
fn sync_file_system(path: &Path) -> std::io::Result<()> {
    let folder = File::open(path)?;
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: syncfs on a descriptor this `File` owns for the duration of the call.
        if unsafe { libc::syncfs(folder.as_raw_fd()) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    #[cfg(not(target_os = "linux"))]
    folder.sync_all()?;
    Ok(())
}

/// Makes the entries of the folder `dir` (at `shown`, for messages) durable, where the file
/// system can.
fn sync_dir(dir: &Dir, shown: &Path) -> Result<(), DatasetError> {
    match dir.sync() {
        // Some file systems cannot sync a folder; the journal still comes after the files.
        Err(e) if e.kind() == std::io::ErrorKind::InvalidInput => Ok(()),
        r => r.map_err(io(shown)),
    }
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
